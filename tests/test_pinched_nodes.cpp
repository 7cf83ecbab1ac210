// Nodes pinched between bones: the half-space margin against known geometry, and the pinch test on
// bone faces pushed into each other.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "pinched_nodes.h"
#include "tet_mesh.h"

namespace {

using repose::largestHalfSpaceMargin;
using V3 = Eigen::Vector3d;

TEST(HalfSpaceMargin, KnownRegions) {
  // The slab |z| <= 1 (no normal spans x or y): its mid-plane clears both faces by 1.
  EXPECT_NEAR(largestHalfSpaceMargin({V3(0, 0, 1), V3(0, 0, -1)}, {-1.0, -1.0}, 5.0), 1.0, 1e-12);
  // Crossed over, z >= 1 and z <= -1: empty, and the best point (z = 0) is 1 short of both.
  EXPECT_NEAR(largestHalfSpaceMargin({V3(0, 0, 1), V3(0, 0, -1)}, {1.0, 1.0}, 5.0), -1.0, 1e-12);
  // The cube |x|, |y|, |z| <= 2: margin 2, or the cap when it is lower.
  std::vector<V3> cube;
  for (int a = 0; a < 3; ++a) {
    cube.push_back(V3::Unit(a));
    cube.push_back(-V3::Unit(a));
  }
  EXPECT_NEAR(largestHalfSpaceMargin(cube, std::vector<double>(6, -2.0), 10.0), 2.0, 1e-12);
  EXPECT_NEAR(largestHalfSpaceMargin(cube, std::vector<double>(6, -2.0), 0.5), 0.5, 1e-12);
  // The corner tet x, y, z >= 0, x + y + z <= 1: its inscribed sphere's radius 1 / (3 + sqrt 3).
  const std::vector<V3> corner = {V3::UnitX(), V3::UnitY(), V3::UnitZ(), -V3(1, 1, 1).normalized()};
  EXPECT_NEAR(largestHalfSpaceMargin(corner, {0.0, 0.0, 0.0, -1.0 / std::sqrt(3.0)}, 10.0), 1.0 / (3.0 + std::sqrt(3.0)),
              1e-12);
  // Two planes that cross far away (a wedge beyond x = 1000) still leave room: no bound on the room.
  const double slope = 1e-3;
  const std::vector<V3> wedge = {V3(slope, 0, 1).normalized(), V3(slope, 0, -1).normalized()};
  EXPECT_GT(largestHalfSpaceMargin(wedge, {1.0 / V3(slope, 0, 1).norm(), 1.0 / V3(slope, 0, 1).norm()}, 1.0), 0.0);
  // More planes than it examines: taken as room.
  EXPECT_EQ(largestHalfSpaceMargin(std::vector<V3>(5, V3::UnitZ()), std::vector<double>(5, 0.0), 1.0, 4),
            std::numeric_limits<double>::infinity());
}

// One free node (0) between two bone triangles, 1-3 below it (bone 0) and 4-6 above (bone 1), each
// making a positive tet with it at rest. Posed with the bones moved by `lower` and `upper` along z.
struct Sandwich {
  repose::Points rest = repose::Points(7, 3), posed = repose::Points(7, 3);
  repose::Tets tets = repose::Tets(2, 4);
  std::vector<int> fixed = {-1, 0, 0, 0, 1, 1, 1};
  Sandwich(double lower, double upper) {
    rest.row(0) << 0, 0, 0;
    const double corners[3][2] = {{-1, -1}, {1, -1}, {0, 1}};
    for (int c = 0; c < 3; ++c) {
      rest.row(1 + c) << corners[c][0], corners[c][1], -1;
      rest.row(4 + c) << corners[c][0], corners[c][1], 1;
    }
    tets << 0, 1, 2, 3, 0, 4, 5, 6;
    for (Eigen::Index t = 0; t < 2; ++t)  // both positive at rest
      if (repose::tetVolume(rest.row(tets(t, 0)), rest.row(tets(t, 1)), rest.row(tets(t, 2)), rest.row(tets(t, 3))) < 0)
        std::swap(tets(t, 2), tets(t, 3));
    posed = rest;
    for (int i = 1; i < 7; ++i) posed(i, 2) += i < 4 ? lower : upper;
  }
};

TEST(PinchedNodes, ANodeBetweenBoneFacesPushedPastEachOther) {
  // The faces moved 1.5 towards each other and past: the node must be above z = 0.5 and below
  // z = -0.5, 0.5 short at best (z = 0), wherever it is now.
  Sandwich s(1.5, -1.5);
  s.posed.row(0) << 0.3, -0.2, 0.7;
  const std::vector<repose::PinchedNode> pinched = repose::findPinchedNodes(s.posed, s.tets, s.fixed);
  ASSERT_EQ(pinched.size(), 1u);
  EXPECT_EQ(pinched[0].node, 0);
  EXPECT_NEAR(pinched[0].shortfall, 0.5, 1e-12);
}

double smallestVolume(const Sandwich& s) {
  double v = std::numeric_limits<double>::infinity();
  for (Eigen::Index t = 0; t < s.tets.rows(); ++t)
    v = std::min(v, repose::tetVolume(s.posed.row(s.tets(t, 0)), s.posed.row(s.tets(t, 1)), s.posed.row(s.tets(t, 2)),
                                      s.posed.row(s.tets(t, 3))));
  return v;
}

TEST(PinchedNodes, RoomLeftIsNoPinch) {
  // Squeezed to a gap of 0.2 with the node outside it: a tet is inverted, but the node has room.
  Sandwich squeezed(0.9, -0.9);
  squeezed.posed.row(0) << 0, 0, 0.5;
  ASSERT_LE(smallestVolume(squeezed), 0.0);
  EXPECT_TRUE(repose::findPinchedNodes(squeezed.posed, squeezed.tets, squeezed.fixed).empty());
  // Faces meeting exactly (a gap of 0) are taken as room: no rounding may call a reachable pose
  // unreachable.
  Sandwich touching(1.0, -1.0);
  ASSERT_LE(smallestVolume(touching), 0.0);
  EXPECT_TRUE(repose::findPinchedNodes(touching.posed, touching.tets, touching.fixed).empty());
  // A tet with a second free node does not count (its room depends on that node too): here only the
  // lower face is the node's, and it leaves room.
  Sandwich crossed(1.5, -1.5);
  crossed.fixed[4] = -1;
  ASSERT_LE(smallestVolume(crossed), 0.0);
  EXPECT_TRUE(repose::findPinchedNodes(crossed.posed, crossed.tets, crossed.fixed).empty());
}

}  // namespace
