#pragma once
// The unit tests' triangle soups: a UV sphere, an axis-aligned box, two soups in one, a sphere with
// its top cut off, and a reader for the binary PLY surfaces of the shared data.
#include <cmath>
#include <cstdint>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "mesh_topology.h"

namespace repose {

/// UV sphere: `rings` latitude bands, `segments` longitude segments, outward triangles.
inline TriangleMesh sphere(const Eigen::Vector3d& c, double r, int rings = 48, int segments = 96) {
  TriangleMesh m;
  const int n = 2 + (rings - 1) * segments;
  m.V.resize(n, 3);
  m.V.row(0) = (c + Eigen::Vector3d(0, 0, r)).transpose();
  m.V.row(1) = (c - Eigen::Vector3d(0, 0, r)).transpose();
  for (int a = 1; a < rings; ++a)
    for (int b = 0; b < segments; ++b) {
      const double th = M_PI * a / rings, ph = 2 * M_PI * b / segments;
      m.V.row(2 + (a - 1) * segments + b) =
          (c + r * Eigen::Vector3d(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th))).transpose();
    }
  std::vector<Eigen::Vector3i> f;
  auto at = [&](int a, int b) { return 2 + (a - 1) * segments + (b % segments); };
  for (int b = 0; b < segments; ++b) {
    f.push_back({0, at(1, b), at(1, b + 1)});
    f.push_back({1, at(rings - 1, b + 1), at(rings - 1, b)});
    for (int a = 1; a + 1 < rings; ++a) {
      f.push_back({at(a, b), at(a + 1, b), at(a + 1, b + 1)});
      f.push_back({at(a, b), at(a + 1, b + 1), at(a, b + 1)});
    }
  }
  m.F.resize(Eigen::Index(f.size()), 3);
  for (std::size_t i = 0; i < f.size(); ++i) m.F.row(Eigen::Index(i)) = f[i].transpose();
  return m;
}

/// Axis-aligned box from lo to hi, 12 triangles.
inline TriangleMesh box(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  TriangleMesh m;
  m.V.resize(8, 3);
  for (int i = 0; i < 8; ++i)
    m.V.row(i) << ((i & 1) ? hi.x() : lo.x()), ((i & 2) ? hi.y() : lo.y()), ((i & 4) ? hi.z() : lo.z());
  m.F.resize(12, 3);
  m.F << 0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4, 2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5;
  return m;
}

inline TriangleMesh concat(const TriangleMesh& a, const TriangleMesh& b) {
  TriangleMesh m;
  m.V.resize(a.V.rows() + b.V.rows(), 3);
  m.V << a.V, b.V;
  m.F.resize(a.F.rows() + b.F.rows(), 3);
  m.F << a.F, (b.F.array() + int(a.V.rows())).matrix();
  return m;
}

/// Drops the triangles whose centroid has z above `zCut`: a sphere with a round hole.
inline TriangleMesh cutTop(const TriangleMesh& s, double zCut) {
  TriangleMesh m;
  m.V = s.V;
  std::vector<int> keep;
  for (Eigen::Index t = 0; t < s.F.rows(); ++t)
    if ((s.V(s.F(t, 0), 2) + s.V(s.F(t, 1), 2) + s.V(s.F(t, 2), 2)) / 3 <= zCut) keep.push_back(int(t));
  m.F.resize(Eigen::Index(keep.size()), 3);
  for (std::size_t i = 0; i < keep.size(); ++i) m.F.row(Eigen::Index(i)) = s.F.row(keep[i]);
  return m;
}

/// Reverses every triangle: the soup faces the other way.
inline TriangleMesh inverted(TriangleMesh m) {
  m.F.col(1).swap(m.F.col(2));
  return m;
}

/// Binary little-endian PLY with float x, y, z vertices and uchar-counted int triangle lists (as
/// trimesh writes them). Throws std::runtime_error on anything else.
inline TriangleMesh readBinaryPly(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open");
  std::string line;
  long vertices = -1, faces = -1;
  while (std::getline(in, line) && line != "end_header") {
    std::istringstream s(line);
    std::string word, kind;
    s >> word;
    if (word == "element") {
      s >> kind;
      (kind == "vertex" ? vertices : faces) = [&] { long n; s >> n; return n; }();
    }
  }
  if (vertices <= 0 || faces <= 0) throw std::runtime_error(path + ": not a PLY surface");
  TriangleMesh m;
  m.V.resize(vertices, 3);
  for (long v = 0; v < vertices; ++v) {
    float p[3];
    in.read(reinterpret_cast<char*>(p), sizeof p);
    m.V.row(v) << p[0], p[1], p[2];
  }
  m.F.resize(faces, 3);
  for (long f = 0; f < faces; ++f) {
    std::uint8_t n = 0;
    std::int32_t ids[3];
    in.read(reinterpret_cast<char*>(&n), 1);
    if (n != 3) throw std::runtime_error(path + ": a face is not a triangle");
    in.read(reinterpret_cast<char*>(ids), sizeof ids);
    m.F.row(f) << ids[0], ids[1], ids[2];
  }
  if (!in) throw std::runtime_error(path + ": truncated");
  return m;
}

}  // namespace repose
