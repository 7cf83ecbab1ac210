// The fold-free continuation: out of a fold that is a local minimum, and not where bones pinch a node.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "corotational_test_meshes.h"

namespace {

using repose::CorotationalOptions;
using repose::CorotationalReport;
using repose::Points;

// A bar bent by 86 degrees about a hinge on its inner face (bones 0: x <= 4 and 1: x >= 8, bone 1 the
// child), warm-started from a fold: the free nodes collapsed onto a curve. Newton and the untangling settle
// in a local minimum with a tet turned inside out; the continuation from the rest shape gets no fold
// on the way and ends in the minimum that a good warm start (the linear blend) reaches directly.
TEST(FixedCorotatedFem, FoldFreeContinuationLeavesNoFoldAndFindsTheMinimum) {
  const FoldedBar f = foldedBar();
  const Box& b = f.b;
  const std::vector<int>& fixed = f.fixed;
  const Points &blended = f.blended, &folded = f.folded;
  CorotationalOptions opt = fixedCorotated(CorotationalOptions::Cholmod);
  opt.stepTolerance = 1e-5;
  opt.boneParents = {-1, 0};
  auto relax = [&](const Points& start, CorotationalOptions::Continuation mode, CorotationalReport& rep) {
    CorotationalOptions o = opt;
    o.continuation = mode;
    Points x = start;
    repose::relaxCorotational(b.nodes, b.tets, fixed, x, o, &rep);
    for (Eigen::Index i = 0; i < x.rows(); ++i)
      if (fixed[std::size_t(i)] >= 0) EXPECT_EQ((x.row(i) - start.row(i)).cwiseAbs().maxCoeff(), 0.0);
    return x;
  };
  CorotationalReport good, stuck, continued, always;
  const Points reference = relax(blended, CorotationalOptions::Never, good);
  ASSERT_EQ(good.invertedAfter, 0);
  relax(folded, CorotationalOptions::Never, stuck);
  const Points x = relax(folded, CorotationalOptions::IfInverted, continued);
  std::printf("folded start: inverted %d -> %d, energy %.4f without the continuation; -> %d, energy %.4f in %d steps "
              "with it; %.4f from the blend\n", stuck.invertedBefore, stuck.invertedAfter, stuck.energyAfter,
              continued.invertedAfter, continued.energyAfter, continued.continuationSteps, good.energyAfter);
  EXPECT_GT(stuck.invertedAfter, 0);  // the case is a fold Newton cannot leave
  EXPECT_EQ(stuck.continuationSteps, 0);
  EXPECT_TRUE(continued.continuationUsed);
  EXPECT_GT(continued.continuationSteps, 0);
  EXPECT_EQ(continued.invertedAfter, 0);
  EXPECT_NEAR(continued.energyAfter, good.energyAfter, 1e-6 * good.energyAfter);
  EXPECT_LT((x - reference).cwiseAbs().maxCoeff(), 1e-3);
  // From the good warm start the continuation (forced) ends in the same minimum.
  const Points y = relax(blended, CorotationalOptions::Always, always);
  EXPECT_TRUE(always.continuationUsed);
  EXPECT_EQ(always.invertedAfter, 0);
  EXPECT_NEAR(always.energyAfter, good.energyAfter, 1e-6 * good.energyAfter);
  EXPECT_LT((y - reference).cwiseAbs().maxCoeff(), 1e-3);
  EXPECT_EQ(continued.continuationRescues, 0);
  // Bones pushed into each other (bone 1 slid over bone 0) leave no fold-free way: the direct
  // result is kept. The path stalls at 2/3, where the tissue is relaxed once; it stalls again
  // there, and a second relaxation at the same place would find the same minimum.
  Points crushed = b.nodes;
  for (Eigen::Index i = 0; i < b.nodes.rows(); ++i)
    if (fixed[std::size_t(i)] == 1) crushed.row(i) += Eigen::RowVector3d(-6, 0, 0);
  CorotationalReport blocked;
  relax(crushed, CorotationalOptions::Always, blocked);
  EXPECT_FALSE(blocked.continuationUsed);
  EXPECT_EQ(blocked.continuationRescues, 1);
}

// Bones pushed past each other across a single free layer (bone 0: x <= 4, bone 1: x >= 6, moved by
// -2.5). The layer's middle node has a tet on a face of each bone (the Kuhn cubes' corner tets), so it
// must lie beyond bone 0's face (x > 4) and before bone 1's (x < 3.5): no fold-free pose exists. The
// continuation is not started for it (the direct result stands, the node reported 0.25 short of
// room); forced, it runs and cannot end.
TEST(FixedCorotatedFem, NoContinuationWhereBonesPinchANode) {
  const Box b = makeBox(10, 2, 2, 1.0);
  std::vector<int> fixed(std::size_t(b.nodes.rows()), -1);
  Points posed = b.nodes;
  for (Eigen::Index i = 0; i < b.nodes.rows(); ++i) {
    if (b.nodes(i, 0) <= 4.0) fixed[std::size_t(i)] = 0;
    if (b.nodes(i, 0) >= 6.0) {
      fixed[std::size_t(i)] = 1;
      posed(i, 0) -= 2.5;
    }
  }
  CorotationalOptions opt = fixedCorotated(CorotationalOptions::Cholmod);
  opt.boneParents = {-1, 0};
  auto relax = [&](CorotationalOptions::Continuation mode, CorotationalReport& rep) {
    CorotationalOptions o = opt;
    o.continuation = mode;
    Points x = posed;
    repose::relaxCorotational(b.nodes, b.tets, fixed, x, o, &rep);
    return x;
  };
  CorotationalReport never, ifInverted, always;
  const Points direct = relax(CorotationalOptions::Never, never);
  const Points x = relax(CorotationalOptions::IfInverted, ifInverted);
  ASSERT_GT(never.invertedAfter, never.invertedRigid);  // folds with free nodes remain
  EXPECT_EQ(never.pinchedNodes, 1);
  EXPECT_NEAR(never.pinchedShortfall, 0.25, 1e-9);
  EXPECT_EQ(ifInverted.continuationSteps, 0);
  EXPECT_EQ(ifInverted.pinchedNodes, 1);
  EXPECT_EQ((x - direct).cwiseAbs().maxCoeff(), 0.0);
  const Points y = relax(CorotationalOptions::Always, always);
  EXPECT_GT(always.continuationSteps, 0);
  EXPECT_FALSE(always.continuationUsed);
  EXPECT_EQ((y - direct).cwiseAbs().maxCoeff(), 0.0);
}

}  // namespace
