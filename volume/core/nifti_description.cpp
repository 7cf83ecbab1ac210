#include "nifti_description.h"

#include "written_file.h"

#include <zlib.h>

#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <algorithm>
#include <cstring>
#include <vector>

namespace repose {
namespace {

constexpr long kDescripOffset = 148;
constexpr std::size_t kDescripBytes = 80;

void patchDescrip(const std::string& name, const std::string& nii, const std::string& text) {
  std::FILE* f = std::fopen(nii.c_str(), "r+b");
  if (!f) throwWriteFailure(name, nii, errno);
  std::int32_t headerSize = 0;
  char magic[4] = {};
  const bool nifti1 = std::fread(&headerSize, 4, 1, f) == 1 && headerSize == 348 &&
                      std::fseek(f, 344, SEEK_SET) == 0 && std::fread(magic, 4, 1, f) == 1 &&
                      std::memcmp(magic, "n+1", 4) == 0;
  if (!nifti1) {  // a NIfTI-2 header (an image beyond NIfTI-1's sizes) keeps its note empty
    std::fclose(f);
    return;
  }
  char descrip[kDescripBytes] = {};
  std::memcpy(descrip, text.data(), std::min(text.size(), kDescripBytes - 1));
  errno = 0;
  const bool written = std::fseek(f, kDescripOffset, SEEK_SET) == 0 && std::fwrite(descrip, kDescripBytes, 1, f) == 1;
  const int err = errno;
  if (std::fclose(f) != 0 || !written) throwWriteFailure(name, nii, err);
}

void gzipFile(const std::string& name, const std::string& from, const std::string& to) {
  std::FILE* in = std::fopen(from.c_str(), "rb");
  if (!in) throwWriteFailure(name, from, errno);
  gzFile out = ::gzopen(to.c_str(), "wb");
  if (!out) {
    const int err = errno;
    std::fclose(in);
    throwWriteFailure(name, to, err);
  }
  std::vector<char> buffer(1 << 20);
  bool ok = true;
  errno = 0;
  for (std::size_t n; ok && (n = std::fread(buffer.data(), 1, buffer.size(), in)) > 0;)
    ok = ::gzwrite(out, buffer.data(), static_cast<unsigned>(n)) == static_cast<int>(n);
  ok = ok && !std::ferror(in);
  const int err = errno;
  std::fclose(in);
  ok = ::gzclose(out) == Z_OK && ok;
  if (!ok) throwWriteFailure(name, to, err ? err : errno);
  if (std::remove(from.c_str()) != 0) throwWriteFailure(name, from, errno);  // or it would be moved out too
}

}  // namespace

void describeNifti(const std::string& name, const std::string& nii, const std::string& text,
                   const std::string& gzipTo) {
  patchDescrip(name, nii, text);
  if (!gzipTo.empty()) gzipFile(name, nii, gzipTo);
}

}  // namespace repose
