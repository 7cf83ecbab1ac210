#include "lattice_crossings.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace repose {
namespace {

/// Sign of orient(a, b, p) in the row plane with p moved by (eps, eps^2): never 0 for an edge of
/// non-zero length, and computed from the edge's endpoints in one canonical order, so two triangles
/// sharing an edge (or a vertex) agree exactly on which side of it p lies.
int orientSign(Eigen::Vector2d a, Eigen::Vector2d b, const Eigen::Vector2d& p) {
  const bool swapped = b.x() < a.x() || (b.x() == a.x() && b.y() < a.y());
  if (swapped) std::swap(a, b);
  double v = (b.x() - a.x()) * (p.y() - a.y()) - (b.y() - a.y()) * (p.x() - a.x());
  if (v == 0) v = b.y() != a.y() ? a.y() - b.y() : b.x() - a.x();
  const int s = v > 0 ? 1 : (v < 0 ? -1 : 0);
  return swapped ? -s : s;
}

}  // namespace

void crossRows(const Eigen::Vector3d& a0, const Eigen::Vector3d& b0, const Eigen::Vector3d& c0, int axis,
               const IndexBox& box0, std::vector<RowCrossing>& out) {
  // The axes taken cyclically from `axis` (a rotation: orientations and so signs are kept), so
  // the row runs along x and the rows are numbered over (y, z).
  const int u = (axis + 1) % 3, v = (axis + 2) % 3;
  auto cyclic = [&](const Eigen::Vector3d& p) { return Eigen::Vector3d(p[axis], p[u], p[v]); };
  const Eigen::Vector3d a = cyclic(a0), b = cyclic(b0), c = cyclic(c0);
  const std::array<int, 3> min{box0.min[axis], box0.min[u], box0.min[v]};
  const std::array<int, 3> dims{box0.dims[axis], box0.dims[u], box0.dims[v]};
  const int j0 = std::max(min[1], int(std::ceil(std::min({a.y(), b.y(), c.y()}))));
  const int j1 = std::min(min[1] + dims[1] - 1, int(std::floor(std::max({a.y(), b.y(), c.y()}))));
  const int k0 = std::max(min[2], int(std::ceil(std::min({a.z(), b.z(), c.z()}))));
  const int k1 = std::min(min[2] + dims[2] - 1, int(std::floor(std::max({a.z(), b.z(), c.z()}))));
  const Eigen::Vector2d A(a.y(), a.z()), B(b.y(), b.z()), C(c.y(), c.z());
  for (int k = k0; k <= k1; ++k)
    for (int j = j0; j <= j1; ++j) {
      const Eigen::Vector2d p(j, k);
      const int sa = orientSign(B, C, p), sb = orientSign(C, A, p), sc = orientSign(A, B, p);
      if (sa != sb || sb != sc || sa == 0) continue;
      // Barycentric coordinates from the plain (unperturbed) areas give where the row meets it.
      const double wa = (C.x() - B.x()) * (p.y() - B.y()) - (C.y() - B.y()) * (p.x() - B.x());
      const double wb = (A.x() - C.x()) * (p.y() - C.y()) - (A.y() - C.y()) * (p.x() - C.x());
      const double wc = (B.x() - A.x()) * (p.y() - A.y()) - (B.y() - A.y()) * (p.x() - A.x());
      const double sum = wa + wb + wc;
      const double x = sum != 0 ? (wa * a.x() + wb * b.x() + wc * c.x()) / sum : (a.x() + b.x() + c.x()) / 3;
      // Voxels i < x lie before the crossing.
      const double last = std::ceil(x) - 1 - min[0];
      if (last < 0) continue;
      const std::uint32_t row = std::uint32_t(std::size_t(k - min[2]) * std::size_t(dims[1]) + std::size_t(j - min[1]));
      out.push_back({row, int(std::min(last, double(dims[0] - 1))), sa});
    }
}

}  // namespace repose
