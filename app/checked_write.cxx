#include "checked_write.h"

#include "written_file.h"

#include <cstdio>
#include <cstdlib>
#include <fcntl.h>
#include <unistd.h>

namespace repose {

const std::string kVtkXmlTail = "</VTKFile>\n";
const std::string kPngTail("IEND\xAE\x42\x60\x82", 8);

void checkWritten(int written, unsigned long errorCode, int err, const std::string& path, const std::string& tail) {
  if (!written || errorCode != 0) throwWriteFailure(path, path, err);
  if (!tail.empty()) requireEndsWith(path, path, tail);
  requireWritten(path, path);
}

QuietStderr::QuietStderr() {
  if (std::getenv("REPOSE_VERBOSE")) return;
  std::fflush(stderr);
  saved_ = ::fcntl(STDERR_FILENO, F_DUPFD_CLOEXEC, 0);
  const int null = ::open("/dev/null", O_WRONLY | O_CLOEXEC);
  if (saved_ >= 0 && null >= 0) ::dup2(null, STDERR_FILENO);
  if (null >= 0) ::close(null);
}

QuietStderr::~QuietStderr() {
  if (saved_ < 0) return;
  std::fflush(stderr);
  ::dup2(saved_, STDERR_FILENO);
  ::close(saved_);
}

}  // namespace repose
