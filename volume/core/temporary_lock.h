#pragma once
// Temporary files and folders (".repose-tmp-<pid>...") are locked (flock) by the process writing them
// for as long as it lives: the lock, not the pid, tells another process whether the writer is gone.
// A pid says nothing once the kernel gives it to a new process, or in another pid namespace; a lock
// is released by the kernel when its holder dies, however it dies.
#include <string>

namespace repose {

/// An flock held on a file or folder; released when this object goes (or its process dies).
class TemporaryLock {
public:
  /// Creates `path` (a folder when `folder`, else an empty file) and locks it. A leftover of a dead
  /// writer under that name is removed first. Throws std::runtime_error "PATH: ..." when the entry
  /// cannot be created, or when a live process holds its lock.
  TemporaryLock(const std::string& path, bool folder);
  ~TemporaryLock();
  TemporaryLock(const TemporaryLock&) = delete;
  TemporaryLock& operator=(const TemporaryLock&) = delete;

private:
  int fd_ = -1;
};

/// Removes `path` (a file or a folder with everything in it) when no process holds its lock, holding
/// the lock meanwhile so that a writer starting under that name waits; true when removed.
bool removeIfUnlocked(const std::string& path);

}  // namespace repose
