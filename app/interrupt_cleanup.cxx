#include "interrupt_cleanup.h"

#include "atomic_outputs.h"

#include <cerrno>
#include <csignal>
#include <fcntl.h>
#include <string>
#include <thread>
#include <unistd.h>
#include <vector>

namespace repose {

namespace {

int signalPipe[2] = {-1, -1};

void onSignal(int s) {
  const int saved = errno;
  const unsigned char c = static_cast<unsigned char>(s);
  (void)!::write(signalPipe[1], &c, 1);
  errno = saved;
}

const char* signalName(int s) { return s == SIGINT ? "SIGINT" : s == SIGTERM ? "SIGTERM" : "SIGHUP"; }

[[noreturn]] void cleanUpAndExit(int s, int err) {
  const std::vector<std::string> dirs = removeTemporaryFolders();
  const std::string line = "repose: error: " + (dirs.empty() ? std::string() : dirs.front() + ": ") +
                           "interrupted by " + signalName(s) +
                           (dirs.empty() ? std::string() : "; nothing written (temporary folder removed)") + "\n";
  (void)!::write(err, line.data(), line.size());
  ::_exit(128 + s);
}

}  // namespace

void cleanUpOnInterrupt() {
  if (::pipe2(signalPipe, O_CLOEXEC) != 0) return;
  // stderr as it is now: a writer may silence fd 2 for a while (QuietStderr).
  const int err = ::fcntl(STDERR_FILENO, F_DUPFD_CLOEXEC, 0);
  std::thread([err] {
    unsigned char c = 0;
    ssize_t n = 0;
    while ((n = ::read(signalPipe[0], &c, 1)) < 0 && errno == EINTR) {
    }
    if (n == 1) cleanUpAndExit(c, err >= 0 ? err : STDERR_FILENO);
  }).detach();
  struct sigaction action {};
  action.sa_handler = onSignal;
  action.sa_flags = SA_RESTART;
  sigemptyset(&action.sa_mask);
  for (int s : {SIGINT, SIGTERM, SIGHUP}) {
    struct sigaction old {};
    if (::sigaction(s, nullptr, &old) == 0 && old.sa_handler == SIG_IGN) continue;
    ::sigaction(s, &action, nullptr);
  }
}

}  // namespace repose
