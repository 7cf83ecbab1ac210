#include "pinched_nodes.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Dense>

namespace repose {

double largestHalfSpaceMargin(const std::vector<Eigen::Vector3d>& normals, const std::vector<double>& offsets,
                              double cap, std::size_t maxPlanes) {
  const std::size_t m = normals.size();
  if (m == 0 || m > maxPlanes) return std::numeric_limits<double>::infinity();
  // Rows r.(x, s) >= beta: the planes (n, -1) >= offset, the cap (0, 0, 0, -1) >= -cap, and for each
  // direction d no normal spans, d.x >= -1 and -d.x >= -1 (they leave the margin alone but make the
  // feasible set pointed, so that its optimum is a vertex: four rows met with equality).
  std::vector<Eigen::Vector4d> rows;
  std::vector<double> beta;
  for (std::size_t i = 0; i < m; ++i) {
    rows.emplace_back(normals[i].x(), normals[i].y(), normals[i].z(), -1.0);
    beta.push_back(offsets[i]);
  }
  rows.emplace_back(0.0, 0.0, 0.0, -1.0);
  beta.push_back(-cap);
  Eigen::Matrix3d gram = Eigen::Matrix3d::Zero();  // sum of n n^T: its null space is what no normal spans
  for (const Eigen::Vector3d& n : normals) gram += n * n.transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(gram);
  for (int d = 0; d < 3; ++d)
    if (eig.eigenvalues()(d) <= 1e-12 * eig.eigenvalues()(2)) {
      const Eigen::Vector3d u = eig.eigenvectors().col(d);
      rows.emplace_back(u.x(), u.y(), u.z(), 0.0);
      beta.push_back(-1.0);
      rows.emplace_back(-u.x(), -u.y(), -u.z(), 0.0);
      beta.push_back(-1.0);
    }
  const std::size_t k = rows.size();
  double best = -std::numeric_limits<double>::infinity();
  Eigen::Matrix4d M;
  Eigen::Vector4d b;
  for (std::size_t i0 = 0; i0 < k; ++i0)
    for (std::size_t i1 = i0 + 1; i1 < k; ++i1)
      for (std::size_t i2 = i1 + 1; i2 < k; ++i2)
        for (std::size_t i3 = i2 + 1; i3 < k; ++i3) {
          const std::size_t pick[4] = {i0, i1, i2, i3};
          for (int r = 0; r < 4; ++r) {
            M.row(r) = rows[pick[r]].transpose();
            b(r) = beta[pick[r]];
          }
          const Eigen::FullPivLU<Eigen::Matrix4d> lu(M);
          if (lu.rank() < 4) continue;
          const Eigen::Vector4d z = lu.solve(b);
          if (!z.allFinite() || z(3) <= best) continue;
          bool feasible = true;
          for (std::size_t j = 0; j < k && feasible; ++j)
            feasible = rows[j].dot(z) >= beta[j] - 1e-9 * (1.0 + std::abs(beta[j]));
          if (feasible) best = z(3);
        }
  // No vertex passed (rounding in a degenerate set of planes): no answer, taken as room.
  return best > -std::numeric_limits<double>::infinity() ? best : std::numeric_limits<double>::infinity();
}

std::vector<PinchedNode> findPinchedNodes(const Points& posed, const Tets& tets, const std::vector<int>& fixedBone) {
  auto P = [&](int v) { return Eigen::Vector3d(posed.row(v).transpose()); };
  auto volume = [&](const int* T) { return tetVolume(P(T[0]), P(T[1]), P(T[2]), P(T[3])); };
  // The corner (0-3) of a tet's only free node; -1 where it has none or several.
  auto loneFreeCorner = [&](const int* T) {
    int corner = -1;
    for (int a = 0; a < 4; ++a)
      if (fixedBone[std::size_t(T[a])] < 0) {
        if (corner >= 0) return -1;
        corner = a;
      }
    return corner;
  };
  // The candidates: the one free node of each inverted tet with three bone nodes.
  std::vector<int> candidates;
  for (Eigen::Index t = 0; t < tets.rows(); ++t) {
    const int* T = tets.data() + 4 * t;
    const int local = loneFreeCorner(T);
    if (local >= 0 && volume(T) <= 0.0) candidates.push_back(T[local]);
  }
  std::sort(candidates.begin(), candidates.end());
  candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
  if (candidates.empty()) return {};
  // Each candidate's bone faces, as (unit normal, offset) with the node's current position as origin:
  // 6 V(x) = g.(x - a) is linear in the node's position x and vanishes on the face's plane.
  std::vector<std::vector<Eigen::Vector3d>> normals(candidates.size());
  std::vector<std::vector<double>> offsets(candidates.size());
  std::vector<double> size(candidates.size(), 0.0);
  for (Eigen::Index t = 0; t < tets.rows(); ++t) {
    const int* T = tets.data() + 4 * t;
    const int local = loneFreeCorner(T);
    if (local < 0) continue;
    const auto it = std::lower_bound(candidates.begin(), candidates.end(), T[local]);
    if (it == candidates.end() || *it != T[local]) continue;
    const std::size_t c = std::size_t(it - candidates.begin());
    const Eigen::Vector3d x = P(T[local]), a = P(T[(local + 1) % 4]);
    Eigen::Vector3d corner[4], g;
    for (int q = 0; q < 4; ++q) corner[q] = P(T[q]);
    for (int d = 0; d < 3; ++d) {  // g_d = 6 V with the node at a + e_d (V is 0 with it at a)
      corner[local] = a + Eigen::Vector3d::Unit(d);
      g(d) = 6.0 * tetVolume(corner[0], corner[1], corner[2], corner[3]);
    }
    const double norm = g.norm();
    if (!(norm > 0.0)) continue;  // a face of no area: not one a rigid bone carries (rest tets have volume)
    normals[c].push_back(g / norm);
    offsets[c].push_back((g / norm).dot(a - x));
    for (int q = 0; q < 4; ++q) size[c] = std::max(size[c], (P(T[q]) - x).norm());
  }
  std::vector<PinchedNode> pinched;
  for (std::size_t c = 0; c < candidates.size(); ++c) {
    const double margin = largestHalfSpaceMargin(normals[c], offsets[c], size[c]);
    if (margin < -1e-9 * size[c]) pinched.push_back({candidates[c], -margin});
  }
  return pinched;
}

}  // namespace repose
