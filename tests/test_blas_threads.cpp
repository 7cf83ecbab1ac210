// The guard that keeps OpenBLAS on the calling thread during the FEM's threaded CG.
#include <gtest/gtest.h>

#include <dlfcn.h>

#include "blas_threads.h"

namespace {

using GetThreads = int (*)();
using SetThreads = void (*)(int);

TEST(SingleThreadedBlas, RunsBlasOnOneThreadAndRestoresTheCount) {
  // The test links CHOLMOD and so the system BLAS; when that is not OpenBLAS there is nothing to do.
  const auto get = reinterpret_cast<GetThreads>(dlsym(RTLD_DEFAULT, "openblas_get_num_threads"));
  const auto set = reinterpret_cast<SetThreads>(dlsym(RTLD_DEFAULT, "openblas_set_num_threads"));
  if (!get || !set) GTEST_SKIP() << "the BLAS is not OpenBLAS";
  const int original = get();
  set(2);
  if (get() != 2) GTEST_SKIP() << "this OpenBLAS runs on one thread only";
  {
    const repose::SingleThreadedBlas guard;
    EXPECT_EQ(get(), 1);
    {
      const repose::SingleThreadedBlas nested;  // a nested guard keeps one thread and restores one
      EXPECT_EQ(get(), 1);
    }
    EXPECT_EQ(get(), 1);
  }
  EXPECT_EQ(get(), 2);
  set(original);
}

}  // namespace
