#include "tet_boundary.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <stdexcept>
#include <string>

#include "parallel_for.h"

namespace repose {

TetBoundary tetBoundary(const Tets& tets) {
  TetBoundary out;
  const std::size_t nT = std::size_t(tets.rows());
  out.boundaryFaceMask.assign(nT, 0);
  out.touchesBoundary.assign(nT, 0);
  if (nT == 0) return out;
  if (tets.minCoeff() < 0) throw std::invalid_argument("tet boundary: negative tet node index");
  if (nT >= (std::size_t(1) << 30)) throw std::invalid_argument("tet boundary: more than 2^30 tets");
  const std::size_t nV = std::size_t(tets.maxCoeff()) + 1;

  // Bucket the 4T faces by their smallest node (CSR), then match faces within each bucket: buckets are
  // small (faces around one node), so this is linear in #T and avoids a global sort.
  std::vector<std::uint32_t> offset(nV + 1, 0);
  auto faceNodes = [&](std::size_t t, int a) {
    std::array<int, 3> f;
    int n = 0;
    for (int c = 0; c < 4; ++c)
      if (c != a) f[n++] = tets(t, c);
    std::sort(f.begin(), f.end());
    return f;
  };
  for (std::size_t t = 0; t < nT; ++t)
    for (int a = 0; a < 4; ++a) ++offset[std::size_t(faceNodes(t, a)[0]) + 1];
  for (std::size_t v = 0; v < nV; ++v) offset[v + 1] += offset[v];
  struct Face {
    int b, c;           // the two larger nodes
    std::uint32_t id;   // 4 * tet + local vertex opposite the face
  };
  std::vector<Face> faces(4 * nT);
  {
    std::vector<std::uint32_t> fill(offset.begin(), offset.end() - 1);
    for (std::size_t t = 0; t < nT; ++t)
      for (int a = 0; a < 4; ++a) {
        const auto f = faceNodes(t, a);
        faces[fill[std::size_t(f[0])]++] = {f[1], f[2], std::uint32_t(4 * t + a)};
      }
  }
  // Faces are entered in increasing id order within a bucket, so each bucket is processed
  // deterministically; distinct buckets touch distinct faces but may share a tet's mask byte, so bits
  // are collected per face first.
  std::vector<std::uint8_t> isBoundary(4 * nT, 0);
  parallelFor(nV, [&](std::size_t vb, std::size_t ve) {
    std::vector<Face> tmp;
    for (std::size_t v = vb; v < ve; ++v) {
      tmp.assign(faces.begin() + offset[v], faces.begin() + offset[v + 1]);
      std::sort(tmp.begin(), tmp.end(), [](const Face& x, const Face& y) {
        return x.b != y.b ? x.b < y.b : x.c != y.c ? x.c < y.c : x.id < y.id;
      });
      for (std::size_t q = 0; q < tmp.size();) {
        std::size_t r = q + 1;
        while (r < tmp.size() && tmp[r].b == tmp[q].b && tmp[r].c == tmp[q].c) ++r;
        if (r == q + 1) isBoundary[tmp[q].id] = 1;
        q = r;
      }
    }
  }, 4096);
  for (std::size_t t = 0; t < nT; ++t) {
    std::uint8_t m = 0;
    for (int a = 0; a < 4; ++a) m |= std::uint8_t(isBoundary[4 * t + a] << a);
    out.boundaryFaceMask[t] = m;
    out.boundaryFaces += std::size_t(isBoundary[4 * t]) + isBoundary[4 * t + 1] + isBoundary[4 * t + 2] + isBoundary[4 * t + 3];
    out.boundaryTets += m != 0;
  }
  std::vector<std::uint8_t> onBoundary(nV, 0);
  for (std::size_t t = 0; t < nT; ++t)
    for (int a = 0; a < 4; ++a)
      if ((out.boundaryFaceMask[t] >> a) & 1)
        for (int c = 0; c < 4; ++c)
          if (c != a) onBoundary[std::size_t(tets(t, c))] = 1;
  parallelFor(nT, [&](std::size_t b, std::size_t e) {
    for (std::size_t t = b; t < e; ++t)
      out.touchesBoundary[t] = onBoundary[std::size_t(tets(t, 0))] | onBoundary[std::size_t(tets(t, 1))] |
                               onBoundary[std::size_t(tets(t, 2))] | onBoundary[std::size_t(tets(t, 3))];
  }, 4096);
  return out;
}

}  // namespace repose
