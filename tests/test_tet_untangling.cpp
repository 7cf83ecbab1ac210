// Untangling inverted tets by moving their free nodes.
#include <gtest/gtest.h>

#include <cmath>

#include "corotational_test_meshes.h"
#include "tet_untangling.h"

namespace {

using repose::Points;
using repose::Tets;

TEST(TetUntangling, FreeNodesLeaveTheFoldAndFixedNodesStay) {
  // A 4x4x4 box with its boundary fixed; two interior nodes pushed through their neighbours.
  const Box b = makeBox(4, 4, 4, 1.0);
  const std::vector<int> fixed = boundaryFixed(b);
  Points posed = b.nodes;
  posed.row(b.id(1, 1, 1)) += Eigen::RowVector3d(1.7, 1.4, 1.6);
  posed.row(b.id(3, 2, 2)) += Eigen::RowVector3d(-1.5, 0.3, -1.2);
  const Points before = posed;
  const repose::UntangleReport rep = repose::untangleTets(b.nodes, b.tets, fixed, posed);
  EXPECT_GT(rep.invertedBefore, 4);
  EXPECT_EQ(rep.invertedAfter, 0);
  EXPECT_EQ(rep.invertedRigid, 0);
  EXPECT_GT(rep.nodesMoved, 0);
  for (Eigen::Index t = 0; t < b.tets.rows(); ++t) {
    const double v = repose::tetVolume(posed.row(b.tets(t, 0)), posed.row(b.tets(t, 1)), posed.row(b.tets(t, 2)),
                                       posed.row(b.tets(t, 3)));
    EXPECT_GT(v, 0.0) << "tet " << t;
  }
  for (Eigen::Index i = 0; i < posed.rows(); ++i)
    if (fixed[std::size_t(i)] >= 0) EXPECT_EQ((posed.row(i) - before.row(i)).cwiseAbs().maxCoeff(), 0.0);
  // Nothing inverted: nothing moves.
  Points rest = b.nodes;
  const repose::UntangleReport none = repose::untangleTets(b.nodes, b.tets, fixed, rest);
  EXPECT_EQ(none.invertedBefore, 0);
  EXPECT_EQ(none.nodesMoved, 0);
  EXPECT_EQ((rest - b.nodes).cwiseAbs().maxCoeff(), 0.0);
}

TEST(TetUntangling, NoTetThatWasPositiveEndsInverted) {
  // Boxes with their boundary fixed and interior nodes thrown about: the inverted tets after
  // untangling must be a subset of those before. (Moves that freed two tets by turning a third
  // passed the count rule and left tets inverted that the input had positive.)
  const Box b = makeBox(6, 6, 6, 1.0);
  const std::vector<int> fixed = boundaryFixed(b);
  auto volumes = [&](const Points& P) {
    std::vector<double> v(std::size_t(b.tets.rows()));
    for (Eigen::Index t = 0; t < b.tets.rows(); ++t)
      v[std::size_t(t)] = repose::tetVolume(P.row(b.tets(t, 0)), P.row(b.tets(t, 1)), P.row(b.tets(t, 2)),
                                            P.row(b.tets(t, 3)));
    return v;
  };
  int repaired = 0;
  for (unsigned seed = 0; seed < 40; ++seed) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> g(0.0, 0.45);
    Points posed = b.nodes;
    for (Eigen::Index i = 0; i < posed.rows(); ++i)
      if (fixed[std::size_t(i)] < 0) posed.row(i) += Eigen::RowVector3d(g(rng), g(rng), g(rng));
    const std::vector<double> before = volumes(posed);
    const repose::UntangleReport rep = repose::untangleTets(b.nodes, b.tets, fixed, posed);
    const std::vector<double> after = volumes(posed);
    for (std::size_t t = 0; t < after.size(); ++t)
      EXPECT_FALSE(before[t] > 0.0 && after[t] <= 0.0) << "seed " << seed << ": tet " << t << " turned";
    EXPECT_LE(rep.invertedAfter, rep.invertedBefore);
    repaired += rep.invertedBefore - rep.invertedAfter;
  }
  EXPECT_GT(repaired, 100);  // the rule still lets untangling do its work
}

TEST(TetUntangling, TetsWithOnlyFixedNodesAreReportedNotMoved) {
  const Box b = makeBox(2, 1, 1, 1.0);
  std::vector<int> fixed(std::size_t(b.nodes.rows()), 0);
  Points posed = b.nodes;
  posed.row(b.id(1, 0, 0)) += Eigen::RowVector3d(0, 3, 3);  // folds tets that have only fixed nodes
  const Points before = posed;
  const repose::UntangleReport rep = repose::untangleTets(b.nodes, b.tets, fixed, posed);
  EXPECT_GT(rep.invertedBefore, 0);
  EXPECT_EQ(rep.invertedAfter, rep.invertedBefore);
  EXPECT_EQ(rep.invertedRigid, rep.invertedAfter);
  EXPECT_EQ((posed - before).cwiseAbs().maxCoeff(), 0.0);
}

TEST(TetUntangling, ANodeStaysWithinItsStarWhereItsTetsContradictEachOther) {
  // One free node between two fixed triangles, its tets positive at rest (the node between the two
  // planes). Posed, the planes cross over: tet A wants the node above z = 1 - x / 1000, tet B below
  // z = -1 + x / 1000, so both are positive only beyond x = 1000, and the least-squares compromise of
  // the two half-spaces lies about 670 away. The node must not be sent there (every tet around it
  // turned inside out and grown a thousandfold): it stays within its star.
  const double slope = 1e-3;
  Points rest(7, 3), posed(7, 3);
  rest.row(0) << 0, 0, 0;
  const double corners[3][2] = {{-1, -1}, {1, -1}, {0, 1}};
  for (int c = 0; c < 3; ++c) {
    const double x = corners[c][0], y = corners[c][1];
    rest.row(1 + c) << x, y, -1;  // below the node
    rest.row(4 + c) << x, y, 1;   // above it
    posed.row(1 + c) << x, y, 1 - slope * x;
    posed.row(4 + c) << x, y, -1 + slope * x;
  }
  posed.row(0) = rest.row(0);
  Tets tets(2, 4);
  tets << 0, 1, 2, 3, 0, 4, 5, 6;
  for (Eigen::Index t = 0; t < 2; ++t)  // orient both positive at rest
    if (repose::tetVolume(rest.row(tets(t, 0)), rest.row(tets(t, 1)), rest.row(tets(t, 2)), rest.row(tets(t, 3))) < 0)
      std::swap(tets(t, 2), tets(t, 3));
  const std::vector<int> fixed = {-1, 0, 0, 0, 1, 1, 1};
  const repose::UntangleReport rep = repose::untangleTets(rest, tets, fixed, posed);
  EXPECT_EQ(rep.invertedBefore, 2);
  double reach = 0.0;
  for (Eigen::Index i = 1; i < 7; ++i) reach = std::max(reach, posed.row(i).norm());
  EXPECT_LE(posed.row(0).norm(), reach) << "the node went to " << posed.row(0);
  EXPECT_LE(rep.maxMove, reach);
  for (Eigen::Index i = 1; i < 7; ++i) EXPECT_EQ(posed(i, 2), i < 4 ? 1 - slope * posed(i, 0) : -1 + slope * posed(i, 0));
}

}  // namespace
