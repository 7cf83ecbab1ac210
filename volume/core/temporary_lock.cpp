#include "temporary_lock.h"

#include <cerrno>
#include <chrono>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <stdexcept>
#include <sys/file.h>
#include <sys/stat.h>
#include <thread>
#include <unistd.h>

namespace repose {
namespace fs = std::filesystem;

namespace {

/// True when `fd` is still the entry named `path` (not removed, nor replaced, since it was opened).
bool stillNamed(int fd, const std::string& path) {
  struct stat opened{}, named{};
  return ::fstat(fd, &opened) == 0 && ::stat(path.c_str(), &named) == 0 && opened.st_dev == named.st_dev &&
         opened.st_ino == named.st_ino;
}

/// LOCK_EX, retried for about a second: a process removing a dead writer's entry holds it briefly.
bool lockSoon(int fd) {
  for (int attempt = 0; attempt < 100; ++attempt) {
    if (::flock(fd, LOCK_EX | LOCK_NB) == 0) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return false;
}

}  // namespace

TemporaryLock::TemporaryLock(const std::string& path, bool folder) {
  for (int attempt = 0; attempt < 10; ++attempt) {
    std::error_code ec;
    const bool created = folder ? fs::create_directory(path, ec) : false;
    fd_ = folder ? ::open(path.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC)
                 : ::open(path.c_str(), O_RDONLY | O_CREAT | O_CLOEXEC, 0644);
    if (fd_ < 0) throw std::runtime_error(path + ": cannot create (" + std::strerror(errno) + ")");
    if (!lockSoon(fd_)) {
      ::close(fd_);
      fd_ = -1;
      throw std::runtime_error(path + ": in use by another running process");
    }
    if (!stillNamed(fd_, path)) {  // removed as a dead writer's before the lock was taken
      ::close(fd_);
      continue;
    }
    if (folder && !created && fs::remove_all(path, ec) > 0) {  // a dead writer's, locked now: start afresh
      ::close(fd_);
      continue;
    }
    return;
  }
  fd_ = -1;
  throw std::runtime_error(path + ": cannot create (removed again and again)");
}

TemporaryLock::~TemporaryLock() {
  if (fd_ >= 0) ::close(fd_);
}

bool removeIfUnlocked(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW);
  if (fd < 0) return false;
  bool removed = false;
  if (::flock(fd, LOCK_EX | LOCK_NB) == 0 && stillNamed(fd, path)) {
    std::error_code ec;
    removed = fs::remove_all(path, ec) > 0;
  }
  ::close(fd);
  return removed;
}

}  // namespace repose
