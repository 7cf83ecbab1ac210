// PointGrid: nearest points and closest pairs against brute force.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "point_grid.h"

using namespace repose;
using V3 = Eigen::Vector3d;

namespace {

// Points on a sphere's surface voxels (a bone-like shell) around `c`.
std::vector<V3> shell(const V3& c, double r, double h) {
  std::vector<V3> pts;
  const int n = int(std::ceil(r / h)) + 1;
  for (int i = -n; i <= n; ++i)
    for (int j = -n; j <= n; ++j)
      for (int k = -n; k <= n; ++k) {
        const V3 p = c + h * V3(i, j, k);
        if (std::abs((p - c).norm() - r) <= 0.5 * h) pts.push_back(p);
      }
  return pts;
}

}  // namespace

TEST(PointGrid, NearestMatchesBruteForceNearAndFar) {
  const std::vector<V3> pts = shell(V3(10, -20, 30), 25, 2);
  const PointGrid grid(pts, 4);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-200, 200);
  for (int q = 0; q < 400; ++q) {
    const V3 x(u(rng), u(rng), u(rng));
    double truth = std::numeric_limits<double>::infinity();
    std::size_t at = 0;
    for (std::size_t n = 0; n < pts.size(); ++n)
      if ((pts[n] - x).norm() < truth) {
        truth = (pts[n] - x).norm();
        at = n;
      }
    const PointGrid::Hit unlimited = grid.nearest(x, 1e9);
    EXPECT_NEAR(unlimited.distance, truth, 1e-12);
    EXPECT_NEAR((pts[unlimited.index] - x).norm(), (pts[at] - x).norm(), 1e-12);
    for (double limit : {5.0, 30.0, 120.0}) {
      const PointGrid::Hit h = grid.nearest(x, limit);
      if (truth <= limit) EXPECT_NEAR(h.distance, truth, 1e-12) << limit;
      else EXPECT_TRUE(std::isinf(h.distance)) << limit;
    }
    EXPECT_LE(grid.boxDistance(x), truth + 1e-12);
  }
}

TEST(PointGrid, ClosestPairOfTwoShells) {
  const std::vector<V3> a = shell(V3(0, 0, 0), 20, 2), b = shell(V3(47, 3, -2), 15, 2);
  const PointGrid ga(a, 6), gb(b, 6);
  double truth = std::numeric_limits<double>::infinity();
  for (const V3& p : a)
    for (const V3& q : b) truth = std::min(truth, (p - q).norm());
  const PointGrid::Pair p = gb.closestPair(a, 100);
  EXPECT_NEAR(p.distance, truth, 1e-12);
  EXPECT_NEAR((a[p.query] - b[p.index]).norm(), truth, 1e-12);
  EXPECT_TRUE(std::isinf(gb.closestPair(a, truth - 0.1).distance));
  // A sample of the queries gives an upper bound within a few spacings.
  const double sampled = gb.closestPair(a, 100, 64).distance;
  EXPECT_GE(sampled, truth - 1e-12);
  EXPECT_LE(sampled, truth + 10);
  EXPECT_LE(gb.boxDistance(ga), truth);
  EXPECT_THROW(PointGrid(a, 0), std::invalid_argument);
  EXPECT_TRUE(std::isinf(PointGrid({}, 1).nearest(V3::Zero(), 10).distance));
}
