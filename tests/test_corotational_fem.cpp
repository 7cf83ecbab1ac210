// The corotational relaxation's driver: start correction, cancelling, bad input, and a benchmark.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "corotational_test_meshes.h"

namespace {

using repose::CorotationalOptions;
using repose::CorotationalReport;
using repose::Points;
using repose::Tets;

// An animation's next frame started from the last frame's correction (relaxed - skinned): the same
// minimum in fewer Newton steps. A correction that would fold more tets than the input is not taken.
TEST(FixedCorotatedFem, StartCorrectionFromTheLastPoseReachesTheSameMinimumSooner) {
  const StampedBlock block = stampedBlock(8, 4, 4, 2, 5, 0.6);
  const Box& b = block.b;
  const std::vector<int>& fixed = block.fixed;
  CorotationalOptions opt = fixedCorotated(CorotationalOptions::TwoLevel);
  opt.coarseAggregateSize = 20;
  const Points frame1 = block.stamped, frame2 = stampedBlock(8, 4, 4, 2, 5, 0.7).stamped;
  Points relaxed1 = frame1;
  repose::relaxCorotational(b.nodes, b.tets, fixed, relaxed1, opt);
  Points cold = frame2, warm = frame2;
  CorotationalReport coldReport, warmReport;
  repose::relaxCorotational(b.nodes, b.tets, fixed, cold, opt, &coldReport);
  opt.startCorrection = relaxed1 - frame1;
  repose::relaxCorotational(b.nodes, b.tets, fixed, warm, opt, &warmReport);
  std::printf("stamped 0.7 deep: %d Newton steps from the skinned pose, %d from the last frame's correction\n",
              coldReport.newtonIterations, warmReport.newtonIterations);
  EXPECT_FALSE(coldReport.correctedStart);
  EXPECT_TRUE(warmReport.correctedStart);
  EXPECT_LT(warmReport.newtonIterations, coldReport.newtonIterations);
  EXPECT_LT((warm - cold).cwiseAbs().maxCoeff(), 1e-5);
  EXPECT_NEAR(warmReport.energyAfter, coldReport.energyAfter, 1e-9 * coldReport.energyAfter);
  for (Eigen::Index v = 0; v < warm.rows(); ++v)
    if (fixed[std::size_t(v)] >= 0) EXPECT_EQ(warm.row(v), frame2.row(v));
  // A correction that folds the block (free nodes pushed through the stamp) is not taken.
  opt.startCorrection = Points::Zero(b.nodes.rows(), 3);
  for (int j = 1; j < b.ny - 1; ++j) opt.startCorrection(b.id(3, j, b.nz - 2), 2) = 3.0;
  Points folded = frame2;
  CorotationalReport foldedReport;
  repose::relaxCorotational(b.nodes, b.tets, fixed, folded, opt, &foldedReport);
  EXPECT_FALSE(foldedReport.correctedStart);
  EXPECT_TRUE(folded == cold);
  // One row per node, finite.
  opt.startCorrection = Points::Zero(b.nodes.rows() - 1, 3);
  Points x = frame2;
  EXPECT_THROW(repose::relaxCorotational(b.nodes, b.tets, fixed, x, opt), std::invalid_argument);
  opt.startCorrection = Points::Zero(b.nodes.rows(), 3);
  opt.startCorrection(0, 0) = std::nan("");
  EXPECT_THROW(repose::relaxCorotational(b.nodes, b.tets, fixed, x, opt), std::invalid_argument);
  EXPECT_EQ(x, frame2);
}

// A cancel check answered true stops the solve wherever it is asked (Newton, untangling rounds, the
// fold-free continuation), with RelaxationCancelled and posed as it came in; never answered true, it
// changes nothing.
TEST(FixedCorotatedFem, CancelStopsTheSolveAndLeavesPosedAsItCameIn) {
  const FoldedBar f = foldedBar();
  CorotationalOptions opt = fixedCorotated(CorotationalOptions::Cholmod);
  opt.boneParents = {-1, 0};
  opt.continuation = CorotationalOptions::IfInverted;
  Points plain = f.folded;
  CorotationalReport plainReport;
  repose::relaxCorotational(f.b.nodes, f.b.tets, f.fixed, plain, opt, &plainReport);
  ASSERT_GT(plainReport.continuationSteps, 0);  // every kind of check point is on the way
  int calls = 0;
  std::set<int> phases;
  double furthest = 0;
  opt.checkpoint = [&](const repose::RelaxationProgress& p) {
    ++calls;
    phases.insert(p.phase);
    furthest = std::max(furthest, p.pathFraction);
    return false;
  };
  Points counted = f.folded;
  repose::relaxCorotational(f.b.nodes, f.b.tets, f.fixed, counted, opt, nullptr);
  EXPECT_EQ((counted - plain).cwiseAbs().maxCoeff(), 0.0);
  ASSERT_GT(calls, plainReport.newtonIterations + plainReport.continuationSteps);
  for (auto phase : {repose::RelaxationProgress::Setup, repose::RelaxationProgress::Newton,
                     repose::RelaxationProgress::Continuation})
    EXPECT_TRUE(phases.count(phase)) << "phase " << phase << " reported";
  EXPECT_GT(furthest, 0.5);  // the path's progress is reported
  EXPECT_LT(furthest, 1.0);
  const int total = calls;
  for (int stopAt : {1, 2, total / 3, total / 2, total - 1, total}) {
    calls = 0;
    opt.checkpoint = [&calls, stopAt](const repose::RelaxationProgress&) { return ++calls >= stopAt; };
    Points x = f.folded;
    EXPECT_THROW(repose::relaxCorotational(f.b.nodes, f.b.tets, f.fixed, x, opt, nullptr), repose::RelaxationCancelled)
        << "cancelled at check " << stopAt << " of " << total;
    EXPECT_EQ(calls, stopAt);
    EXPECT_EQ((x - f.folded).cwiseAbs().maxCoeff(), 0.0) << "cancelled at check " << stopAt;
  }
  // The linear model asks too.
  CorotationalOptions linear;
  linear.model = CorotationalOptions::Linear;
  linear.checkpoint = [](const repose::RelaxationProgress& p) { return p.phase == repose::RelaxationProgress::Linear; };
  Points y = f.blended;
  EXPECT_THROW(repose::relaxCorotational(f.b.nodes, f.b.tets, f.fixed, y, linear, nullptr), repose::RelaxationCancelled);
  EXPECT_EQ((y - f.blended).cwiseAbs().maxCoeff(), 0.0);
}

TEST(CorotationalFem, BadInput) {
  const Box b = makeBox(1, 1, 1, 1.0);
  std::vector<int> fixed(b.nodes.rows(), -1);
  fixed[0] = 0;
  Points posed = b.nodes;
  CorotationalOptions opt;
  // Sizes.
  Points shortPosed = b.nodes.topRows(3);
  EXPECT_THROW(repose::relaxCorotational(b.nodes, b.tets, fixed, shortPosed, opt), std::invalid_argument);
  std::vector<int> shortFixed(3, 0);
  EXPECT_THROW(repose::relaxCorotational(b.nodes, b.tets, shortFixed, posed, opt), std::invalid_argument);
  Tets badTets = b.tets;
  badTets(0, 2) = 99;
  EXPECT_THROW(repose::relaxCorotational(b.nodes, badTets, fixed, posed, opt), std::invalid_argument);
  Tets flipped = b.tets;
  std::swap(flipped(0, 2), flipped(0, 3));
  EXPECT_THROW(repose::relaxCorotational(b.nodes, flipped, fixed, posed, opt), std::invalid_argument);
  // Options.
  for (double nu : {0.5, 0.6, -1.0}) {
    CorotationalOptions o;
    o.poisson = nu;
    EXPECT_THROW(repose::relaxCorotational(b.nodes, b.tets, fixed, posed, o), std::invalid_argument);
  }
  CorotationalOptions o;
  o.outerIterations = 0;
  EXPECT_THROW(repose::relaxCorotational(b.nodes, b.tets, fixed, posed, o), std::invalid_argument);
  CorotationalOptions o2;
  o2.maxNewtonIterations = 0;
  EXPECT_THROW(repose::relaxCorotational(b.nodes, b.tets, fixed, posed, o2), std::invalid_argument);
  o2 = CorotationalOptions{};
  o2.stepTolerance = 0;
  EXPECT_THROW(repose::relaxCorotational(b.nodes, b.tets, fixed, posed, o2), std::invalid_argument);
  o2 = CorotationalOptions{};
  o2.coarseAggregateSize = 0;
  EXPECT_THROW(repose::relaxCorotational(b.nodes, b.tets, fixed, posed, o2), std::invalid_argument);
  o2 = CorotationalOptions{};
  o2.maxContinuationSteps = 0;
  EXPECT_THROW(repose::relaxCorotational(b.nodes, b.tets, fixed, posed, o2), std::invalid_argument);
  o2 = CorotationalOptions{};
  std::vector<int> twoBones = fixed;
  twoBones[1] = 1;
  o2.boneParents = {-1};  // bone 1 has no parent entry
  EXPECT_THROW(repose::relaxCorotational(b.nodes, b.tets, twoBones, posed, o2), std::invalid_argument);
  o2 = CorotationalOptions{};
  o2.twoLevelBelowTolerance = -1;
  EXPECT_THROW(repose::relaxCorotational(b.nodes, b.tets, fixed, posed, o2), std::invalid_argument);
  o2 = CorotationalOptions{};
  o2.coarseRefreshInterval = 0;
  EXPECT_THROW(repose::relaxCorotational(b.nodes, b.tets, fixed, posed, o2), std::invalid_argument);
  // No fixed node: singular.
  std::vector<int> none(b.nodes.rows(), -1);
  EXPECT_THROW(repose::relaxCorotational(b.nodes, b.tets, none, posed, opt), std::invalid_argument);
  // No free node: a no-op.
  std::vector<int> all(b.nodes.rows(), 2);
  Points moved = b.nodes * 1.1;
  const Points before = moved;
  CorotationalReport rep;
  repose::relaxCorotational(b.nodes, b.tets, all, moved, opt, &rep);
  EXPECT_EQ((moved - before).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(rep.outerIterations, 0);
  EXPECT_TRUE(posed.isApprox(b.nodes));  // failed calls left posed untouched
}

// Benchmark (run with --gtest_also_run_disabled_tests): ~200 k nodes, a bent box.
TEST(CorotationalFem, DISABLED_BenchmarkBentBox) {
  const double h = 1.0;
  const Box b = makeBox(99, 44, 44, h);
  const double L = 99 * h;
  std::vector<int> fixed(b.nodes.rows(), -1);
  Points posed(b.nodes.rows(), 3);
  // Skinning-like warm start: rotation blended linearly along the bar up to 60 degrees about y
  // through the bar's middle; the two end slabs (5 node layers) rigid and fixed.
  const double angle = M_PI / 3;
  const Eigen::Vector3d centre(0, 22 * h, 22 * h);
  for (Eigen::Index i = 0; i < posed.rows(); ++i) {
    const double s = std::clamp((b.nodes(i, 0) - 0.3 * L) / (0.4 * L), 0.0, 1.0);
    const Eigen::Matrix3d Ri = Eigen::AngleAxisd(angle * s, Eigen::Vector3d::UnitY()).toRotationMatrix();
    const Eigen::Vector3d c = centre + Eigen::Vector3d(0.5 * L, 0, 0);
    posed.row(i) = (Ri * (b.nodes.row(i).transpose() - c) + c).transpose();
    const int ix = int(std::lround(b.nodes(i, 0) / h));
    if (ix < 5) fixed[i] = 0;
    if (ix > b.nx - 6) fixed[i] = 1;
  }
  std::printf("box: %lld nodes, %lld tets\n", (long long)b.nodes.rows(), (long long)b.tets.rows());
  const double restVolume = repose::meshVolume(b.nodes, b.tets);
  for (auto pre : {CorotationalOptions::Jacobi, CorotationalOptions::IncompleteCholesky}) {
    CorotationalOptions opt;
    opt.model = CorotationalOptions::Linear;
    opt.preconditioner = pre;
    opt.maxCgIterations = 5000;
    Points x = posed;
    CorotationalReport rep;
    repose::relaxCorotational(b.nodes, b.tets, fixed, x, opt, &rep);
    std::printf("%s: %.2f s (assembly %.2f s, CG %.2f s), CG iterations %d, relative residual %.2e, inverted %d -> %d, "
                "volume ratio skinned %.4f -> relaxed %.4f\n",
                pre == CorotationalOptions::Jacobi ? "Jacobi" : "IncompleteCholesky",
                rep.seconds,
                rep.assemblySeconds, rep.solveSeconds,
                rep.cgIterations[0], rep.relativeResidual[0], rep.invertedBefore, rep.invertedAfter,
                repose::meshVolume(posed, b.tets) / restVolume,
                repose::meshVolume(x, b.tets) / restVolume);
    EXPECT_LE(rep.relativeResidual[0], opt.tolerance);
  }
}

}  // namespace
