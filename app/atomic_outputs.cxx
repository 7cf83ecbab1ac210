#include "atomic_outputs.h"

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <unistd.h>

namespace repose {
namespace fs = std::filesystem;

AtomicOutputs::AtomicOutputs(const std::string& finalDir) : finalDir_(finalDir) {
  makeDirectories(finalDir_);
  tempDir_ = (fs::path(finalDir_) / (".repose-tmp-" + std::to_string(::getpid()))).string();
  std::error_code ec;
  fs::remove_all(tempDir_, ec);
  makeDirectories(tempDir_);
}

AtomicOutputs::~AtomicOutputs() {
  std::error_code ec;
  fs::remove_all(tempDir_, ec);
}

std::string AtomicOutputs::stage(const std::string& name) const {
  return (fs::path(tempDir_) / name).string();
}

void AtomicOutputs::commit() {
  for (const auto& entry : fs::directory_iterator(tempDir_)) {
    const fs::path target = fs::path(finalDir_) / entry.path().filename();
    std::error_code ec;
    if (fs::is_directory(target)) fs::remove_all(target, ec);
    fs::rename(entry.path(), target, ec);
    if (ec) throw std::runtime_error(target.string() + ": cannot write (" + ec.message() + ")");
  }
  committed_ = true;
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
  std::ofstream out(path, std::ios::binary);
  out << text;
  if (!out) throw std::runtime_error(path + ": cannot write");
}

bool fileExists(const std::string& path) { return fs::exists(path); }

std::string imageExtension(const std::string& path) {
  const std::string name = fs::path(path).filename().string();
  for (const char* ext : {".nii.gz", ".nii", ".nrrd", ".nhdr", ".mha", ".mhd"})
    if (name.size() > std::strlen(ext) && name.compare(name.size() - std::strlen(ext), std::string::npos, ext) == 0)
      return ext;
  const auto dot = name.rfind('.');
  return dot == std::string::npos ? "" : name.substr(dot);
}

}  // namespace repose
