#include "image_file_integrity.h"

#include <zlib.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace repose {
namespace {

using Bytes = std::vector<unsigned char>;

std::ifstream openBinary(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + " cannot be opened");
  return in;
}

std::string directoryOf(const std::string& path) {
  const auto slash = path.find_last_of('/');
  return slash == std::string::npos ? std::string() : path.substr(0, slash + 1);
}

std::string trim(std::string s) {
  while (!s.empty() && (s.back() == '\r' || s.back() == ' ' || s.back() == '\t')) s.pop_back();
  const auto first = s.find_first_not_of(" \t");
  return first == std::string::npos ? std::string() : s.substr(first);
}

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

using Sink = std::function<void(const unsigned char*, std::size_t)>;

/// Inflates a zlib or gzip stream (concatenated gzip members too) from the current position of
/// `in` to its end, verifying each trailer; returns the inflated size and passes the bytes to
/// `sink`. A stream that ends early or fails its check throws.
std::uint64_t inflateToEnd(std::istream& in, const Sink& sink = {}) {
  z_stream z{};
  if (inflateInit2(&z, 15 + 32) != Z_OK) throw std::runtime_error("cannot start zlib");
  Bytes input(1 << 16), output(1 << 18);
  std::uint64_t total = 0;
  int status = Z_OK;
  bool ended = false;
  while (true) {
    if (z.avail_in == 0) {
      in.read(reinterpret_cast<char*>(input.data()), static_cast<std::streamsize>(input.size()));
      z.next_in = input.data();
      z.avail_in = static_cast<uInt>(in.gcount());
      if (z.avail_in == 0) break;
    }
    if (ended) {  // another gzip member follows, or trailing bytes that are not ours to judge
      if (z.avail_in >= 2 && z.next_in[0] == 0x1f && z.next_in[1] == 0x8b) {
        inflateReset(&z);
        ended = false;
      } else {
        break;
      }
    }
    z.next_out = output.data();
    z.avail_out = static_cast<uInt>(output.size());
    status = inflate(&z, Z_NO_FLUSH);
    const std::size_t produced = output.size() - z.avail_out;
    if (sink && produced) sink(output.data(), produced);
    total += produced;
    if (status == Z_STREAM_END) {
      ended = true;
    } else if (status != Z_OK && status != Z_BUF_ERROR) {
      const std::string why = z.msg ? z.msg : "zlib error " + std::to_string(status);
      inflateEnd(&z);
      throw std::runtime_error("damaged compressed data (" + why + ")");
    }
  }
  inflateEnd(&z);
  if (!ended) throw std::runtime_error("compressed data cut short (the file is truncated)");
  return total;
}

void requireBytes(std::uint64_t available, std::uint64_t needed) {
  if (available < needed)
    throw std::runtime_error("file holds " + std::to_string(available) + " bytes of voxels, its header promises " +
                             std::to_string(needed) + " (the file is truncated or its header is wrong)");
}

// ---- NIfTI ---------------------------------------------------------------------------------------

template <class T>
T field(const Bytes& h, std::size_t offset, bool swap) {
  T v;
  unsigned char b[sizeof(T)];
  std::memcpy(b, h.data() + offset, sizeof(T));
  if (swap) std::reverse(b, b + sizeof(T));
  std::memcpy(&v, b, sizeof(T));
  return v;
}

std::int32_t headerSize(const Bytes& h, bool& swap) {
  if (h.size() < 4) return 0;
  for (bool s : {false, true}) {
    const std::int32_t n = field<std::int32_t>(h, 0, s);
    if (n == 348 || n == 540) {
      swap = s;
      return n;
    }
  }
  return 0;
}

struct NiftiLayout {
  double offset = -1;  ///< where the voxels start; -1 when the bytes are not a NIfTI header
  int floatBytes = 0;  ///< 4 or 8 for float32/float64 voxels, else 0
  bool swap = false;
  bool pair = false;  ///< a two-file NIfTI (.hdr + .img): the offset is into the .img
};

/// NIfTI header of `h` (its first 544 bytes, or all when shorter): where its voxels start and what
/// they are. Refuses non-finite or non-positive voxel sizes and non-finite transforms.
NiftiLayout niftiLayout(const Bytes& h) {
  NiftiLayout layout;
  bool& swap = layout.swap;
  const std::int32_t size = headerSize(h, swap);
  const bool pair1 = size == 348 && h.size() >= 348 && std::memcmp(h.data() + 344, "ni1", 4) == 0;
  const bool pair2 = size == 540 && h.size() >= 540 && std::memcmp(h.data() + 4, "ni2", 3) == 0;
  const bool v1 = pair1 || (size == 348 && h.size() >= 352 && std::memcmp(h.data() + 344, "n+1", 4) == 0);
  const bool v2 = pair2 || (size == 540 && h.size() >= 544 && std::memcmp(h.data() + 4, "n+2", 3) == 0);
  if (!v1 && !v2) return layout;
  layout.pair = pair1 || pair2;
  auto real = [&](std::size_t v1Offset, std::size_t v2Offset) {
    return v1 ? double(field<float>(h, v1Offset, swap)) : field<double>(h, v2Offset, swap);
  };
  const std::int64_t rank = v1 ? field<std::int16_t>(h, 40, swap) : field<std::int64_t>(h, 16, swap);
  if (rank < 1 || rank > 7) throw std::runtime_error("NIfTI header has " + std::to_string(rank) + " dimensions");
  for (int a = 1; a <= rank; ++a) {  // the NIfTI library prints its own complaint to stderr: speak first
    const std::int64_t n = v1 ? field<std::int16_t>(h, 40 + 2 * a, swap) : field<std::int64_t>(h, 16 + 8 * a, swap);
    if (n < 1) throw std::runtime_error("NIfTI header gives axis " + std::to_string(a - 1) + " " + std::to_string(n) + " voxels");
  }
  for (int a = 1; a <= std::min<std::int64_t>(rank, 3); ++a) {
    const double spacing = real(76 + 4 * a, 104 + 8 * a);
    if (!std::isfinite(spacing) || spacing <= 0) {
      std::ostringstream why;
      why << "voxel size " << spacing << " along axis " << a - 1 << " is not a positive number";
      throw std::runtime_error(why.str());
    }
  }
  const int qformCode = v1 ? field<std::int16_t>(h, 252, swap) : field<std::int32_t>(h, 344, swap);
  const int sformCode = v1 ? field<std::int16_t>(h, 254, swap) : field<std::int32_t>(h, 348, swap);
  for (int i = 0; i < 6 && qformCode > 0; ++i)
    if (!std::isfinite(real(256 + 4 * i, 352 + 8 * i)))
      throw std::runtime_error("NIfTI qform (orientation or origin) is not finite");
  for (int i = 0; i < 12 && sformCode > 0; ++i)
    if (!std::isfinite(real(280 + 4 * i, 400 + 8 * i)))
      throw std::runtime_error("NIfTI sform (orientation or origin) is not finite");
  const double offset = v1 ? double(field<float>(h, 108, swap)) : double(field<std::int64_t>(h, 168, swap));
  if (!std::isfinite(offset) || offset < 0) throw std::runtime_error("NIfTI voxel offset is not valid");
  const int datatype = field<std::int16_t>(h, v1 ? 70 : 12, swap);
  layout.floatBytes = datatype == 16 ? 4 : datatype == 64 ? 8 : 0;
  layout.offset = layout.pair ? offset : std::max(offset, v1 ? 352.0 : 544.0);
  return layout;
}

/// Follows a NIfTI file's bytes as they stream by: its layout once the header has passed, the
/// size, and the float voxels that are NaN or infinite (the NIfTI library turns them into 0 on
/// read, so a damaged label or intensity would pass as background).
class NiftiScan {
public:
  explicit NiftiScan(std::uint64_t voxelBytes) : voxelBytes_(voxelBytes) {}
  /// For the .img of a two-file NIfTI, whose header was read apart.
  NiftiScan(std::uint64_t voxelBytes, const NiftiLayout& layout) : voxelBytes_(voxelBytes), parsed_(true), layout_(layout) {}
  void feed(const unsigned char* p, std::size_t n) {
    if (!parsed_) {
      const std::size_t take = std::min(n, kHead - head_.size());
      head_.insert(head_.end(), p, p + take);
      if (head_.size() == kHead) parse();
      position_ += take;
      p += take;
      n -= take;
    }
    scan(p, n);
  }
  /// Checks the size once the stream has ended; returns false when it was not NIfTI.
  bool finish() {
    if (!parsed_) parse();
    if (layout_.offset < 0) return false;
    const auto offset = static_cast<std::uint64_t>(layout_.offset);
    requireBytes(position_ > offset ? position_ - offset : 0, voxelBytes_);
    if (nonFinite_)
      throw std::runtime_error("voxel values are not finite (" + std::to_string(nonFinite_) + " NaN or infinity)");
    return true;
  }

private:
  static constexpr std::size_t kHead = 544;
  void parse() {
    parsed_ = true;
    layout_ = niftiLayout(head_);
    if (layout_.offset >= 0) {
      const std::uint64_t start = position_;
      position_ = 0;
      scan(head_.data(), head_.size());
      position_ = start;
    }
  }
  void scan(const unsigned char* p, std::size_t n) {
    const std::size_t b = std::size_t(layout_.floatBytes);
    if (b && layout_.offset >= 0) {
      const auto begin = static_cast<std::uint64_t>(layout_.offset), end = begin + voxelBytes_;
      for (std::size_t i = 0; i < n; ++i) {
        const std::uint64_t at = position_ + i;
        if (at < begin || at >= end) continue;
        value_[(at - begin) % b] = p[i];
        if ((at - begin) % b == b - 1) countIfNonFinite();
      }
    }
    position_ += n;
  }
  void countIfNonFinite() {
    const Bytes v(value_, value_ + layout_.floatBytes);
    const double x = layout_.floatBytes == 4 ? double(field<float>(v, 0, layout_.swap)) : field<double>(v, 0, layout_.swap);
    nonFinite_ += std::isfinite(x) ? 0 : 1;
  }
  std::uint64_t voxelBytes_, position_ = 0, nonFinite_ = 0;
  Bytes head_;
  bool parsed_ = false;
  NiftiLayout layout_;
  unsigned char value_[8] = {};
};

// ---- NRRD and MetaImage: text headers ------------------------------------------------------------

enum class Encoding { Raw, Compressed, Ascii, Hex, Bzip2 };

struct DataLocation {
  std::string file;       ///< where the voxels are
  std::uint64_t offset = 0;
  Encoding encoding = Encoding::Raw;
  bool checkable = true;  ///< false for layouts not checked (unknown encodings, file lists, end-anchored data)
  std::uint64_t values = 0;  ///< voxel values the header promises (NRRD's sizes), for text encodings
};

DataLocation nrrdData(const std::string& path) {
  std::ifstream in = openBinary(path);
  DataLocation d{path};
  std::string line;
  std::getline(in, line);
  for (int n = 0; n < 100000 && std::getline(in, line); ++n) {
    line = trim(line);
    if (line.empty()) {
      if (d.file == path) d.offset = static_cast<std::uint64_t>(in.tellg());
      return d;
    }
    if (line[0] == '#') continue;
    const auto colon = line.find(':');
    if (colon == std::string::npos) continue;
    const std::string key = lower(trim(line.substr(0, colon)));
    std::string value = trim(line.substr(colon + 1));
    if (!value.empty() && value[0] == '=') continue;  // key/value comment pair
    if (key == "encoding") {
      value = lower(value);
      d.encoding = value == "gzip" || value == "gz"   ? Encoding::Compressed
                   : value == "ascii" || value == "text" || value == "txt" ? Encoding::Ascii
                   : value == "hex"                   ? Encoding::Hex
                   : value == "bzip2" || value == "bz2" ? Encoding::Bzip2
                                                      : Encoding::Raw;
      d.checkable = d.checkable && (d.encoding != Encoding::Raw || value == "raw");
    } else if (key == "sizes") {
      std::istringstream sizes(value);
      d.values = 1;
      for (std::uint64_t n = 0; sizes >> n;) d.values *= n;
    } else if (key == "data file" || key == "datafile") {
      if (value.find(' ') != std::string::npos || value == "LIST") return {path, 0, Encoding::Raw, false};
      d.file = value[0] == '/' ? value : directoryOf(path) + value;
      d.offset = 0;
    } else if (key == "line skip" || key == "lineskip") {
      d.checkable = d.checkable && value == "0";
    } else if (key == "byte skip" || key == "byteskip") {
      d.checkable = d.checkable && value.find('-') == std::string::npos;
    }
  }
  if (d.file != path) return d;  // detached header may end without a blank line
  throw std::runtime_error("NRRD header has no data (no blank line after it and no data file)");
}

DataLocation metaImageData(const std::string& path) {
  std::ifstream in = openBinary(path);
  DataLocation d{path};
  std::string line;
  for (int n = 0; n < 100000 && std::getline(in, line); ++n) {
    const auto eq = line.find('=');
    if (eq == std::string::npos) continue;
    const std::string key = lower(trim(line.substr(0, eq)));
    const std::string value = trim(line.substr(eq + 1));
    if (key == "compresseddata") d.encoding = lower(value) == "true" ? Encoding::Compressed : Encoding::Raw;
    if (key == "headersize" && value != "0") d.checkable = false;
    if (key == "elementdatafile") {
      if (value == "LOCAL") {
        d.offset = static_cast<std::uint64_t>(in.tellg());
      } else if (value == "LIST" || value.find('%') != std::string::npos || value.find(' ') != std::string::npos) {
        d.checkable = false;
      } else {
        d.file = value[0] == '/' ? value : directoryOf(path) + value;
      }
      return d;
    }
  }
  throw std::runtime_error("MetaImage header has no ElementDataFile");
}

/// Counts what a text encoding holds from the current position of `in` to its end: numbers (ASCII,
/// separated by white space or commas) or hex digits (white space between them ignored).
std::uint64_t countText(std::istream& in, Encoding encoding) {
  std::uint64_t count = 0;
  bool inToken = false;
  std::vector<char> chunk(1 << 18);
  while (in.read(chunk.data(), static_cast<std::streamsize>(chunk.size())) || in.gcount()) {
    for (std::streamsize i = 0; i < in.gcount(); ++i) {
      const unsigned char c = static_cast<unsigned char>(chunk[std::size_t(i)]);
      const bool separator = std::isspace(c) || (encoding == Encoding::Ascii && c == ',');
      if (encoding == Encoding::Hex) {
        if (std::isxdigit(c)) ++count;
        else if (!separator) throw std::runtime_error("hex data holds a character that is not a hex digit");
      } else {
        count += !separator && !inToken ? 1 : 0;
        inToken = !separator;
      }
    }
  }
  return count;
}

void checkDataAt(const DataLocation& d, std::uint64_t voxelBytes) {
  if (d.encoding == Encoding::Bzip2)
    throw std::runtime_error("bzip2-encoded NRRD data cannot be read; save it raw or gzip-encoded");
  std::ifstream in = openBinary(d.file);
  in.seekg(0, std::ios::end);
  const std::uint64_t size = static_cast<std::uint64_t>(in.tellg());
  if (d.offset > size) requireBytes(0, voxelBytes);
  in.seekg(static_cast<std::streamoff>(d.offset));
  if (d.encoding == Encoding::Raw) return requireBytes(size - d.offset, voxelBytes);
  if (d.encoding == Encoding::Compressed) return requireBytes(inflateToEnd(in), voxelBytes);
  const std::uint64_t count = countText(in, d.encoding);
  const bool hex = d.encoding == Encoding::Hex;
  const std::uint64_t needed = hex ? 2 * voxelBytes : d.values;
  if (count < needed)
    throw std::runtime_error("file holds " + std::to_string(count) + (hex ? " hex digits" : " values") +
                             ", its header promises " + std::to_string(needed) +
                             " (the file is truncated or its header is wrong)");
}

void checkDataLocation(const std::string& header, const DataLocation& d, std::uint64_t voxelBytes) {
  if (!d.checkable) return;
  try {
    checkDataAt(d, voxelBytes);
  } catch (const std::runtime_error& e) {
    if (d.file == header) throw;
    throw std::runtime_error("data file " + d.file + ": " + e.what());  // the file at fault, named
  }
}

/// Every number of a geometry field ("(1,0,0) (0,1,0)", "8 8 10") must be finite; "none" marks a
/// non-spatial axis in NRRD.
void requireFiniteNumbers(const std::string& key, std::string value) {
  for (char& c : value)
    if (c == '(' || c == ')' || c == ',') c = ' ';
  std::istringstream tokens(value);
  for (std::string token; tokens >> token;) {
    if (token == "none") continue;
    char* end = nullptr;
    const double x = std::strtod(token.c_str(), &end);
    if (*end != '\0' || !std::isfinite(x))
      throw std::runtime_error("header field '" + key + "' holds '" + token + "', not a finite number");
  }
}

/// Geometry fields of a NRRD or MetaImage text header, checked before ITK sees them (a NaN in a
/// direction aborts deep inside ITK's matrix code; a NaN spacing is passed on as it is).
void checkTextHeaderGeometry(const std::string& path, char separator) {
  static const char* const kGeometry[] = {"spacings", "space directions", "space origin", "thicknesses",
                                          "transformmatrix", "rotation", "orientation", "offset", "position",
                                          "origin", "elementspacing", "elementsize", "centerofrotation"};
  std::ifstream in = openBinary(path);
  std::string line;
  for (int n = 0; n < 100000 && std::getline(in, line); ++n) {
    if (trim(line).empty()) return;  // NRRD: the data follows
    const auto at = line.find(separator);
    if (at == std::string::npos || line[0] == '#') continue;
    const std::string key = lower(trim(line.substr(0, at)));
    if (key == "elementdatafile") return;  // MetaImage: the data follows
    for (const char* g : kGeometry)
      if (key == g) requireFiniteNumbers(key, trim(line.substr(at + 1)));
  }
}

bool endsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && lower(s.substr(s.size() - suffix.size())) == suffix;
}

/// Passes a whole file's bytes to `sink`, inflated (and checked) when the file is gzip.
void streamFile(const std::string& path, const Sink& sink) {
  std::ifstream in = openBinary(path);
  unsigned char magic[2] = {0, 0};
  in.read(reinterpret_cast<char*>(magic), 2);
  in.clear();
  in.seekg(0);
  if (magic[0] == 0x1f && magic[1] == 0x8b) {
    inflateToEnd(in, sink);
    return;
  }
  Bytes chunk(1 << 18);
  while (in.read(reinterpret_cast<char*>(chunk.data()), static_cast<std::streamsize>(chunk.size())) || in.gcount())
    sink(chunk.data(), static_cast<std::size_t>(in.gcount()));
}

// ---- two-file NIfTI (.hdr + .img) ----------------------------------------------------------------

bool isNiftiData(const std::string& path) { return endsWith(path, ".img") || endsWith(path, ".img.gz"); }

/// The other file of a two-file NIfTI named by `path` (.hdr <-> .img, gzipped or not: the first that
/// exists, else the plain name); "" when `path` is named as neither.
std::string niftiCompanion(const std::string& path) {
  for (const char* ext : {".hdr", ".img", ".hdr.gz", ".img.gz"}) {
    if (!endsWith(path, ext)) continue;
    const std::string stem = path.substr(0, path.size() - std::strlen(ext));
    const std::string other = stem + (ext[1] == 'h' ? ".img" : ".hdr");
    return std::ifstream(other) || !std::ifstream(other + ".gz") ? other : other + ".gz";
  }
  return "";
}

/// The first 544 bytes of a NIfTI header file (fewer when it is shorter), gzipped or not.
Bytes niftiHead(const std::string& path) {
  gzFile gz = gzopen(path.c_str(), "rb");  // reads plain files as they are
  if (!gz) throw std::runtime_error(path + " cannot be opened");
  Bytes head(544);
  const int got = gzread(gz, head.data(), static_cast<unsigned>(head.size()));
  gzclose(gz);
  head.resize(got > 0 ? std::size_t(got) : 0);
  return head;
}

/// The .img of a two-file NIfTI holds every voxel its header promises (and finite floats).
void checkNiftiData(const std::string& data, const NiftiLayout& layout, std::uint64_t voxelBytes) {
  if (!std::ifstream(data)) throw std::runtime_error("data file " + data + " is missing or unreadable");
  try {
    NiftiScan scan(voxelBytes, layout);
    streamFile(data, [&](const unsigned char* p, std::size_t n) { scan.feed(p, n); });
    scan.finish();
  } catch (const std::runtime_error& e) {
    throw std::runtime_error("data file " + data + ": " + e.what());
  }
}

}  // namespace

void checkImageHeader(const std::string& path) {
  std::ifstream in = openBinary(path);
  char magic[4] = {0, 0, 0, 0};
  in.read(magic, 4);
  if (std::memcmp(magic, "NRRD", 4) == 0) return checkTextHeaderGeometry(path, ':');
  if (endsWith(path, ".mha") || endsWith(path, ".mhd")) return checkTextHeaderGeometry(path, '=');
  niftiLayout(niftiHead(isNiftiData(path) ? niftiCompanion(path) : path));
}

void checkImageFileIntegrity(const std::string& path, std::uint64_t voxelBytes) {
  const std::string companion = niftiCompanion(path);
  if (!companion.empty()) {
    const std::string header = isNiftiData(path) ? companion : path, data = isNiftiData(path) ? path : companion;
    const NiftiLayout layout = niftiLayout(niftiHead(header));
    if (layout.pair) return checkNiftiData(data, layout, voxelBytes);
  }
  std::ifstream in = openBinary(path);
  char magic[4] = {0, 0, 0, 0};
  in.read(magic, 4);
  if (std::memcmp(magic, "NRRD", 4) == 0) return checkDataLocation(path, nrrdData(path), voxelBytes);
  if (endsWith(path, ".mha") || endsWith(path, ".mhd")) return checkDataLocation(path, metaImageData(path), voxelBytes);
  NiftiScan nifti(voxelBytes);
  streamFile(path, [&](const unsigned char* p, std::size_t n) { nifti.feed(p, n); });
  nifti.finish();
}

}  // namespace repose
