// Relaxing part of the mesh on its own: neighbourhoods of untangled nodes and the strained region.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "corotational_test_meshes.h"

namespace {

using repose::CorotationalOptions;
using repose::CorotationalReport;
using repose::Points;
using repose::Tets;

// relaxNeighbourhood is the whole mesh's minimum over the neighbourhood's nodes: the same as a
// whole-mesh solve with every other free node held, nodes outside it untouched; with rings enough
// to reach every free node, the whole-mesh solve itself.
TEST(FixedCorotatedFem, NeighbourhoodSolveIsTheWholeSolveWithTheRestHeld) {
  const StampedBlock s = stampedBlock(8, 4, 6, 3, 5, 0.8);
  const Box& b = s.b;
  CorotationalOptions opt = fixedCorotated(CorotationalOptions::Cholmod);
  opt.untangle = false;  // as in the neighbourhood's own solve
  opt.continuation = CorotationalOptions::Never;
  const int centre = b.id(4, 2, 4);
  std::vector<char> unknown(std::size_t(b.nodes.rows()), 0);  // one ring: the centre and its free neighbours
  for (Eigen::Index t = 0; t < b.tets.rows(); ++t)
    if ((b.tets.row(t).array() == centre).any())
      for (int c = 0; c < 4; ++c) unknown[std::size_t(b.tets(t, c))] = s.fixed[std::size_t(b.tets(t, c))] < 0;
  std::vector<int> held = s.fixed;
  for (std::size_t v = 0; v < held.size(); ++v)
    if (!unknown[v] && held[v] < 0) held[v] = 0;
  Points expected = s.stamped;
  repose::relaxCorotational(b.nodes, b.tets, held, expected, opt);

  Points x = s.stamped;
  CorotationalReport rep;
  repose::relaxNeighbourhood(b.nodes, b.tets, s.fixed, x, {centre}, 1, opt, &rep);
  EXPECT_GT(rep.newtonIterations, 0);
  EXPECT_GT((x - s.stamped).cwiseAbs().maxCoeff(), 1e-3);  // the stamp's push reaches the centre
  EXPECT_LT((x - expected).cwiseAbs().maxCoeff(), 1e-6);
  for (Eigen::Index v = 0; v < x.rows(); ++v)
    if (!unknown[std::size_t(v)]) EXPECT_EQ(x.row(v), s.stamped.row(v)) << "node " << v;

  Points whole = s.stamped, y = s.stamped;
  repose::relaxCorotational(b.nodes, b.tets, s.fixed, whole, opt);
  repose::relaxNeighbourhood(b.nodes, b.tets, s.fixed, y, {centre}, 20, opt);
  EXPECT_LT((y - whole).cwiseAbs().maxCoeff(), 1e-6);

  // Fixed centre nodes only: nothing to solve. A node out of range: refused, posed untouched.
  Points z = s.stamped;
  repose::relaxNeighbourhood(b.nodes, b.tets, s.fixed, z, {b.id(4, 2, 0)}, 3, opt, &rep);
  EXPECT_EQ(rep.newtonIterations, 0);
  EXPECT_EQ(z, s.stamped);
  EXPECT_THROW(repose::relaxNeighbourhood(b.nodes, b.tets, s.fixed, z, {int(b.nodes.rows())}, 1, opt),
               std::invalid_argument);
  Tets badTets = b.tets;
  badTets(3, 2) = int(b.nodes.rows());
  EXPECT_THROW(repose::relaxNeighbourhood(b.nodes, badTets, s.fixed, z, {centre}, 1, opt), std::invalid_argument);
  EXPECT_EQ(z, s.stamped);
}

// The folded bar's direct solve (the continuation off) leaves tets that the untangling frees, over
// several rounds. Relaxing only each round's moved nodes and their neighbours, then the whole mesh
// once, ends where a whole-mesh solve after every round does, in fewer whole-mesh Newton steps.
TEST(FixedCorotatedFem, UntanglingRoundsRelaxTheNeighbourhoodThenTheWholeMesh) {
  const FoldedBar f = foldedBar();
  CorotationalOptions opt = fixedCorotated(CorotationalOptions::Cholmod);
  opt.stepTolerance = 1e-5;
  opt.continuation = CorotationalOptions::Never;
  CorotationalReport local, whole;
  Points x = f.folded, y = f.folded;
  opt.untangleRelaxRings = 2;
  repose::relaxCorotational(f.b.nodes, f.b.tets, f.fixed, x, opt, &local);
  opt.untangleRelaxRings = -1;
  repose::relaxCorotational(f.b.nodes, f.b.tets, f.fixed, y, opt, &whole);
  std::printf("untangling rounds: %d + %d neighbourhood Newton steps against %d whole-mesh ones; energy %.6f, %.6f\n",
              local.newtonIterations, local.untangleNewtonIterations, whole.newtonIterations, local.energyAfter,
              whole.energyAfter);
  EXPECT_GT(local.untangledNodes, 0);
  EXPECT_GT(local.untangleNewtonIterations, 0);
  EXPECT_EQ(whole.untangleNewtonIterations, 0);
  EXPECT_LT(local.newtonIterations, whole.newtonIterations);
  EXPECT_EQ(local.invertedAfter, whole.invertedAfter);
  EXPECT_LE(local.invertedAfter, local.invertedBefore);
  EXPECT_NEAR(local.energyAfter, whole.energyAfter, 1e-6 * whole.energyAfter);
  EXPECT_LT((x - y).cwiseAbs().maxCoeff(), 1e-3);
  for (Eigen::Index i = 0; i < x.rows(); ++i)
    if (f.fixed[std::size_t(i)] >= 0) EXPECT_EQ(x.row(i), f.folded.row(i));
}

// A bar bent at a joint as skinning bends a limb: bones hold its end slabs, the tissue left of
// x = 10 stays, right of x = 14 turns rigidly about the joint, and only between is it strained.
struct SkinnedJoint {
  Box b = makeBox(24, 4, 4, 1.0);
  std::vector<int> fixed;
  Points skinned;
};
SkinnedJoint skinnedJoint(double angle) {
  SkinnedJoint j;
  const Box& b = j.b;
  j.fixed.assign(std::size_t(b.nodes.rows()), -1);
  j.skinned = b.nodes;
  const Eigen::Vector3d joint(12, 2, 2);
  const Eigen::Matrix3d R = Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitY()).toRotationMatrix();
  for (Eigen::Index i = 0; i < b.nodes.rows(); ++i) {
    const double x = b.nodes(i, 0), w = std::clamp((x - 10.0) / 4.0, 0.0, 1.0);
    const Eigen::Vector3d p = b.nodes.row(i).transpose();
    j.skinned.row(i) = ((1 - w) * p + w * (R * (p - joint) + joint)).transpose();
    if (x <= 2.0) j.fixed[std::size_t(i)] = 0;
    if (x >= 22.0) j.fixed[std::size_t(i)] = 1;
  }
  return j;
}

// From a cold start the strained region goes first, on its own: the joint's tissue and three rings,
// not the rigidly moved rest. The whole mesh then needs fewer Newton steps to the same minimum. A warm
// start, a threshold no tet reaches and a threshold of 0 go straight to the whole mesh.
TEST(FixedCorotatedFem, StrainedRegionFirstReachesTheSameMinimumInFewerWholeMeshSteps) {
  const SkinnedJoint j = skinnedJoint(0.9);
  const std::size_t nFree = std::size_t(std::count(j.fixed.begin(), j.fixed.end(), -1));
  CorotationalOptions opt = fixedCorotated(CorotationalOptions::Cholmod);
  opt.continuation = CorotationalOptions::Never;
  // At the tolerances of a pose (the filter's): fewer whole-mesh steps, to no higher an energy.
  opt.stepTolerance = 1e-2;
  opt.energyTolerance = 1e-3;
  Points first = j.skinned, whole = j.skinned;
  CorotationalReport firstReport, wholeReport;
  repose::relaxCorotational(j.b.nodes, j.b.tets, j.fixed, first, opt, &firstReport);
  opt.strainedRegionThreshold = 0.0;
  repose::relaxCorotational(j.b.nodes, j.b.tets, j.fixed, whole, opt, &wholeReport);
  std::printf("skinned joint: strained region %d of %zu free nodes, %d Newton steps, then %d whole-mesh ones, "
              "against %d; energy %.9g, %.9g\n",
              firstReport.strainedRegionNodes, nFree, firstReport.strainedRegionNewtonIterations,
              firstReport.newtonIterations, wholeReport.newtonIterations, firstReport.energyAfter, wholeReport.energyAfter);
  // The joint's 5 node columns (x = 10 .. 14) and 3 rings each side, of the 19 free columns.
  EXPECT_EQ(firstReport.strainedRegionNodes, 11 * 5 * 5);
  EXPECT_GT(firstReport.strainedRegionNewtonIterations, 0);
  EXPECT_GT(firstReport.strainedRegionSeconds, 0.0);
  EXPECT_LT(firstReport.newtonIterations, wholeReport.newtonIterations);
  EXPECT_EQ(wholeReport.strainedRegionNodes, 0);
  EXPECT_LE(firstReport.energyAfter, wholeReport.energyAfter * (1 + 1e-3));
  EXPECT_EQ(firstReport.invertedAfter, 0);
  for (Eigen::Index v = 0; v < first.rows(); ++v)
    if (j.fixed[std::size_t(v)] >= 0) EXPECT_EQ(first.row(v), j.skinned.row(v));
  // Solved tightly, both ways end at the same minimum.
  opt.stepTolerance = 1e-4;
  opt.energyTolerance = 1e-9;
  Points tight[2] = {j.skinned, j.skinned};
  CorotationalReport tightReport[2];
  for (int k = 0; k < 2; ++k) {
    opt.strainedRegionThreshold = k == 0 ? 1e-4 : 0.0;
    repose::relaxCorotational(j.b.nodes, j.b.tets, j.fixed, tight[k], opt, &tightReport[k]);
  }
  EXPECT_GT(tightReport[0].strainedRegionNodes, 0);
  EXPECT_NEAR(tightReport[0].energyAfter, tightReport[1].energyAfter, 1e-6 * tightReport[1].energyAfter);
  EXPECT_LT((tight[0] - tight[1]).cwiseAbs().maxCoeff(), 1e-3);

  // No tet strained above the threshold: nothing first.
  opt.stepTolerance = 1e-2;
  opt.energyTolerance = 1e-3;
  opt.strainedRegionThreshold = 1e6;
  Points none = j.skinned;
  CorotationalReport noneReport;
  repose::relaxCorotational(j.b.nodes, j.b.tets, j.fixed, none, opt, &noneReport);
  EXPECT_EQ(noneReport.strainedRegionNodes, 0);
  EXPECT_EQ(none, whole);
  // A warm start is next to its minimum already.
  opt.strainedRegionThreshold = 1e-4;
  opt.startCorrection = first - j.skinned;
  Points warm = skinnedJoint(0.95).skinned;
  CorotationalReport warmReport;
  repose::relaxCorotational(j.b.nodes, j.b.tets, j.fixed, warm, opt, &warmReport);
  EXPECT_TRUE(warmReport.correctedStart);
  EXPECT_EQ(warmReport.strainedRegionNodes, 0);
  // A negative threshold or ring count is refused.
  opt.startCorrection.resize(0, 3);
  opt.strainedRegionThreshold = -1.0;
  EXPECT_THROW(repose::relaxCorotational(j.b.nodes, j.b.tets, j.fixed, warm, opt), std::invalid_argument);
  opt.strainedRegionThreshold = 1e-4;
  opt.strainedRegionRings = -1;
  EXPECT_THROW(repose::relaxCorotational(j.b.nodes, j.b.tets, j.fixed, warm, opt), std::invalid_argument);
}

}  // namespace
