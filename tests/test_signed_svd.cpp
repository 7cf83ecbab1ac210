// The SVD with det U = det V = +1 (Irving et al. 2004).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <random>
#include <vector>

#include "signed_svd.h"

namespace {

Eigen::Matrix3d someRotation() {
  return Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
}

TEST(SignedSvd, ReconstructsRotationsStretchesInversionsAndDegenerateMatrices) {
  std::mt19937 rng(3);
  std::normal_distribution<double> n01;
  std::vector<Eigen::Matrix3d> cases;
  for (int i = 0; i < 400; ++i) {  // general matrices, half of them inverted
    Eigen::Matrix3d F;
    for (int k = 0; k < 9; ++k) F(k / 3, k % 3) = n01(rng);
    cases.push_back(F);
  }
  for (int i = 0; i < 200; ++i) {  // near-rotations (most tets of a pose), clustered singular values
    const Eigen::Matrix3d R =
        Eigen::AngleAxisd(3.0 * n01(rng), Eigen::Vector3d(n01(rng), n01(rng), n01(rng)).normalized()).toRotationMatrix();
    Eigen::Matrix3d E;
    for (int k = 0; k < 9; ++k) E(k / 3, k % 3) = 1e-6 * n01(rng);
    cases.push_back(R * (Eigen::Matrix3d::Identity() + E));
  }
  cases.push_back(Eigen::Matrix3d::Identity());
  cases.push_back(Eigen::Vector3d(1, 1, -1).asDiagonal());             // a reflection: inverted
  cases.push_back(Eigen::Vector3d(2, 0.5, 0).asDiagonal());            // flat
  cases.push_back(Eigen::Vector3d(0, 3, 0).asDiagonal());              // a line
  cases.push_back(Eigen::Matrix3d::Zero());
  cases.push_back(someRotation() * Eigen::Vector3d(1.2, 1.2, 0.7).asDiagonal() * someRotation().transpose());
  for (const Eigen::Matrix3d& F : cases) {
    Eigen::Matrix3d U, V;
    Eigen::Vector3d s;
    repose::signedSvd(F, U, s, V);
    const double scale = std::max(1.0, F.norm());
    EXPECT_LT((U * s.asDiagonal() * V.transpose() - F).norm(), 1e-9 * scale) << F;
    EXPECT_LT((U.transpose() * U - Eigen::Matrix3d::Identity()).norm(), 1e-9);
    EXPECT_LT((V.transpose() * V - Eigen::Matrix3d::Identity()).norm(), 1e-9);
    EXPECT_NEAR(U.determinant(), 1.0, 1e-9);
    EXPECT_NEAR(V.determinant(), 1.0, 1e-9);
    EXPECT_GE(s(0), std::abs(s(1)) - 1e-12 * scale);
    EXPECT_GE(s(1), std::abs(s(2)) - 1e-9 * scale);
    EXPECT_GE(s(1), 0.0);
    // The magnitudes are the singular values, and the sign of the last is that of det F.
    const Eigen::Vector3d ref = Eigen::JacobiSVD<Eigen::Matrix3d>(F).singularValues();
    EXPECT_LT((s.cwiseAbs() - ref).norm(), 1e-9 * scale);
    if (std::abs(F.determinant()) > 1e-9) EXPECT_EQ(s(2) < 0, F.determinant() < 0);
  }
}

}  // namespace
