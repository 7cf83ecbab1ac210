// A temporary entry is removed by another process exactly when its writer is gone: the lock, held
// while the writer lives and dropped by the kernel when it dies (even by SIGKILL), decides.
#include "temporary_lock.h"

#include <gtest/gtest.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;

namespace {

fs::path freshFolder(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / (name + "-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

/// A child process that creates and locks `path`, then waits to be killed; returns its pid once the
/// entry exists (its lock is taken before the entry can be seen under its name by the test).
pid_t lockingChild(const fs::path& path, bool folder) {
  int ready[2];
  if (::pipe(ready) != 0) throw std::runtime_error("pipe");
  const pid_t pid = ::fork();
  if (pid == 0) {
    const repose::TemporaryLock lock(path.string(), folder);
    (void)!::write(ready[1], "x", 1);
    for (;;) ::pause();
  }
  char c;
  (void)!::read(ready[0], &c, 1);
  ::close(ready[0]);
  ::close(ready[1]);
  return pid;
}

void kill9(pid_t pid) {
  ::kill(pid, SIGKILL);
  ::waitpid(pid, nullptr, 0);
}

}  // namespace

TEST(TemporaryLock, KeptWhileItsWriterLivesRemovedOnceItDied) {
  const fs::path dir = freshFolder("temporary-lock");
  for (bool folder : {true, false}) {
    const fs::path path = dir / (folder ? ".repose-tmp-1" : ".repose-tmp-1-labels.nii.gz");
    const pid_t writer = lockingChild(path, folder);
    if (folder) std::ofstream(path / "part.vtu") << "partial";
    EXPECT_FALSE(repose::removeIfUnlocked(path.string()));
    EXPECT_TRUE(fs::exists(path));
    kill9(writer);  // no clean-up runs: only the kernel drops the lock
    EXPECT_TRUE(repose::removeIfUnlocked(path.string()));
    EXPECT_FALSE(fs::exists(path));
  }
  fs::remove_all(dir);
}

TEST(TemporaryLock, AnEntryInUseIsRefusedALeftoverIsTakenOver) {
  const fs::path dir = freshFolder("temporary-lock-reuse");
  const fs::path path = dir / ".repose-tmp-2";
  const pid_t writer = lockingChild(path, true);
  EXPECT_THROW(repose::TemporaryLock(path.string(), true), std::runtime_error);
  EXPECT_TRUE(fs::exists(path));
  std::ofstream(path / "old.vtu") << "left by a dead run";
  kill9(writer);
  {
    const repose::TemporaryLock lock(path.string(), true);  // a dead writer's leftover: emptied, then ours
    EXPECT_TRUE(fs::is_directory(path));
    EXPECT_TRUE(fs::is_empty(path));
    EXPECT_FALSE(repose::removeIfUnlocked(path.string()));
  }
  EXPECT_TRUE(repose::removeIfUnlocked(path.string()));
  fs::remove_all(dir);
}

TEST(TemporaryLock, MissingEntriesAndSymlinksAreLeftAlone) {
  const fs::path dir = freshFolder("temporary-lock-missing");
  EXPECT_FALSE(repose::removeIfUnlocked((dir / ".repose-tmp-3").string()));
  fs::create_directory(dir / "target");
  fs::create_directory_symlink(dir / "target", dir / ".repose-tmp-4");
  EXPECT_FALSE(repose::removeIfUnlocked((dir / ".repose-tmp-4").string()));
  EXPECT_TRUE(fs::exists(dir / "target"));
  fs::remove_all(dir);
}
