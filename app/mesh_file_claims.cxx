#include "mesh_file_claims.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <map>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace repose {
namespace {

constexpr double kMaxDeflateRatio = 1032;  // deflate's largest expansion (zlib's technical notes)
constexpr double kMaxCount = 2147483647;   // counts beyond an int are damage, not anatomy

std::string lowerExtension(const std::string& path) {
  const auto dot = path.find_last_of('.');
  const auto slash = path.find_last_of('/');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  std::string ext = path.substr(dot);
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

std::uint64_t fileSize(std::ifstream& in) {
  in.seekg(0, std::ios::end);
  const auto size = static_cast<std::uint64_t>(in.tellg());
  in.seekg(0);
  return size;
}

/// A word of a file for a message: short and printable.
std::string shown(const std::string& word) {
  std::string out = word.substr(0, 20);
  for (char& c : out)
    if (!std::isprint(static_cast<unsigned char>(c))) c = '?';
  return out;
}

/// A claimed count: a whole number in 0..kMaxCount whose elements, `minBytes` each, fit in
/// `available` bytes (`expansion` times `fileBytes` for data that may be compressed).
double claimedCount(const std::string& text, const std::string& what, double minBytes, double fileBytes,
                    double expansion = 1) {
  char* end = nullptr;
  const double n = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || !(n >= 0) || n != std::floor(n) || n > kMaxCount)
    throw std::runtime_error("header claims '" + shown(text) + "' " + what + ", not a count");
  if (n * minBytes > fileBytes * expansion)
    throw std::runtime_error("header claims " + text + " " + what + ", more than the file's " +
                             std::to_string(std::uint64_t(fileBytes)) + " bytes can hold" +
                             (expansion > 1 ? " even compressed" : "") + " (truncated or damaged)");
  return n;
}

/// ASCII STL, word by word: solid NAME, then facets (normal, outer loop of three finite vertices,
/// endloop, endfacet) up to endsolid. VTK's reader skips what it does not understand.
void checkAsciiStl(std::ifstream& in) {
  std::string line, word;
  std::getline(in, line);  // solid NAME
  std::int64_t facet = 0;
  auto expect = [&](const char* what) {
    if (!(in >> word)) throw std::runtime_error("ASCII STL ends inside facet " + std::to_string(facet) + " (truncated)");
    if (word != what)
      throw std::runtime_error("ASCII STL facet " + std::to_string(facet) + ": '" + shown(word) + "' where '" +
                               what + "' belongs");
  };
  auto numbers = [&] {
    for (int c = 0; c < 3; ++c) {
      if (!(in >> word)) throw std::runtime_error("ASCII STL ends inside facet " + std::to_string(facet) + " (truncated)");
      char* end = nullptr;
      const double x = std::strtod(word.c_str(), &end);
      if (*end != '\0' || !std::isfinite(x))
        throw std::runtime_error("ASCII STL facet " + std::to_string(facet) + ": '" + shown(word) +
                                 "' is not a finite number");
    }
  };
  while (in >> word) {
    if (word == "endsolid") {
      std::getline(in, line);  // its name
      if (!(in >> word)) return;
      if (word != "solid") throw std::runtime_error("ASCII STL: '" + shown(word) + "' after endsolid");
      std::getline(in, line);
      continue;
    }
    if (word != "facet")
      throw std::runtime_error("ASCII STL: '" + shown(word) + "' where a facet or endsolid belongs");
    expect("normal");
    numbers();
    expect("outer");
    expect("loop");
    for (int v = 0; v < 3; ++v) {
      expect("vertex");
      numbers();
    }
    expect("endloop");
    expect("endfacet");
    ++facet;
  }
  throw std::runtime_error("ASCII STL without 'endsolid' (truncated)");
}

void checkStl(std::ifstream& in, std::uint64_t size) {
  char head[84] = {};
  in.read(head, 84);
  std::uint32_t triangles = 0;
  std::memcpy(&triangles, head + 80, 4);  // binary STL is little-endian, as this machine
  if (size >= 84 && size == 84 + 50 * std::uint64_t(triangles)) return;
  std::string start(head, static_cast<std::size_t>(in.gcount()));
  start.erase(0, start.find_first_not_of(" \t\r\n"));
  if (start.rfind("solid", 0) == 0) {
    in.clear();
    in.seekg(0);
    return checkAsciiStl(in);
  }
  if (size < 84) throw std::runtime_error("not an STL file (" + std::to_string(size) + " bytes)");
  throw std::runtime_error("binary STL of " + std::to_string(triangles) + " triangles should have " +
                           std::to_string(84 + 50 * std::uint64_t(triangles)) + " bytes, the file has " +
                           std::to_string(size) + " (truncated or not an STL)");
}

struct PlyType {
  int bytes = 0;
  char kind = 'i';  ///< 'i' signed, 'u' unsigned, 'f' floating point
};

PlyType plyType(const std::string& name) {
  static const std::map<std::string, PlyType> types = {
      {"char", {1, 'i'}},   {"int8", {1, 'i'}},   {"uchar", {1, 'u'}},  {"uint8", {1, 'u'}},   {"short", {2, 'i'}},
      {"int16", {2, 'i'}},  {"ushort", {2, 'u'}}, {"uint16", {2, 'u'}}, {"int", {4, 'i'}},     {"int32", {4, 'i'}},
      {"uint", {4, 'u'}},   {"uint32", {4, 'u'}}, {"float", {4, 'f'}},  {"float32", {4, 'f'}}, {"double", {8, 'f'}},
      {"float64", {8, 'f'}}};
  const auto it = types.find(name);
  if (it == types.end()) throw std::runtime_error("PLY header names an unknown type '" + name + "'");
  return it->second;
}

struct PlyProperty {
  std::string name;
  PlyType value;
  PlyType count;  ///< bytes 0 for a scalar property
};

struct PlyElement {
  std::string name, count;
  std::vector<PlyProperty> properties;
};

/// Reads the PLY body value by value, as the header describes it: a file cut short, a list longer
/// than the file, a non-finite vertex coordinate or a face naming a missing vertex is refused here,
/// before VTK's PLY library (which crashes on some of them) sees the file.
class PlyWalk {
public:
  PlyWalk(std::ifstream& in, const std::string& format) : in_(in), format_(format) {}

  void element(const PlyElement& e, double count, double vertices) {
    const bool face = e.name == "face";
    for (double k = 0; k < count; ++k)
      for (const PlyProperty& p : e.properties) {
        const double n = p.count.bytes ? value(p.count) : 1;
        if (!(n >= 0) || n != std::floor(n) || n > 1e6)
          throw std::runtime_error(e.name + " " + number(k) + ": list of " + number(n) + " values");
        for (double v = 0; v < n; ++v) {
          const double x = value(p.value);
          if (!std::isfinite(x)) throw std::runtime_error(e.name + " " + number(k) + ": a value is not finite");
          if (face && p.count.bytes && (x < 0 || x >= vertices || x != std::floor(x)))
            throw std::runtime_error("face " + number(k) + " names vertex " + number(x) + ", the file has " +
                                     number(vertices));
        }
      }
  }

private:
  static std::string number(double x) {
    std::ostringstream text;
    text << std::setprecision(12) << x;
    return text.str();
  }
  double value(const PlyType& t) {
    if (format_ == "ascii") {
      std::string word;
      if (!(in_ >> word)) throw std::runtime_error("the file ends before its header's counts (truncated)");
      char* end = nullptr;
      const double x = std::strtod(word.c_str(), &end);
      if (*end != '\0') throw std::runtime_error("'" + word + "' is not a number");
      return x;
    }
    unsigned char b[8];
    if (!in_.read(reinterpret_cast<char*>(b), t.bytes))
      throw std::runtime_error("the file ends before its header's counts (truncated)");
    if (format_ == "binary_big_endian") std::reverse(b, b + t.bytes);
    auto as = [&](auto v) {
      std::memcpy(&v, b, sizeof v);
      return double(v);
    };
    if (t.kind == 'f') return t.bytes == 4 ? as(float()) : as(double());
    if (t.bytes == 1) return t.kind == 'i' ? as(std::int8_t()) : as(std::uint8_t());
    if (t.bytes == 2) return t.kind == 'i' ? as(std::int16_t()) : as(std::uint16_t());
    return t.kind == 'i' ? as(std::int32_t()) : as(std::uint32_t());
  }
  std::ifstream& in_;
  std::string format_;
};

void checkPly(std::ifstream& in, std::uint64_t size) {
  std::string line;
  std::getline(in, line);
  if (line.rfind("ply", 0) != 0) throw std::runtime_error("not a PLY file (no 'ply' line)");
  std::string format;
  std::vector<PlyElement> elements;
  for (int n = 0; n < 10000 && std::getline(in, line); ++n) {
    std::istringstream words(line);
    std::string key;
    words >> key;
    if (key == "end_header") {
      if (format != "ascii" && format != "binary_little_endian" && format != "binary_big_endian")
        throw std::runtime_error("PLY format '" + format + "' is not ascii or binary");
      const double available = double(size) - double(in.tellg());
      std::vector<double> counts;
      double vertices = 0;
      for (const PlyElement& e : elements) {  // every count plausible before anything is read
        double minBytes = 0;
        for (const PlyProperty& p : e.properties) minBytes += format == "ascii" ? 2 : std::max(p.count.bytes, p.value.bytes);
        counts.push_back(claimedCount(e.count, e.name + " elements", minBytes, available));
        if (e.name == "vertex") vertices = counts.back();
      }
      PlyWalk walk(in, format);
      for (std::size_t e = 0; e < elements.size(); ++e) walk.element(elements[e], counts[e], vertices);
      return;
    }
    if (key == "format") {
      words >> format;
    } else if (key == "element") {
      PlyElement e;
      words >> e.name >> e.count;
      elements.push_back(e);
    } else if (key == "property") {
      if (elements.empty()) throw std::runtime_error("PLY property before any element");
      std::string type, countType, name;
      words >> type;
      PlyProperty p;
      if (type == "list") {
        words >> countType >> type;
        p.count = plyType(countType);
      }
      p.value = plyType(type);
      words >> p.name;
      elements.back().properties.push_back(p);
    }
  }
  throw std::runtime_error("PLY header without 'end_header'");
}

/// OBJ: vertices finite, face indices (1-based, negative relative to the last vertex) in range.
void checkObj(std::ifstream& in) {
  std::string line;
  std::int64_t vertices = 0;
  std::vector<std::pair<std::int64_t, std::int64_t>> forward;  // (index, line) naming a later vertex
  for (std::int64_t number = 1; std::getline(in, line); ++number) {
    std::istringstream words(line);
    std::string key;
    words >> key;
    const std::string at = " (line " + std::to_string(number) + ")";
    if (key == "v") {
      for (int c = 0; c < 3; ++c) {
        std::string word;
        words >> word;
        char* end = nullptr;
        const double x = std::strtod(word.c_str(), &end);
        if (word.empty() || *end != '\0' || !std::isfinite(x))
          throw std::runtime_error("vertex coordinate '" + word + "' is not a finite number" + at);
      }
      ++vertices;
    } else if (key == "f" || key == "l") {
      int corners = 0;
      for (std::string word; words >> word; ++corners) {
        char* end = nullptr;
        const long long i = std::strtoll(word.c_str(), &end, 10);
        if (end == word.c_str() || (*end != '\0' && *end != '/') || i == 0 || i < -vertices)
          throw std::runtime_error("face index '" + word + "' names no vertex" + at);
        if (i > vertices) forward.push_back({i, number});
      }
      if (corners < (key == "f" ? 3 : 2))
        throw std::runtime_error(std::string(key == "f" ? "face" : "line") + " with " + std::to_string(corners) +
                                 " vertices" + at);
    }
  }
  for (const auto& [index, number] : forward)
    if (index > vertices)
      throw std::runtime_error("face index " + std::to_string(index) + " names no vertex (the file has " +
                               std::to_string(vertices) + ") (line " + std::to_string(number) + ")");
}

/// Legacy VTK: every "POINTS n", "POLYGONS n size", ... fits in the file, at 2 bytes a value.
void checkLegacyVtk(std::ifstream& in, std::uint64_t size) {
  static const std::map<std::string, int> valuesPer = {{"POINTS", 3}, {"VERTICES", 1}, {"LINES", 1},
                                                       {"POLYGONS", 1}, {"TRIANGLE_STRIPS", 1}, {"CELLS", 1},
                                                       {"CELL_TYPES", 1}, {"POINT_DATA", 1}, {"CELL_DATA", 1}};
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream words(line);
    std::string key, count, total;
    words >> key >> count;
    const auto it = valuesPer.find(key);
    if (it == valuesPer.end()) continue;
    claimedCount(count, key, 2.0 * it->second, double(size));
    if ((key == "POLYGONS" || key == "LINES" || key == "VERTICES" || key == "TRIANGLE_STRIPS" || key == "CELLS") &&
        words >> total)
      claimedCount(total, key + " values", 2.0, double(size));
  }
}

/// VTK XML: NumberOfPoints/Cells/Polys/... fit in the file even if compressed at deflate's best.
void checkXmlVtk(std::ifstream& in, std::uint64_t size) {
  std::string head(static_cast<std::size_t>(std::min<std::uint64_t>(size, 1 << 16)), '\0');
  in.read(&head[0], static_cast<std::streamsize>(head.size()));
  for (const char* attribute : {"NumberOfPoints", "NumberOfCells", "NumberOfPolys", "NumberOfStrips",
                                "NumberOfLines", "NumberOfVerts"}) {
    const std::string key = std::string(attribute) + "=\"";
    for (auto at = head.find(key); at != std::string::npos; at = head.find(key, at + 1)) {
      const auto begin = at + key.size(), end = head.find('"', begin);
      if (end == std::string::npos) break;
      claimedCount(head.substr(begin, end - begin), attribute, std::strcmp(attribute, "NumberOfPoints") ? 1 : 3,
                   double(size), kMaxDeflateRatio);
    }
  }
}

}  // namespace

void checkMeshFileClaims(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot be opened");
  const std::uint64_t size = fileSize(in);
  const std::string ext = lowerExtension(path);
  if (size == 0) throw std::runtime_error("empty file");
  if (ext == ".stl") return checkStl(in, size);
  if (ext == ".ply") return checkPly(in, size);
  if (ext == ".obj") return checkObj(in);
  if (ext == ".vtk") return checkLegacyVtk(in, size);
  if (ext == ".vtp" || ext == ".vtu") return checkXmlVtk(in, size);
}

}  // namespace repose
