#include "tet_laplacian.h"

#include <Eigen/Dense>

#include <atomic>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "parallel_for.h"

namespace repose {

Eigen::SparseMatrix<double> tetStiffnessMatrix(const Points& nodes, const Tets& tets) {
  const Eigen::Index nv = nodes.rows(), nt = tets.rows();
  for (Eigen::Index t = 0; t < nt; ++t)
    for (int c = 0; c < 4; ++c)
      if (tets(t, c) < 0 || tets(t, c) >= nv)
        throw std::invalid_argument("tetStiffnessMatrix: tet " + std::to_string(t) +
                                    " references node " + std::to_string(tets(t, c)) +
                                    " outside [0, " + std::to_string(nv) + ")");

  // Element matrices K_e = V G G^T (G: 4x3 gradients of the barycentric shape functions), computed
  // in parallel straight into the triplet list (16 entries per tet).
  using Triplet = Eigen::Triplet<double>;
  std::vector<Triplet> triplets(std::size_t(nt) * 16);
  std::atomic<long long> degenerate{-1};
  parallelFor(std::size_t(nt), [&](std::size_t begin, std::size_t end) {
    for (std::size_t t = begin; t < end; ++t) {
      const int idx[4] = {tets(t, 0), tets(t, 1), tets(t, 2), tets(t, 3)};
      const Eigen::Vector3d x0 = nodes.row(idx[0]);
      Eigen::Matrix3d D;
      D.col(0) = nodes.row(idx[1]).transpose() - x0;
      D.col(1) = nodes.row(idx[2]).transpose() - x0;
      D.col(2) = nodes.row(idx[3]).transpose() - x0;
      const double det = D.determinant();
      const double scale = std::max({D.col(0).squaredNorm(), D.col(1).squaredNorm(),
                                     D.col(2).squaredNorm()});
      // Relative test: a sliver with volume far below its edge length cubed is degenerate.
      if (!std::isfinite(det) || std::abs(det) <= 1e-12 * scale * std::sqrt(scale)) {
        degenerate.store(static_cast<long long>(t));
        for (int k = 0; k < 16; ++k) triplets[t * 16 + k] = Triplet(idx[k / 4], idx[k % 4], 0.0);
        continue;
      }
      const Eigen::Matrix3d Dinv = D.inverse();  // rows: gradients of λ1..λ3
      Eigen::Matrix<double, 4, 3> G;
      G.bottomRows<3>() = Dinv;
      G.row(0) = -Dinv.colwise().sum();
      const double volume = std::abs(det) / 6.0;
      const Eigen::Matrix4d Ke = volume * G * G.transpose();
      for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b) triplets[t * 16 + a * 4 + b] = Triplet(idx[a], idx[b], Ke(a, b));
    }
  }, 4096);
  if (degenerate.load() >= 0)
    throw std::invalid_argument("tetStiffnessMatrix: tet " + std::to_string(degenerate.load()) +
                                " is degenerate (zero volume); remesh or remove it");

  Eigen::SparseMatrix<double> K(nv, nv);
  K.setFromTriplets(triplets.begin(), triplets.end());
  return K;
}

}  // namespace repose
