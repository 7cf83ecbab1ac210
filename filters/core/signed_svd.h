#pragma once
// Signed singular value decomposition of a 3x3 deformation gradient, F = U diag(sigma) V^T with
// det U = det V = +1 (Irving et al. 2004): an inverted F gets a negative smallest sigma instead of a
// reflection in U or V, so rotations taken from it never flip a tet.
#include <Eigen/Dense>
#include <cmath>

namespace repose {

/// F   3x3 (any: inverted, degenerate or zero)
/// U,V out: rotations (orthonormal, determinant +1)
/// sigma out: |sigma(0)| >= |sigma(1)| >= |sigma(2)|, sigma(0), sigma(1) >= 0, sign(sigma(2)) = sign(det F)
/// V comes from the eigenvectors of F^T F (Eigen's closed-form 3x3 solver), U from Gram-Schmidt on
/// the columns of F V: about ten times faster than JacobiSVD, which the elastic energy calls for
/// every tet at every line-search trial.
inline void signedSvd(const Eigen::Matrix3d& F, Eigen::Matrix3d& U, Eigen::Vector3d& sigma, Eigen::Matrix3d& V) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
  eig.computeDirect(F.transpose() * F);
  // Ascending eigenvalues: reverse so the largest stretch comes first.
  V.col(0) = eig.eigenvectors().col(2);
  V.col(1) = eig.eigenvectors().col(1);
  V.col(2) = V.col(0).cross(V.col(1));  // det V = +1 by construction
  const Eigen::Matrix3d B = F * V;
  const double scale = F.cwiseAbs().maxCoeff();
  const double tiny = 1e-30 + 1e-13 * scale;
  Eigen::Vector3d u0 = B.col(0);
  const double s0 = u0.norm();
  if (s0 > tiny) {
    u0 /= s0;
  } else {  // F = 0: any rotation will do
    U.setIdentity();
    sigma.setZero();
    V.setIdentity();
    return;
  }
  Eigen::Vector3d u1 = B.col(1) - u0.dot(B.col(1)) * u0;
  double s1 = u1.norm();
  if (s1 > tiny) {
    u1 /= s1;
  } else {  // rank 1: any unit vector orthogonal to u0
    u1 = std::abs(u0.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
    u1 = (u1 - u0.dot(u1) * u0).normalized();
    s1 = u1.dot(B.col(1));
    if (s1 < 0) {
      u1 = -u1;
      s1 = -s1;
    }
  }
  const Eigen::Vector3d u2 = u0.cross(u1);
  U.col(0) = u0;
  U.col(1) = u1;
  U.col(2) = u2;
  sigma = Eigen::Vector3d(s0, s1, u2.dot(B.col(2)));
}

}  // namespace repose
