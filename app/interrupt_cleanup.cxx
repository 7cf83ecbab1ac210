#include "interrupt_cleanup.h"

#include "atomic_outputs.h"

#include <cerrno>
#include <csignal>
#include <fcntl.h>
#include <fstream>
#include <iterator>
#include <string>
#include <thread>
#include <unistd.h>
#include <vector>

namespace repose {

namespace {

int signalPipe[2] = {-1, -1};
std::string outPath;  // the command's --out, named when no output folder exists yet

/// The value of --out (or --out=VALUE) on this process's command line, "" without one. Read from
/// /proc so that every command is covered without passing its arguments here.
std::string outOption() {
  std::ifstream in("/proc/self/cmdline", std::ios::binary);
  const std::string all((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::string previous, found;
  for (std::size_t begin = 0, end; begin < all.size(); begin = end + 1) {
    end = all.find('\0', begin);
    if (end == std::string::npos) end = all.size();
    const std::string arg = all.substr(begin, end - begin);
    if (previous == "--out") found = arg;
    if (arg.rfind("--out=", 0) == 0) found = arg.substr(6);
    previous = arg;
  }
  return found;
}

void onSignal(int s) {
  const int saved = errno;
  const unsigned char c = static_cast<unsigned char>(s);
  (void)!::write(signalPipe[1], &c, 1);
  errno = saved;
}

const char* signalName(int s) { return s == SIGINT ? "SIGINT" : s == SIGTERM ? "SIGTERM" : "SIGHUP"; }

[[noreturn]] void cleanUpAndExit(int s, int err) {
  const std::vector<std::string> dirs = removeTemporaryFolders();
  const std::string named = !dirs.empty() ? dirs.front() : outPath;
  const std::string line = "repose: error: " + (named.empty() ? std::string() : named + ": ") + "interrupted by " +
                           signalName(s) +
                           (dirs.empty() ? "; nothing written yet" : "; nothing written (temporary folder removed)") + "\n";
  (void)!::write(err, line.data(), line.size());
  ::_exit(128 + s);
}

}  // namespace

void cleanUpOnInterrupt() {
  outPath = outOption();
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
