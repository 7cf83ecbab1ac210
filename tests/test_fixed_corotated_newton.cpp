// Newton on the fixed-corotated energy: known minima, invariants, solvers, threads and inverted tets.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>

#include "corotational_test_meshes.h"
#include "parallel_for.h"

namespace {

using repose::CorotationalOptions;
using repose::CorotationalReport;
using repose::Points;
using repose::Tets;

TEST(FixedCorotatedFem, SingleTetUnderPureRotationHasNoElasticForce) {
  Points rest(4, 3);
  rest << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0.2, 0.3, 1;
  Tets tets(1, 4);
  tets << 0, 1, 2, 3;
  const Points rotated = transform(rest, someRotation(), Eigen::Vector3d(5, -3, 2));
  std::vector<int> fixed = {0, 0, 0, -1};
  CorotationalOptions opt = fixedCorotated();
  Points posed = rotated;
  CorotationalReport rep;
  repose::relaxCorotational(rest, tets, fixed, posed, opt, &rep);
  EXPECT_LT((posed - rotated).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT(rep.energyBefore, 1e-20);  // no elastic energy in a rotated rest shape
  EXPECT_TRUE(rep.converged);

  posed = rotated;
  posed.row(3) += Eigen::RowVector3d(0.1, -0.05, 0.08);
  repose::relaxCorotational(rest, tets, fixed, posed, opt, &rep);
  EXPECT_LT((posed.row(3) - rotated.row(3)).norm(), 1e-6);
  EXPECT_GT(rep.energyBefore, 0.0);
  EXPECT_LT(rep.energyAfter, 1e-12);
  EXPECT_EQ((posed.topRows(3) - rotated.topRows(3)).cwiseAbs().maxCoeff(), 0.0);
}

// The bent box of the invariance test, with both end slabs clamped.
void bentBox(const Box& b, double angle, std::vector<int>& fixed, Points& posed) {
  fixed.assign(std::size_t(b.nodes.rows()), -1);
  posed = b.nodes;
  const double L = (b.nx - 1) * (b.nodes(1, 0) - b.nodes(0, 0));
  for (Eigen::Index i = 0; i < posed.rows(); ++i) {
    const double s = b.nodes(i, 0) / L;
    posed.row(i) = (Eigen::AngleAxisd(angle * s, Eigen::Vector3d::UnitY()).toRotationMatrix() *
                    b.nodes.row(i).transpose()).transpose();
  }
  for (int k = 0; k < b.nz; ++k)
    for (int j = 0; j < b.ny; ++j) {
      fixed[b.id(0, j, k)] = 0;
      fixed[b.id(b.nx - 1, j, k)] = 1;
    }
}

TEST(FixedCorotatedFem, InvariantToRigidMotionOfTheWholeProblem) {
  const Box b = makeBox(4, 3, 3, 1.5);
  std::vector<int> fixed;
  Points posed;
  bentBox(b, 0.8, fixed, posed);
  CorotationalOptions opt = fixedCorotated();
  opt.stepTolerance = 1e-6;  // about the energy's round-off
  Points x = posed;
  CorotationalReport rep;
  repose::relaxCorotational(b.nodes, b.tets, fixed, x, opt, &rep);
  std::printf("bent box: %d Newton iterations, energy %.3e -> %.3e\n", rep.newtonIterations, rep.energyBefore, rep.energyAfter);
  EXPECT_TRUE(rep.converged);
  EXPECT_LT(rep.energyAfter, rep.energyBefore);
  const Eigen::Matrix3d Q = someRotation();
  const Eigen::Vector3d t(10, 20, -30);
  Points xq = transform(posed, Q, t);
  repose::relaxCorotational(transform(b.nodes, Q, t), b.tets, fixed, xq, opt);
  EXPECT_LT((xq - transform(x, Q, t)).cwiseAbs().maxCoeff(), 1e-5);
  EXPECT_GT((x - posed).cwiseAbs().maxCoeff(), 1e-3);
}

// The two-level preconditioner inside Newton (aggregates from the rest pose, rigid modes about the
// bent pose) reaches the minimum the direct solver does, with its coarse level rebuilt for every
// solve or kept for four (coarseRefreshInterval: only the preconditioner differs).
TEST(FixedCorotatedFem, TwoLevelPreconditionerReachesTheDirectSolversMinimum) {
  const Box b = makeBox(12, 4, 4, 1.0);
  std::vector<int> fixed;
  Points posed;
  bentBox(b, 0.8, fixed, posed);
  Points x[3];
  for (int k = 0; k < 3; ++k) {
    CorotationalOptions opt = fixedCorotated(k == 0 ? CorotationalOptions::Cholmod : CorotationalOptions::TwoLevel);
    opt.stepTolerance = 1e-6;
    opt.coarseAggregateSize = 20;  // several aggregates on this small mesh
    opt.coarseRefreshInterval = k == 1 ? 1 : 4;
    x[k] = posed;
    CorotationalReport rep;
    repose::relaxCorotational(b.nodes, b.tets, fixed, x[k], opt, &rep);
    EXPECT_TRUE(rep.converged) << "run " << k;
    EXPECT_EQ(rep.invertedAfter, 0);
    if (k == 2) EXPECT_GT(rep.newtonIterations, 4);  // the coarse level was kept for some solves
  }
  EXPECT_LT((x[1] - x[0]).cwiseAbs().maxCoeff(), 1e-4);
  EXPECT_LT((x[2] - x[0]).cwiseAbs().maxCoeff(), 1e-4);
  EXPECT_GT((x[1] - posed).cwiseAbs().maxCoeff(), 1e-2);
}

// The squeezed block of NearlyIncompressibleSqueezedBlockKeepsVolume under the nonlinear model:
// det F is kept to second order too, so the volume is kept far better than by the linear model.
TEST(FixedCorotatedFem, NearlyIncompressibleSqueezedBlockKeepsVolume) {
  const Box b = makeBox(6, 6, 6, 1.0);
  std::vector<int> fixed(b.nodes.rows(), -1);
  for (int j = 0; j < b.ny; ++j)
    for (int i = 0; i < b.nx; ++i) {
      fixed[b.id(i, j, 0)] = 0;
      fixed[b.id(i, j, b.nz - 1)] = 1;
    }
  Points squeezed = b.nodes;
  for (Eigen::Index i = 0; i < squeezed.rows(); ++i) squeezed(i, 2) *= 0.9;
  const double v0 = repose::meshVolume(b.nodes, b.tets);
  double ratio[2];
  for (int m = 0; m < 2; ++m) {
    CorotationalOptions opt = fixedCorotated(CorotationalOptions::Cholmod);
    opt.poisson = 0.49;
    if (m == 0) {
      opt.model = CorotationalOptions::Linear;
      opt.outerIterations = 10;
    }
    Points x = squeezed;
    CorotationalReport rep;
    repose::relaxCorotational(b.nodes, b.tets, fixed, x, opt, &rep);
    EXPECT_EQ(rep.invertedAfter, 0);
    ratio[m] = repose::meshVolume(x, b.tets) / v0;
  }
  std::printf("squeezed block volume ratio, nu = 0.49: linear %.5f, fixed-corotated %.5f\n", ratio[0], ratio[1]);
  EXPECT_NEAR(ratio[1], 1.0, 0.01);
  EXPECT_LT(std::abs(ratio[1] - 1), std::abs(ratio[0] - 1));
  // A compressible block (nu = 0) just follows the plates.
  CorotationalOptions opt = fixedCorotated();
  opt.poisson = 0.0;
  Points x = squeezed;
  repose::relaxCorotational(b.nodes, b.tets, fixed, x, opt);
  EXPECT_NEAR(repose::meshVolume(x, b.tets) / v0, 0.9, 0.01);
}

// The energy and region volumes are summed in a fixed order, so the result does not depend on how the
// threads split the work (with vtkSMPTools' pools the chunks finish in a different order every run):
// the same pose twice gives the same nodes to the last bit.
TEST(FixedCorotatedFem, SameResultHoweverTheThreadsSplitTheWork) {
  const StampedBlock block = stampedBlock(16, 6, 6, 4, 11, 1.2);
  const Box& b = block.b;
  const std::vector<int>& fixed = block.fixed;
  const Points& stamped = block.stamped;
  std::vector<int> half(std::size_t(b.tets.rows()));
  for (Eigen::Index t = 0; t < b.tets.rows(); ++t) half[std::size_t(t)] = b.nodes(b.tets(t, 0), 0) < 8.0 ? 0 : 1;
  CorotationalOptions opt = fixedCorotated(CorotationalOptions::TwoLevel);
  opt.coarseAggregateSize = 40;
  opt.volumeRegions = half;
  // Chunks of growing, uneven sizes, run last to first: another order of the partial sums.
  auto reversed = [](std::size_t n, std::size_t grain, const repose::RangeBody& body) {
    std::vector<std::pair<std::size_t, std::size_t>> chunks;
    for (std::size_t b0 = 0, k = 1; b0 < n; b0 += k * std::max<std::size_t>(grain, 1) + 1, ++k)
      chunks.emplace_back(b0, std::min(n, b0 + k * std::max<std::size_t>(grain, 1) + 1));
    for (auto c = chunks.rbegin(); c != chunks.rend(); ++c) body(c->first, c->second);
  };
  Points x[2] = {stamped, stamped};
  CorotationalReport rep[2];
  repose::relaxCorotational(b.nodes, b.tets, fixed, x[0], opt, &rep[0]);
  repose::setParallelRunner(reversed);
  repose::relaxCorotational(b.nodes, b.tets, fixed, x[1], opt, &rep[1]);
  repose::setParallelRunner(repose::ParallelRunner());
  EXPECT_GT(b.tets.rows(), 4 * 512);  // several blocks of the fixed-order sums
  EXPECT_GT(rep[0].newtonIterations, 2);
  EXPECT_EQ(rep[0].newtonIterations, rep[1].newtonIterations);
  EXPECT_EQ(rep[0].energyAfter, rep[1].energyAfter);
  EXPECT_TRUE(x[0] == x[1]) << "largest difference " << (x[0] - x[1]).cwiseAbs().maxCoeff();
  EXPECT_GT((x[0] - stamped).cwiseAbs().maxCoeff(), 0.1);
}

TEST(FixedCorotatedFem, InvertedTetsAreUntangledAndTheCountNeverGrows) {
  const Box b = makeBox(3, 3, 3, 1.0);
  const std::vector<int> fixed = boundaryFixed(b);
  Points posed = b.nodes;
  posed.row(b.id(1, 1, 1)) += Eigen::RowVector3d(1.6, 1.3, 1.5);  // past its neighbours
  posed.row(b.id(2, 2, 1)) += Eigen::RowVector3d(-1.4, -1.2, 0.9);
  for (auto pre : {CorotationalOptions::Jacobi, CorotationalOptions::IncompleteCholesky, CorotationalOptions::Cholmod}) {
    Points x = posed;
    CorotationalReport rep;
    repose::relaxCorotational(b.nodes, b.tets, fixed, x, fixedCorotated(pre), &rep);
    EXPECT_GT(rep.invertedBefore, 0);
    EXPECT_EQ(rep.invertedAfter, 0) << "preconditioner " << pre;
    EXPECT_LT((x - b.nodes).cwiseAbs().maxCoeff(), 1e-6) << "preconditioner " << pre;
  }
}

// A bar bent by 100 degrees about its middle from a linear-blend-skinning-like warm start, which
// folds the inside of the bend: the inverted tets are removed and volume is regained (not all of it:
// the two rigid ends overlap a little at the inner corner, and their tets cannot move).
TEST(FixedCorotatedFem, SharplyBentBarUnfoldsAndKeepsVolume) {
  const Box b = makeBox(12, 4, 4, 1.0);
  std::vector<int> fixed(std::size_t(b.nodes.rows()), -1);
  Points posed = b.nodes;
  const Eigen::Vector3d centre(6, 2, 2);
  const Eigen::Matrix3d Rend = Eigen::AngleAxisd(1.75, Eigen::Vector3d::UnitY()).toRotationMatrix();
  for (Eigen::Index i = 0; i < posed.rows(); ++i) {
      // Rigid up to x = 5 and from x = 7, positions in between blended linearly.
    const double w = std::clamp((b.nodes(i, 0) - 5.0) / 2.0, 0.0, 1.0);
    const Eigen::Vector3d p = b.nodes.row(i).transpose();
    posed.row(i) = ((1 - w) * p + w * (Rend * (p - centre) + centre)).transpose();
    fixed[std::size_t(i)] = w == 0.0 ? 0 : w == 1.0 ? 1 : -1;
  }
  CorotationalOptions opt = fixedCorotated(CorotationalOptions::Cholmod);
  opt.stepTolerance = 1e-5;
  Points x = posed;
  CorotationalReport rep;
  repose::relaxCorotational(b.nodes, b.tets, fixed, x, opt, &rep);
  const double v0 = repose::meshVolume(b.nodes, b.tets);
  std::printf("bent bar: inverted %d -> %d, volume ratio %.4f -> %.4f, %d Newton iterations\n", rep.invertedBefore,
              rep.invertedAfter, repose::meshVolume(posed, b.tets) / v0, repose::meshVolume(x, b.tets) / v0,
              rep.newtonIterations);
  EXPECT_GT(rep.invertedBefore, 0);
  EXPECT_EQ(rep.invertedAfter, 0);
  EXPECT_LT(std::abs(repose::meshVolume(x, b.tets) / v0 - 1), 0.6 * std::abs(repose::meshVolume(posed, b.tets) / v0 - 1));
  for (Eigen::Index i = 0; i < x.rows(); ++i)
    if (fixed[std::size_t(i)] >= 0) EXPECT_EQ((x.row(i) - posed.row(i)).cwiseAbs().maxCoeff(), 0.0);
}

}  // namespace
