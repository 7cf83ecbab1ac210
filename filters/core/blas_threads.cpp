#include "blas_threads.h"

#include <dlfcn.h>

#include <initializer_list>

namespace repose {
namespace {
using GetThreads = int (*)();
using SetThreads = void (*)(int);

// Looked up at run time: the BLAS behind libblas.so.3 is chosen by the system, not at link time,
// and a Python import loads it without adding its symbols to the global scope.
void* symbol(const char* name) {
  if (void* s = dlsym(RTLD_DEFAULT, name)) return s;
  for (const char* library : {"libopenblas.so.0", "libblas.so.3"})
    if (void* handle = dlopen(library, RTLD_LAZY | RTLD_NOLOAD)) {
      void* s = dlsym(handle, name);
      dlclose(handle);  // RTLD_NOLOAD took a reference on the already loaded library
      if (s) return s;
    }
  return nullptr;
}
GetThreads getThreads() { return reinterpret_cast<GetThreads>(symbol("openblas_get_num_threads")); }
SetThreads setThreads() { return reinterpret_cast<SetThreads>(symbol("openblas_set_num_threads")); }
}  // namespace

SingleThreadedBlas::SingleThreadedBlas() {
  const GetThreads get = getThreads();
  const SetThreads set = setThreads();
  if (!get || !set) return;
  previous_ = get();
  if (previous_ > 1) set(1);
}

SingleThreadedBlas::~SingleThreadedBlas() {
  const SetThreads set = setThreads();
  if (set && previous_ > 1) set(previous_);
}

}  // namespace repose
