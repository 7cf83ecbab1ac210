// Generalized winding numbers against known solutions: solid angles, closed and open surfaces,
// overlapping and nested pieces, and the hierarchical evaluation against the exact sum.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

#include "triangle_soups.h"
#include "winding_number.h"

using namespace repose;

namespace {

/// Solid angle of the rectangle [0,a] x [0,b] in the plane z = 0 seen from (0, 0, d), d > 0
/// (the classic closed form, independent of the triangle formula).
double cornerRectangleSolidAngle(double a, double b, double d) {
  return std::atan(a * b / (d * std::sqrt(d * d + a * a + b * b)));
}

/// The unit cube [0,1]^3 without its top face (z = 1): outward triangles, an open box.
TriangleMesh openBox() {
  TriangleMesh c = box({0, 0, 0}, {1, 1, 1});
  TriangleMesh m;
  m.V = c.V;
  m.F.resize(10, 3);
  int n = 0;
  for (Eigen::Index t = 0; t < 12; ++t) {
    const bool top = c.V(c.F(t, 0), 2) == 1 && c.V(c.F(t, 1), 2) == 1 && c.V(c.F(t, 2), 2) == 1;
    if (!top) m.F.row(n++) = c.F.row(t);
  }
  EXPECT_EQ(n, 10);
  return m;
}

double tree(const TriangleMesh& m, const Eigen::Vector3d& q) { return WindingNumberTree(m.V, m.F)(q); }

}  // namespace

TEST(WindingNumber, SolidAngleOfAnOctantTriangle) {
  // The triangle (1,0,0), (0,1,0), (0,0,1) covers one octant of the directions from the origin.
  const Eigen::Vector3d a(1, 0, 0), b(0, 1, 0), c(0, 0, 1), o(0, 0, 0);
  EXPECT_NEAR(triangleSolidAngle(a, b, c, o), 4 * M_PI / 8, 1e-14);
  EXPECT_NEAR(triangleSolidAngle(a, c, b, o), -4 * M_PI / 8, 1e-14);  // facing the origin: negative
  // In its plane, beside it: nothing.
  EXPECT_NEAR(triangleSolidAngle(a, b, c, Eigen::Vector3d(3, -2, 0)), 0.0, 1e-14);
  EXPECT_NEAR(triangleSolidAngle(a, b, c, Eigen::Vector3d(2, 2, -3)), 0.0, 1e-14);
  // A unit square's quarter, seen from above its corner: the closed form.
  const double exact = cornerRectangleSolidAngle(1, 1, 0.5);
  const Eigen::Vector3d q(0, 0, -0.5), p0(0, 0, 0), p1(1, 0, 0), p2(1, 1, 0), p3(0, 1, 0);
  EXPECT_NEAR(triangleSolidAngle(p0, p1, p2, q) + triangleSolidAngle(p0, p2, p3, q), exact, 1e-14);
}

TEST(WindingNumber, ClosedSurfacesAreOneInsideZeroOutside) {
  const TriangleMesh s = sphere({1, 2, 3}, 10, 24, 48);
  const WindingNumberTree t(s.V, s.F);
  for (const Eigen::Vector3d& q : {Eigen::Vector3d(1, 2, 3), Eigen::Vector3d(8, 2, 3), Eigen::Vector3d(1, -5, 9)}) {
    EXPECT_NEAR(windingNumberExact(s.V, s.F, q), 1.0, 1e-12);
    EXPECT_NEAR(t(q), 1.0, 5e-3);  // the far clusters by their expansion
  }
  for (const Eigen::Vector3d& q : {Eigen::Vector3d(12, 2, 3), Eigen::Vector3d(1, 2, -8), Eigen::Vector3d(100, 0, 0)}) {
    EXPECT_NEAR(windingNumberExact(s.V, s.F, q), 0.0, 1e-12);
    EXPECT_NEAR(t(q), 0.0, 5e-3);
  }
  const TriangleMesh c = box({0, 0, 0}, {1, 1, 1});
  EXPECT_NEAR(windingNumberExact(c.V, c.F, {0.5, 0.5, 0.5}), 1.0, 1e-14);
  EXPECT_NEAR(windingNumberExact(c.V, c.F, {0.01, 0.99, 0.5}), 1.0, 1e-12);
  EXPECT_NEAR(windingNumberExact(c.V, c.F, {1.01, 0.5, 0.5}), 0.0, 1e-12);
  // On a face, between the jump from 1 to 0: the other five faces see half the sphere of directions.
  EXPECT_NEAR(windingNumberExact(c.V, c.F, {0.5, 0.5, 1.0}), 0.5, 1e-12);
  // Facing inward, the same surface counts -1.
  EXPECT_NEAR(windingNumberExact(c.V, inverted(c).F, {0.5, 0.5, 0.5}), -1.0, 1e-14);
}

TEST(WindingNumber, CubeWithAFaceRemoved) {
  const TriangleMesh m = openBox();
  // At the centre each face subtends a sixth of the sphere: 5/6 with one missing.
  EXPECT_NEAR(windingNumberExact(m.V, m.F, {0.5, 0.5, 0.5}), 5.0 / 6.0, 1e-14);
  EXPECT_NEAR(tree(m, {0.5, 0.5, 0.5}), 5.0 / 6.0, 1e-14);
  // Elsewhere: 1 minus the missing face's solid angle, four corner rectangles of the closed form.
  const Eigen::Vector3d q(0.3, 0.6, 0.25);
  const double d = 1 - q.z(), x0 = q.x(), x1 = 1 - q.x(), y0 = q.y(), y1 = 1 - q.y();
  const double missing = cornerRectangleSolidAngle(x0, y0, d) + cornerRectangleSolidAngle(x1, y0, d) +
                         cornerRectangleSolidAngle(x0, y1, d) + cornerRectangleSolidAngle(x1, y1, d);
  EXPECT_NEAR(windingNumberExact(m.V, m.F, q), 1.0 - missing / (4 * M_PI), 1e-14);
  // Above the opening, outside: only the missing face's part is absent from the closed box's 0.
  const Eigen::Vector3d above(0.5, 0.5, 1.5);
  const double seen = 4 * cornerRectangleSolidAngle(0.5, 0.5, 0.5);
  EXPECT_NEAR(windingNumberExact(m.V, m.F, above), seen / (4 * M_PI), 1e-14);
  EXPECT_LT(windingNumberExact(m.V, m.F, above), 0.5);  // w >= 1/2 stays below the opening
}

TEST(WindingNumber, OverlappingPiecesCountTwiceNestedInwardShellIsACavity) {
  const TriangleMesh two = concat(box({0, 0, 0}, {2, 2, 2}), box({1, 1, 1}, {3, 3, 3}));
  const WindingNumberTree t(two.V, two.F);
  for (const auto& [q, w] : {std::pair<Eigen::Vector3d, double>{{1.5, 1.5, 1.5}, 2.0},  // in both
                             {{0.5, 0.5, 0.5}, 1.0},
                             {{2.5, 2.5, 2.5}, 1.0},
                             {{2.5, 0.5, 0.5}, 0.0}}) {
    EXPECT_NEAR(windingNumberExact(two.V, two.F, q), w, 1e-12);
    EXPECT_NEAR(t(q), w, 5e-3);
  }
  // An outward sphere holding an inward one: 0 in the cavity, 1 in the shell.
  const TriangleMesh shell = concat(sphere({0, 0, 0}, 10, 24, 48), inverted(sphere({0, 0, 0}, 6, 16, 32)));
  const WindingNumberTree s(shell.V, shell.F);
  for (const auto& [q, w] : {std::pair<Eigen::Vector3d, double>{{0, 0, 0}, 0.0}, {{0, 0, 8}, 1.0}, {{0, 11, 0}, 0.0}}) {
    EXPECT_NEAR(windingNumberExact(shell.V, shell.F, q), w, 1e-12);
    // The tree's worst case: at the centre every cluster of the inner sphere lies at the same
    // distance and their expansions err the same way (0.018 there).
    EXPECT_NEAR(s(q), w, 2e-2);
  }
}

TEST(WindingNumber, TreeMatchesTheExactSumOnARealFemur) {
  // The Visible Human female's left femur as the atlas ships it: 3 holes at the knee, 91 mm wide.
  const TriangleMesh m = readBinaryPly(std::string(REPOSE_SHARED_DATA) + "/visible_human/female/femur_left.ply");
  const WindingNumberTree t(m.V, m.F);
  EXPECT_GT(t.nodeCount(), 1000u);
  // Points in and around it, and near its surface: vertices moved 0.5 mm in random directions.
  const Eigen::Vector3d lo = m.V.colwise().minCoeff().transpose(), hi = m.V.colwise().maxCoeff().transpose();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.2, 1.2), v(-1, 1);
  std::vector<Eigen::Vector3d> points;
  for (int n = 0; n < 400; ++n) points.push_back(lo + (hi - lo).cwiseProduct(Eigen::Vector3d(u(rng), u(rng), u(rng))));
  for (Eigen::Index n = 0; n < m.V.rows(); n += 37)
    points.push_back(m.V.row(n).transpose() + 0.5 * Eigen::Vector3d(v(rng), v(rng), v(rng)).normalized());
  std::vector<double> exact;
  int inside = 0;
  for (const auto& q : points) exact.push_back(windingNumberExact(m.V, m.F, q)), inside += exact.back() >= 0.5;
  auto worstError = [&](const WindingNumberTree& tree) {
    double worst = 0;
    for (std::size_t n = 0; n < points.size(); ++n) worst = std::max(worst, std::abs(tree(points[n]) - exact[n]));
    return worst;
  };
  const double worst = worstError(t);
  EXPECT_GT(inside, 20);
  EXPECT_LT(worst, 1e-2);  // measured: 0.008
  // A larger beta trades speed for accuracy.
  WindingNumberOptions precise;
  precise.beta = 4;
  EXPECT_LT(worstError(WindingNumberTree(m.V, m.F, precise)), worst / 4);
  // Far away only the root's expansion is summed.
  for (const double far : {1e3, 1e4}) {
    const Eigen::Vector3d q = 0.5 * (lo + hi) + far * Eigen::Vector3d(0.6, 0, 0.8);
    EXPECT_LT(std::abs(t(q) - windingNumberExact(m.V, m.F, q)), 1e-5);
  }
  // In the shaft the holes at the knee, 180 mm away, barely show; between the condyles, right above
  // the widest hole, w falls towards 1/2.
  const double shaft = windingNumberExact(m.V, m.F, {122, 56, -200}), knee = windingNumberExact(m.V, m.F, {119, 71, -345});
  EXPECT_GT(shaft, 0.97);
  EXPECT_LT(shaft, 1.0);
  EXPECT_LT(knee, shaft);
}

TEST(WindingNumber, BadInput) {
  const TriangleMesh c = box({0, 0, 0}, {1, 1, 1});
  EXPECT_THROW(WindingNumberTree(MeshVertices(), MeshTriangles()), std::invalid_argument);
  MeshTriangles bad = c.F;
  bad(2, 1) = 8;
  EXPECT_THROW(WindingNumberTree(c.V, bad), std::invalid_argument);
  EXPECT_THROW(windingNumberExact(c.V, bad, {0, 0, 0}), std::invalid_argument);
  MeshVertices nan = c.V;
  nan(1, 1) = NAN;
  EXPECT_THROW(WindingNumberTree(nan, c.F), std::invalid_argument);
  WindingNumberOptions o;
  o.beta = 0.5;
  EXPECT_THROW(WindingNumberTree(c.V, c.F, o), std::invalid_argument);
}
