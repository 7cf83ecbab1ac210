#include "written_file.h"

#include <zlib.h>

#include <cctype>
#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <stdexcept>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <unistd.h>
#include <vector>

namespace repose {
namespace fs = std::filesystem;

namespace {

bool tellsWhy(int err) {
  switch (err) {
    case ENOSPC: case EDQUOT: case EFBIG: case EIO: case EROFS: case EACCES: case EPERM:
    case ENOENT: case ENOTDIR: case ENAMETOOLONG: case EMFILE: case ENFILE: case ENOMEM:
      return true;
    default:
      return false;
  }
}

std::uintmax_t sizeOrZero(const std::string& path) {
  std::error_code ec;
  const std::uintmax_t n = fs::file_size(path, ec);
  return ec ? 0 : n;
}

/// fsync of one file or folder; 0 or the errno.
int syncPath(const std::string& path, bool folder) {
  const int fd = ::open(path.c_str(), (folder ? O_RDONLY | O_DIRECTORY : O_RDONLY) | O_CLOEXEC);
  if (fd < 0) return errno;
  const int rc = ::fsync(fd) == 0 || errno == EINVAL ? 0 : errno;  // EINVAL: a file system without fsync
  ::close(fd);
  return rc;
}

/// "No space left on device" -> "no space left on device", the way messages continue.
std::string errorText(int err) {
  std::string text = std::strerror(err);
  if (!text.empty()) text[0] = static_cast<char>(std::tolower(static_cast<unsigned char>(text[0])));
  return text;
}

}  // namespace

bool isStorageError(int err) {
  return err == ENOSPC || err == EDQUOT || err == EFBIG || err == EIO || err == EROFS;
}

std::string knownWriteFailure(const std::string& path, int err) {
  if (tellsWhy(err)) return errorText(err);
  fs::path dir = fs::path(path).parent_path();
  if (dir.empty()) dir = ".";
  struct statvfs vfs{};
  if (::statvfs(dir.c_str(), &vfs) == 0 && vfs.f_bavail == 0) return errorText(ENOSPC);
  struct rlimit limit{};
  if (::getrlimit(RLIMIT_FSIZE, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY && sizeOrZero(path) >= limit.rlim_cur)
    return errorText(EFBIG);
  return "";
}

std::string writeFailureReason(const std::string& path, int err) {
  const std::string known = knownWriteFailure(path, err);
  return known.empty() ? "the file is incomplete" : known;
}

void throwWriteFailure(const std::string& name, const std::string& path, int err) {
  throw WriteFailure(name, writeFailureReason(path, err));
}

void requireWritten(const std::string& name, const std::string& path, std::uintmax_t minBytes) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) {
    for (const auto& entry : fs::directory_iterator(path))
      requireWritten((fs::path(name) / entry.path().filename()).string(), entry.path().string(), minBytes);
    if (const int err = syncPath(path, true)) throwWriteFailure(name, path, err);
    return;
  }
  if (!fs::exists(path, ec)) throwWriteFailure(name, path, ENOENT);
  if (const int err = syncPath(path, false)) throwWriteFailure(name, path, err);
  if (sizeOrZero(path) < minBytes) throwWriteFailure(name, path);
}

void syncFolder(const std::string& dir) {
  if (const int err = syncPath(dir, true)) throwWriteFailure(dir, dir, err);
}

void requireEndsWith(const std::string& name, const std::string& path, const std::string& tail) {
  const std::uintmax_t size = sizeOrZero(path);
  std::string last(tail.size(), '\0');
  FILE* f = size >= tail.size() ? std::fopen(path.c_str(), "rb") : nullptr;
  const bool read = f && std::fseek(f, long(size - tail.size()), SEEK_SET) == 0 &&
                    std::fread(&last[0], 1, last.size(), f) == last.size();
  if (f) std::fclose(f);
  if (!read || last != tail) throwWriteFailure(name, path);
}

void requireCompleteGzip(const std::string& name, const std::string& path, std::uintmax_t minBytes) {
  gzFile gz = ::gzopen(path.c_str(), "rb");
  if (!gz) throwWriteFailure(name, path, errno);
  std::vector<char> buffer(1 << 20);
  std::uintmax_t total = 0;
  int n = 0;
  while ((n = ::gzread(gz, buffer.data(), unsigned(buffer.size()))) > 0) total += std::uintmax_t(n);
  int code = Z_OK;
  ::gzerror(gz, &code);
  if (::gzdirect(gz)) code = Z_DATA_ERROR;  // not gzip at all
  // A cut-short stream reads as a short file with Z_BUF_ERROR; a bad CRC as n < 0 with Z_DATA_ERROR.
  const bool complete = n == 0 && code == Z_OK && ::gzclose_r(gz) == Z_OK;
  if (n != 0 || code != Z_OK) ::gzclose_r(gz);
  if (!complete || total < minBytes) throwWriteFailure(name, path);
}

}  // namespace repose
