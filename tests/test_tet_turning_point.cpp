// Where a tet moving along a step turns flat: known roots, and the first sign change of sampled cubics.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <random>

#include "tet_turning_point.h"

namespace {

using repose::tetTurningPoint;
using M3 = Eigen::Matrix3d;

TEST(TetTurningPoint, KnownCases) {
  // Shrunk uniformly: det(I - 2a I) = (1 - 2a)^3, flat at a = 1/2 (a triple root: within 1e-5 of
  // it the cubic is below its rounding).
  EXPECT_NEAR(tetTurningPoint(M3::Identity(), -2.0 * M3::Identity(), 1.0), 0.5, 1e-5);
  // One edge pushed through the opposite face: det = 1 - 4a, flat at 1/4.
  M3 E = M3::Zero();
  E(2, 2) = -4.0;
  EXPECT_NEAR(tetTurningPoint(M3::Identity(), E, 1.0), 0.25, 1e-12);
  // ... but not before the limit: the limit.
  EXPECT_EQ(tetTurningPoint(M3::Identity(), E, 0.2), 0.2);
  // Still, or turned towards a rotation (det(I + a (R - I)) > 0 all the way): the limit.
  EXPECT_EQ(tetTurningPoint(M3::Identity(), M3::Zero(), 1.1), 1.1);
  const M3 R = Eigen::AngleAxisd(2.5, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  EXPECT_EQ(tetTurningPoint(M3::Identity(), R - M3::Identity(), 1.0), 1.0);
  // Not positive to begin with: left to the caller's sign check.
  EXPECT_EQ(tetTurningPoint(-M3::Identity(), M3::Identity(), 1.0), 1.0);
}

TEST(TetTurningPoint, FirstSignChangeOfRandomSteps) {
  std::mt19937 rng(7);
  std::normal_distribution<double> g;
  int turned = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    M3 D = M3::Identity() + 0.3 * M3::NullaryExpr([&]() { return g(rng); });
    if (D.determinant() <= 0.0) continue;
    const M3 E = 1.5 * M3::NullaryExpr([&]() { return g(rng); });
    const double a = tetTurningPoint(D, E, 1.0);
    // The first sign change on a fine grid (the two agree unless a root pair falls within a sample).
    double reference = 1.0;
    for (int k = 1; k <= 100000; ++k)
      if ((D + (k * 1e-5) * E).determinant() <= 0.0) {
        reference = k * 1e-5;
        break;
      }
    if (reference < 1.0) ++turned;
    EXPECT_NEAR(a, reference, 2e-5) << "trial " << trial;
    EXPECT_GT((D + 0.9 * a * E).determinant(), 0.0);  // where the line search starts
  }
  EXPECT_GT(turned, 200);  // the steps turn many tets
}

}  // namespace
