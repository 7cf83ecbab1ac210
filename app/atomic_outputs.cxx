#include "atomic_outputs.h"

#include "temporary_lock.h"
#include "written_file.h"

#include <cerrno>
#include <csignal>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <regex>
#include <map>
#include <sstream>
#include <stdexcept>
#include <sys/file.h>
#include <unistd.h>

namespace repose {
namespace fs = std::filesystem;

namespace {

const std::string kTempPrefix = ".repose-tmp-";

/// The temporary folders of this process's live AtomicOutputs, guarded so that a commit and the
/// signal handler's removal never interleave.
std::mutex& registryMutex() {
  static std::mutex m;
  return m;
}
/// Temporary folder -> (final folder, outermost folder created for it or "").
std::map<std::string, std::pair<std::string, std::string>>& registry() {
  static std::map<std::string, std::pair<std::string, std::string>> folders;
  return folders;
}

/// Removes `dir` and its parents up to `root` while they are empty (fs::remove leaves a full one).
void removeEmptyUpTo(const fs::path& dir, const fs::path& root) {
  if (root.empty()) return;
  std::error_code ec;
  for (fs::path p = dir; !p.empty(); p = p.parent_path()) {
    if (!fs::remove(p, ec) || p == root) return;
  }
}

/// The outermost missing folder on the way to `dir` ("" when it exists).
std::string firstMissing(const fs::path& dir) {
  std::error_code ec;
  fs::path missing;
  for (fs::path p = fs::absolute(dir).lexically_normal(); !p.empty() && !fs::exists(p, ec); p = p.parent_path())
    missing = p;
  return missing.string();
}

void removeWithRetries(const std::string& dir) {
  // Writer threads may still create files in it; a few passes empty it.
  std::error_code ec;
  for (int pass = 0; pass < 20 && fs::exists(dir, ec); ++pass) fs::remove_all(dir, ec);
}

/// The pid in ".repose-tmp-<pid>[-...]", or 0.
pid_t pidOf(const std::string& name) {
  if (name.compare(0, kTempPrefix.size(), kTempPrefix) != 0) return 0;
  std::size_t i = kTempPrefix.size(), end = i;
  while (end < name.size() && std::isdigit(static_cast<unsigned char>(name[end]))) ++end;
  if (end == i || end - i > 9 || (end < name.size() && name[end] != '-')) return 0;
  return static_cast<pid_t>(std::stol(name.substr(i, end - i)));
}

}  // namespace

AtomicOutputs::AtomicOutputs(const std::string& finalDir) : finalDir_(finalDir), createdRoot_(firstMissing(finalDir)) {
  makeDirectories(finalDir_);
  removeStaleTemporaryFolders(finalDir_);
  tempDir_ = (fs::path(finalDir_) / (kTempPrefix + std::to_string(::getpid()))).string();
  lock_ = std::make_unique<TemporaryLock>(tempDir_, true);
  std::lock_guard<std::mutex> lock(registryMutex());
  registry()[tempDir_] = {finalDir_, createdRoot_};
}

AtomicOutputs::~AtomicOutputs() {
  std::lock_guard<std::mutex> lock(registryMutex());
  registry().erase(tempDir_);
  std::error_code ec;
  fs::remove_all(tempDir_, ec);
  lock_.reset();
  if (!committed_) removeEmptyUpTo(fs::absolute(finalDir_).lexically_normal(), createdRoot_);
}

std::string AtomicOutputs::stage(const std::string& name) const {
  return (fs::path(tempDir_) / name).string();
}

void AtomicOutputs::commit() {
  std::lock_guard<std::mutex> lock(registryMutex());
  for (const auto& entry : fs::directory_iterator(tempDir_))
    requireWritten((fs::path(finalDir_) / entry.path().filename()).string(), entry.path().string());
  for (const auto& entry : fs::directory_iterator(tempDir_)) {
    const fs::path target = fs::path(finalDir_) / entry.path().filename();
    std::error_code ec;
    if (fs::is_directory(target)) fs::remove_all(target, ec);
    fs::rename(entry.path(), target, ec);
    if (ec) throw std::runtime_error(target.string() + ": cannot write (" + ec.message() + ")");
  }
  committed_ = true;
  syncFolder(finalDir_);  // the renames themselves reach the disk
}

std::vector<std::string> removeTemporaryFolders() {
  std::lock_guard<std::mutex> lock(registryMutex());
  std::vector<std::string> finalDirs;
  for (const auto& [dir, final] : registry()) {
    removeWithRetries(dir);
    removeEmptyUpTo(fs::absolute(final.first).lexically_normal(), final.second);
    finalDirs.push_back(final.first);
  }
  registry().clear();
  return finalDirs;
}

int removeStaleTemporaryFolders(const std::string& dir) {
  int removed = 0;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    const pid_t pid = pidOf(entry.path().filename().string());
    if (pid > 0 && pid != ::getpid() && removeIfUnlocked(entry.path().string())) ++removed;
  }
  return removed;
}

std::string withFinalPaths(std::string message) {
  static const std::regex temp("\\.repose-tmp-[0-9]+/");
  return std::regex_replace(message, temp, "");
}

void makeDirectories(const std::string& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir)) throw std::runtime_error(dir + ": cannot create directory");
}

std::string readTextFile(const std::string& path) {
  if (fs::is_directory(path)) throw std::runtime_error(path + ": is a directory, not a file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot read (" + std::strerror(errno) + ")");
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

void writeTextFile(const std::string& path, const std::string& text) {
  errno = 0;
  std::ofstream out(path, std::ios::binary);
  out << text;
  out.close();  // the last buffer is written here: a full disk shows only now
  if (!out) throwWriteFailure(path, path, errno);
  requireWritten(path, path, text.size());
}

bool fileExists(const std::string& path) { return fs::exists(path); }

std::string imageExtension(const std::string& path) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) return "/";  // a DICOM series: the derived one is a folder too
  const std::string name = fs::path(path).filename().string();
  for (const char* ext : {".nii.gz", ".nii", ".nrrd", ".nhdr", ".mha", ".mhd"})
    if (name.size() > std::strlen(ext) && name.compare(name.size() - std::strlen(ext), std::string::npos, ext) == 0)
      return ext;
  const auto dot = name.rfind('.');
  return dot == std::string::npos ? "" : name.substr(dot);
}

}  // namespace repose
