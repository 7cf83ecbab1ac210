// Static corotational FEM relaxation: known solutions and invariants.
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <chrono>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <random>
#include <set>
#include <stdexcept>
#include <thread>

#include "block_sparse_cg.h"
#include "continuation_stall.h"
#include "corotational_fem.h"
#include "parallel_for.h"
#include "signed_svd.h"
#include "tet_untangling.h"
#include "two_level_preconditioner.h"
#include "volume_term.h"
#include "box_tet_mesh.h"
#include "tet_mesh.h"

namespace {

using repose::CorotationalOptions;
using repose::CorotationalReport;
using repose::Points;
using repose::Tets;

struct Box {
  Points nodes;
  Tets tets;
  int nx, ny, nz;  // nodes per axis
  int id(int i, int j, int k) const { return (k * ny + j) * nx + i; }
};

/// cx by cy by cz cubes of edge h from the origin, each split into the 6 Kuhn tets.
Box makeBox(int cx, int cy, int cz, double h) {
  Box b;
  b.nx = cx + 1;
  b.ny = cy + 1;
  b.nz = cz + 1;
  kuhnBoxMesh(Eigen::Vector3d::Zero(), h * Eigen::Vector3d(cx, cy, cz), {cx, cy, cz}, b.nodes, b.tets);
  return b;
}

/// A block of cx by cy by cz unit cubes, its bottom fixed (bone 0) and a stamp (bone 1) pressed depth
/// into its top over the node columns from <= i <= to.
struct StampedBlock {
  Box b;
  std::vector<int> fixed;
  Points stamped;
};
StampedBlock stampedBlock(int cx, int cy, int cz, int from, int to, double depth) {
  StampedBlock s{makeBox(cx, cy, cz, 1.0), {}, {}};
  const Box& b = s.b;
  s.fixed.assign(std::size_t(b.nodes.rows()), -1);
  s.stamped = b.nodes;
  for (int j = 0; j < b.ny; ++j)
    for (int i = 0; i < b.nx; ++i) {
      s.fixed[std::size_t(b.id(i, j, 0))] = 0;
      if (i >= from && i <= to) {
        s.fixed[std::size_t(b.id(i, j, b.nz - 1))] = 1;
        s.stamped(b.id(i, j, b.nz - 1), 2) -= depth;
      }
    }
  return s;
}

Points transform(const Points& P, const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
  Points Q(P.rows(), 3);
  for (Eigen::Index i = 0; i < P.rows(); ++i) Q.row(i) = (R * P.row(i).transpose() + t).transpose();
  return Q;
}

Eigen::Matrix3d someRotation() {
  return Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
}

TEST(CorotationalFem, SingleTetUnderPureRotationHasNoElasticForce) {
  Points rest(4, 3);
  rest << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0.2, 0.3, 1;
  Tets tets(1, 4);
  tets << 0, 1, 2, 3;
  const Eigen::Matrix3d R = someRotation();
  const Eigen::Vector3d t(5, -3, 2);
  const Points rotated = transform(rest, R, t);
  std::vector<int> fixed = {0, 0, 0, -1};
  CorotationalOptions opt;
  opt.model = CorotationalOptions::Linear;
  opt.poisson = 0.3;
  opt.tolerance = 1e-14;

  // At the rigidly moved rest shape the free node feels no force: it stays.
  Points posed = rotated;
  CorotationalReport rep;
  repose::relaxCorotational(rest, tets, fixed, posed, opt, &rep);
  EXPECT_LT((posed - rotated).cwiseAbs().maxCoeff(), 1e-12);

  // Displaced, it returns to its rotated rest position once the rotation is re-extracted.
  posed = rotated;
  posed.row(3) += Eigen::RowVector3d(0.1, -0.05, 0.08);
  opt.outerIterations = 30;
  repose::relaxCorotational(rest, tets, fixed, posed, opt, &rep);
  EXPECT_LT((posed.row(3) - rotated.row(3)).norm(), 1e-6);
  EXPECT_EQ(rep.outerIterations, 30);
  EXPECT_EQ(rep.cgIterations.size(), 30u);
  EXPECT_EQ(rep.invertedAfter, 0);
  // Fixed nodes are exactly where they were.
  EXPECT_EQ((posed.topRows(3) - rotated.topRows(3)).cwiseAbs().maxCoeff(), 0.0);
}

TEST(CorotationalFem, BarStretchedByItsEndsHasUniformStrain) {
  const double h = 2.0, strain = 0.01;
  const Box b = makeBox(10, 2, 2, h);
  const double L = 10 * h;
  std::vector<int> fixed(b.nodes.rows(), -1);
  Points posed = b.nodes;
  for (int k = 0; k < b.nz; ++k)
    for (int j = 0; j < b.ny; ++j) {
      fixed[b.id(0, j, k)] = 0;
      fixed[b.id(b.nx - 1, j, k)] = 1;
      posed(b.id(b.nx - 1, j, k), 0) += strain * L;
    }
  // (BlockJacobi and TwoLevel: the float upper blocks, solving for the correction to the start.)
  for (auto pre : {CorotationalOptions::Jacobi, CorotationalOptions::IncompleteCholesky, CorotationalOptions::Cholmod,
                   CorotationalOptions::BlockJacobi, CorotationalOptions::TwoLevel}) {
    CorotationalOptions opt;
    opt.model = CorotationalOptions::Linear;
    opt.poisson = 0.0;  // no lateral contraction: u = (strain x, 0, 0) is the exact solution
    opt.tolerance = 1e-13;
    opt.preconditioner = pre;
    Points x = posed;
    CorotationalReport rep;
    repose::relaxCorotational(b.nodes, b.tets, fixed, x, opt, &rep);
    ASSERT_EQ(rep.relativeResidual.size(), 1u);
    EXPECT_LE(rep.relativeResidual[0], 1e-13);
    double worst = 0;
    for (Eigen::Index i = 0; i < x.rows(); ++i) {
      const Eigen::RowVector3d expected(b.nodes(i, 0) * (1 + strain), b.nodes(i, 1), b.nodes(i, 2));
      worst = std::max(worst, (x.row(i) - expected).norm());
    }
    EXPECT_LT(worst, 1e-6 * strain * L) << "preconditioner " << pre;
  }
}

TEST(CorotationalFem, InvariantToRigidMotionOfTheWholeProblem) {
  const Box b = makeBox(4, 3, 3, 1.5);
  std::vector<int> fixed(b.nodes.rows(), -1);
  Points posed = b.nodes;
  // Bend: one end fixed at rest, the other end rotated 30 degrees about a lateral axis.
  const Eigen::Matrix3d bend = Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitY()).toRotationMatrix();
  for (Eigen::Index i = 0; i < posed.rows(); ++i) {
    const double s = b.nodes(i, 0) / (4 * 1.5);
    const Eigen::Matrix3d Ri = Eigen::AngleAxisd(0.5 * s, Eigen::Vector3d::UnitY()).toRotationMatrix();
    posed.row(i) = (Ri * b.nodes.row(i).transpose()).transpose();
  }
  for (int k = 0; k < b.nz; ++k)
    for (int j = 0; j < b.ny; ++j) {
      fixed[b.id(0, j, k)] = 0;
      fixed[b.id(b.nx - 1, j, k)] = 1;
      posed.row(b.id(b.nx - 1, j, k)) = (bend * b.nodes.row(b.id(b.nx - 1, j, k)).transpose()).transpose();
    }
  CorotationalOptions opt;
  opt.model = CorotationalOptions::Linear;
  opt.tolerance = 1e-13;
  opt.maxCgIterations = 10000;
  opt.outerIterations = 3;
  // Double-precision CG: the default float block matrix rounds at about 1e-7 of the correction.
  opt.preconditioner = CorotationalOptions::Jacobi;
  Points x = posed;
  repose::relaxCorotational(b.nodes, b.tets, fixed, x, opt);

  const Eigen::Matrix3d Q = someRotation();
  const Eigen::Vector3d t(10, 20, -30);
  Points xq = transform(posed, Q, t);
  repose::relaxCorotational(transform(b.nodes, Q, t), b.tets, fixed, xq, opt);
  const Points expected = transform(x, Q, t);
  EXPECT_LT((xq - expected).cwiseAbs().maxCoeff(), 1e-8);
  // And the solve did something: the free nodes moved away from the warm start.
  EXPECT_GT((x - posed).cwiseAbs().maxCoeff(), 1e-3);
}

// Block squeezed between plates (top moved down 10 %, both plates clamped); returns volume ratio.
double squeezedVolumeRatio(double poisson, CorotationalReport* rep) {
  const double h = 1.0;
  const Box b = makeBox(6, 6, 6, h);
  std::vector<int> fixed(b.nodes.rows(), -1);
  Points posed = b.nodes;
  const double H = 6 * h;
  for (int j = 0; j < b.ny; ++j)
    for (int i = 0; i < b.nx; ++i) {
      fixed[b.id(i, j, 0)] = 0;
      fixed[b.id(i, j, b.nz - 1)] = 1;
    }
  for (Eigen::Index i = 0; i < posed.rows(); ++i) posed(i, 2) *= 0.9;  // warm start: uniform squeeze
  CorotationalOptions opt;
  opt.model = CorotationalOptions::Linear;
  opt.poisson = poisson;
  opt.tolerance = 1e-10;
  opt.maxCgIterations = 20000;
  opt.outerIterations = 2;
  repose::relaxCorotational(b.nodes, b.tets, fixed, posed, opt, rep);
  (void)H;
  return repose::meshVolume(posed, b.tets) / repose::meshVolume(b.nodes, b.tets);
}

TEST(CorotationalFem, NearlyIncompressibleSqueezedBlockKeepsVolume) {
  CorotationalReport rep;
  const double incompressible = squeezedVolumeRatio(0.49, &rep);
  EXPECT_NEAR(incompressible, 1.0, 0.03);
  EXPECT_EQ(rep.invertedAfter, 0);
  const double compressible = squeezedVolumeRatio(0.0, &rep);
  EXPECT_NEAR(compressible, 0.9, 0.005);
  std::printf("squeezed block volume ratio: nu=0.49 %.4f, nu=0 %.4f\n", incompressible, compressible);
}

TEST(CorotationalFem, InvertedSkinnedTetsAreUninverted) {
  const Box b = makeBox(3, 3, 3, 1.0);
  std::vector<int> fixed(b.nodes.rows(), -1);
  for (int k = 0; k < b.nz; ++k)
    for (int j = 0; j < b.ny; ++j)
      for (int i = 0; i < b.nx; ++i)
        if (i == 0 || j == 0 || k == 0 || i == b.nx - 1 || j == b.ny - 1 || k == b.nz - 1)
          fixed[b.id(i, j, k)] = 0;
  Points posed = b.nodes;
  posed.row(b.id(1, 1, 1)) += Eigen::RowVector3d(1.6, 1.3, 1.5);  // past its neighbours
  for (auto pre : {CorotationalOptions::Jacobi, CorotationalOptions::IncompleteCholesky}) {
    CorotationalOptions opt;
    opt.model = CorotationalOptions::Linear;
    opt.preconditioner = pre;
    // The default single outer iteration already un-inverts; more converge to the rest shape.
    Points x = posed;
    CorotationalReport rep;
    repose::relaxCorotational(b.nodes, b.tets, fixed, x, opt, &rep);
    EXPECT_GT(rep.invertedBefore, 0);
    EXPECT_EQ(rep.invertedAfter, 0) << "preconditioner " << pre;
    opt.outerIterations = 20;
    opt.tolerance = 1e-12;
    x = posed;
    repose::relaxCorotational(b.nodes, b.tets, fixed, x, opt, &rep);
    EXPECT_EQ(rep.invertedAfter, 0);
    std::printf("inverted %d -> %d, max distance to rest %.2e\n", rep.invertedBefore, rep.invertedAfter, (x - b.nodes).cwiseAbs().maxCoeff());
    EXPECT_LT((x - b.nodes).cwiseAbs().maxCoeff(), 1e-6);
  }
}

// ---- The nonlinear fixed-corotated model ----

CorotationalOptions fixedCorotated(CorotationalOptions::Preconditioner pre = CorotationalOptions::Jacobi) {
  CorotationalOptions opt;
  opt.model = CorotationalOptions::FixedCorotated;
  opt.preconditioner = pre;
  opt.tolerance = 1e-10;
  opt.stepTolerance = 1e-8;
  opt.maxNewtonIterations = 200;
  opt.energyTolerance = 0;
  opt.maxCgIterations = 20000;
  return opt;
}

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

// A block indented by a stamp on part of its top: linear tets at nu = 0.45 lose volume under the
// stamp. A volume term per region (two halves of the block) holds each half's volume as a whole,
// and the minimum does not depend on the solver (CHOLMOD's Newton matrix omits the term's low-rank
// part, so its iterates differ; the two-level CG includes it).
TEST(FixedCorotatedFem, RegionVolumeTermsKeepEachRegionsVolume) {
  const StampedBlock block = stampedBlock(8, 4, 4, 2, 5, 0.6);
  const Box& b = block.b;
  const std::vector<int>& fixed = block.fixed;
  const Points& stamped = block.stamped;
  std::vector<int> half(std::size_t(b.tets.rows()));
  std::vector<double> restVolume(2, 0.0);
  for (Eigen::Index t = 0; t < b.tets.rows(); ++t) {
    double cx = 0;
    for (int a = 0; a < 4; ++a) cx += 0.25 * b.nodes(b.tets(t, a), 0);
    half[std::size_t(t)] = cx < 4.0 ? 0 : 1;
    restVolume[std::size_t(half[std::size_t(t)])] += repose::tetVolume(
        b.nodes.row(b.tets(t, 0)).transpose(), b.nodes.row(b.tets(t, 1)).transpose(),
        b.nodes.row(b.tets(t, 2)).transpose(), b.nodes.row(b.tets(t, 3)).transpose());
  }
  auto halfRatios = [&](const Points& x) {
    std::vector<double> v(2, 0.0);
    for (Eigen::Index t = 0; t < b.tets.rows(); ++t)
      v[std::size_t(half[std::size_t(t)])] += repose::tetVolume(
          x.row(b.tets(t, 0)).transpose(), x.row(b.tets(t, 1)).transpose(), x.row(b.tets(t, 2)).transpose(),
          x.row(b.tets(t, 3)).transpose());
    return std::vector<double>{v[0] / restVolume[0], v[1] / restVolume[1]};
  };
  CorotationalOptions opt = fixedCorotated(CorotationalOptions::TwoLevel);
  opt.poisson = 0.45;
  opt.coarseAggregateSize = 20;
  Points plain = stamped;
  repose::relaxCorotational(b.nodes, b.tets, fixed, plain, opt);
  const std::vector<double> without = halfRatios(plain);
  opt.volumeRegions = half;
  opt.regionVolumeStiffness = 10.0;
  opt.regionVolumeTolerance = 1.0;  // the penalty alone here; the multiplier updates are tested below
  Points held[2] = {stamped, stamped};
  for (int k = 0; k < 2; ++k) {
    opt.preconditioner = k == 0 ? CorotationalOptions::TwoLevel : CorotationalOptions::Cholmod;
    CorotationalReport rep;
    repose::relaxCorotational(b.nodes, b.tets, fixed, held[k], opt, &rep);
    EXPECT_TRUE(rep.converged) << "preconditioner " << opt.preconditioner;
    EXPECT_EQ(rep.invertedAfter, 0);
    const std::vector<double> with = halfRatios(held[k]);
    ASSERT_EQ(rep.regionVolumeRatio.size(), 2u);
    for (int r = 0; r < 2; ++r) {
      EXPECT_NEAR(rep.regionVolumeRatio[std::size_t(r)], with[std::size_t(r)], 1e-9);
      EXPECT_LT(std::abs(with[std::size_t(r)] - 1), 0.25 * std::abs(without[std::size_t(r)] - 1)) << "half " << r;
    }
    std::printf("stamped block, nu = 0.45, volume ratio of the halves: %.5f %.5f, with region terms %.5f %.5f\n",
                without[0], without[1], with[0], with[1]);
  }
  EXPECT_LT(without[0], 0.99);
  EXPECT_LT((held[0] - held[1]).cwiseAbs().maxCoeff(), 1e-4);
  EXPECT_GT((held[0] - plain).cwiseAbs().maxCoeff(), 1e-2);
  // The penalty leaves each half short by about its pressure / stiffness; the multiplier updates
  // (augmented Lagrangian) take each half to its rest volume within the tolerance.
  const std::vector<double> penaltyOnly = halfRatios(held[0]);
  EXPECT_GT(std::max(std::abs(penaltyOnly[0] - 1), std::abs(penaltyOnly[1] - 1)), 1e-3);
  opt.preconditioner = CorotationalOptions::TwoLevel;
  opt.regionVolumeTolerance = 1e-5;
  for (double stiffness : {10.0, 30.0}) {
    opt.regionVolumeStiffness = stiffness;
    Points exact = stamped;
    CorotationalReport rep;
    repose::relaxCorotational(b.nodes, b.tets, fixed, exact, opt, &rep);
    const std::vector<double> ratio = halfRatios(exact);
    std::printf("stiffness %.0f: after %d multiplier updates the halves keep %.7f %.7f of their volume\n", stiffness,
                rep.regionVolumeUpdates, ratio[0], ratio[1]);
    EXPECT_GE(rep.regionVolumeUpdates, 1);
    EXPECT_LE(rep.regionVolumeUpdates, opt.maxRegionVolumeUpdates);
    EXPECT_EQ(rep.invertedAfter, 0);
    for (int r = 0; r < 2; ++r) EXPECT_NEAR(ratio[std::size_t(r)], 1.0, 1e-5) << "stiffness " << stiffness << " half " << r;
    for (Eigen::Index v = 0; v < exact.rows(); ++v)
      if (fixed[std::size_t(v)] >= 0) EXPECT_EQ(exact.row(v), stamped.row(v));
  }
  opt.maxRegionVolumeUpdates = -1;
  EXPECT_THROW(repose::relaxCorotational(b.nodes, b.tets, fixed, plain, opt), std::invalid_argument);
  opt.maxRegionVolumeUpdates = 4;
  opt.regionVolumeTolerance = -1e-5;
  EXPECT_THROW(repose::relaxCorotational(b.nodes, b.tets, fixed, plain, opt), std::invalid_argument);
  opt.regionVolumeTolerance = 1e-5;
  // Bad regions: one entry per tet, each below the tet count.
  Points x = stamped;
  opt.volumeRegions.back() = int(b.tets.rows());
  EXPECT_THROW(repose::relaxCorotational(b.nodes, b.tets, fixed, x, opt), std::invalid_argument);
  opt.volumeRegions.pop_back();
  EXPECT_THROW(repose::relaxCorotational(b.nodes, b.tets, fixed, x, opt), std::invalid_argument);
  EXPECT_EQ(x, stamped);
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

TEST(FixedCorotatedFem, InvertedTetsAreUntangledAndTheCountNeverGrows) {
  const Box b = makeBox(3, 3, 3, 1.0);
  std::vector<int> fixed(b.nodes.rows(), -1);
  for (int k = 0; k < b.nz; ++k)
    for (int j = 0; j < b.ny; ++j)
      for (int i = 0; i < b.nx; ++i)
        if (i == 0 || j == 0 || k == 0 || i == b.nx - 1 || j == b.ny - 1 || k == b.nz - 1)
          fixed[b.id(i, j, k)] = 0;
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

// A bar bent by 86 degrees about a hinge on its inner face (bones 0: x <= 4 and 1: x >= 8, bone 1 the
// child), warm-started from a fold: the free nodes collapsed onto a curve. Newton and the untangling settle
// in a local minimum with a tet turned inside out; the continuation from the rest shape gets no fold
// on the way and ends in the minimum that a good warm start (the linear blend) reaches directly.
struct FoldedBar {
  Box b = makeBox(12, 4, 4, 1.0);
  std::vector<int> fixed;
  Points blended, folded;
};
FoldedBar foldedBar() {
  FoldedBar f;
  const Box& b = f.b;
  f.fixed.assign(std::size_t(b.nodes.rows()), -1);
  f.blended = f.folded = b.nodes;
  const Eigen::Vector3d hinge(6, 2, 0);
  const Eigen::Matrix3d Rend = Eigen::AngleAxisd(1.5, Eigen::Vector3d::UnitY()).toRotationMatrix();
  for (Eigen::Index i = 0; i < b.nodes.rows(); ++i) {
    const double w = std::clamp((b.nodes(i, 0) - 4.0) / 4.0, 0.0, 1.0);
    const Eigen::Vector3d p = b.nodes.row(i).transpose();
    f.blended.row(i) = ((1 - w) * p + w * (Rend * (p - hinge) + hinge)).transpose();
    f.fixed[std::size_t(i)] = w == 0.0 ? 0 : w == 1.0 ? 1 : -1;
    const Eigen::Vector3d c(6, 2, 2);  // all free rest nodes here, then blended
    const Eigen::Vector3d collapsed = (1 - w) * c + w * (Rend * (c - hinge) + hinge);
    f.folded.row(i) =
        f.fixed[std::size_t(i)] < 0 ? Eigen::RowVector3d(collapsed.transpose()) : Eigen::RowVector3d(f.blended.row(i));
  }
  return f;
}

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

// A cancel check answered true stops the solve wherever it is asked (Newton, untangling rounds, the
// fold-free continuation), with RelaxationCancelled and posed as it came in; never answered true, it
// changes nothing.
// The continuation's stall test judges the pace of the last 20 steps against twice the step budget
// (200 steps: 400), not the step length: a path that slows down and squeezes through goes on.
TEST(ContinuationStall, PaceAgainstTwiceTheBudget) {
  using repose::continuationPaceStalls;
  auto path = [](std::vector<double> steps) {  // s after each step
    std::vector<double> s;
    double at = 0.0;
    for (double d : steps) s.push_back(at = std::min(1.0, at + d));
    return s;
  };
  // 20 steps of 1e-3 after 0.5 in 10 steps: 480 steps still to go at that pace, 510 in all.
  std::vector<double> steps(10, 0.05);
  steps.insert(steps.end(), 20, 1e-3);
  EXPECT_TRUE(continuationPaceStalls(path(steps), 30, 200));
  EXPECT_FALSE(continuationPaceStalls(path(steps), 30, 300));  // 510 against 600
  // Fewer than 21 steps known: no pace yet, however short the steps.
  EXPECT_FALSE(continuationPaceStalls(path(std::vector<double>(20, 1e-7)), 20, 200));
  EXPECT_TRUE(continuationPaceStalls(path(std::vector<double>(21, 1e-7)), 21, 200));
  // The walk's slowest path: short steps (6e-5 of the path), then the pace picks up; at no point
  // does it project more than 400 steps.
  std::vector<double> walk(8, 0.06);
  walk.insert(walk.end(), 12, 6e-5);
  walk.insert(walk.end(), 40, 0.0135);
  const std::vector<double> walkPath = path(walk);
  for (std::size_t k = 1; k <= walkPath.size(); ++k)
    EXPECT_FALSE(continuationPaceStalls(std::vector<double>(walkPath.begin(), walkPath.begin() + std::ptrdiff_t(k)),
                                        int(k), 200))
        << "after step " << k;
  // Just inside and just beyond twice the budget: a pace of 1e-3 with 0.35 to go after 20 steps
  // needs 371 steps in all; with 0.45 to go, 471.
  EXPECT_FALSE(continuationPaceStalls(path({0.63, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3,
                                             1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3}),
                                      21, 200));
  EXPECT_TRUE(continuationPaceStalls(path({0.53, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3,
                                            1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3}),
                                     21, 200));
  // A path at its end, or one that does not move: done, and stalled.
  EXPECT_FALSE(continuationPaceStalls(path(std::vector<double>(30, 0.05)), 30, 200));
  std::vector<double> still(25, 0.0);
  still[0] = 0.4;
  EXPECT_TRUE(continuationPaceStalls(path(still), 25, 200));
}

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

// The volume term and its two guards below J = eps: p and the stiffness are h's derivatives (central
// differences), both guards join the plain term smoothly at eps (value, p and, for the barrier, the
// stiffness), the barrier grows without bound as J -> 0 and is infinite at and below 0, and the
// penalty stays finite through inversion.
TEST(VolumeTerm, DerivativesContinuityAndTheBarrier) {
  const repose::VolumeTerm term{24.5, 245.0, 0.1};
  for (bool barrier : {false, true}) {
    for (double J : {0.002, 0.01, 0.03, 0.07, 0.099, 0.101, 0.5, 1.0, 1.7}) {
      double p, k, pp, kp, pm, km;
      term(J, barrier, p, k);
      const double e = 1e-6 * J;
      const double hp = term(J + e, barrier, pp, kp), hm = term(J - e, barrier, pm, km);
      EXPECT_NEAR(p, (hp - hm) / (2 * e), 1e-5 * (1 + std::abs(p))) << "J " << J << " barrier " << barrier;
      EXPECT_NEAR(k, (pp - pm) / (2 * e), 1e-4 * (1 + std::abs(k))) << "J " << J << " barrier " << barrier;
    }
    double pl, kl, pr, kr;
    const double left = term(0.1 - 1e-12, barrier, pl, kl), right = term(0.1, barrier, pr, kr);
    EXPECT_NEAR(left, right, 1e-9);
    EXPECT_NEAR(pl, pr, 1e-8);
    if (barrier) EXPECT_NEAR(kl, kr, 1e-6);
  }
  double p, k;
  const double at2 = term(1e-2, true, p, k), at8 = term(1e-8, true, p, k);  // logarithmic growth
  EXPECT_GT(k, 1e6);
  EXPECT_GT(at8, at2 + 0.01 * 245.0 * std::log(1e5));
  EXPECT_GT(term(1e-200, true, p, k), at8 + 0.01 * 245.0 * std::log(1e150));
  EXPECT_TRUE(std::isinf(term(0.0, true, p, k)));
  EXPECT_TRUE(std::isinf(term(-0.2, true, p, k)));
  EXPECT_TRUE(std::isfinite(term(-0.2, false, p, k)));
  EXPECT_LT(p, 0.0);  // the penalty pushes an inverted tet back
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

namespace {

/// fixedBone of a box whose boundary nodes are held (bone 0) and interior free.
std::vector<int> boundaryFixed(const Box& b) {
  std::vector<int> fixed(std::size_t(b.nodes.rows()), -1);
  for (int k = 0; k < b.nz; ++k)
    for (int j = 0; j < b.ny; ++j)
      for (int i = 0; i < b.nx; ++i)
        if (i == 0 || j == 0 || k == 0 || i == b.nx - 1 || j == b.ny - 1 || k == b.nz - 1) fixed[b.id(i, j, k)] = 0;
  return fixed;
}

}  // namespace

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

namespace {

// A random SPD matrix of 3x3 blocks: block (i, i + d) for each offset d (and its transpose), and a
// diagonal of diagonal + |N(0, 1)| (diagonally dominant). dense gets the matrix; the result holds
// its nonzero blocks in float, both triangles.
repose::BlockSparseMatrix3f randomSpdBlocks(int n, std::initializer_list<int> offsets, double diagonal,
                                            std::mt19937& rng, Eigen::MatrixXd& dense) {
  std::normal_distribution<double> g;
  dense = Eigen::MatrixXd::Zero(3 * n, 3 * n);
  for (int i = 0; i < n; ++i)
    for (int d : offsets)
      if (i + d < n) {
        Eigen::Matrix3d B;
        for (int k = 0; k < 9; ++k) B(k / 3, k % 3) = 0.3 * g(rng);
        dense.block<3, 3>(3 * i, 3 * (i + d)) = B;
        dense.block<3, 3>(3 * (i + d), 3 * i) = B.transpose();
      }
  for (int i = 0; i < 3 * n; ++i) dense(i, i) = diagonal + std::abs(g(rng));
  repose::BlockSparseMatrix3f A;
  A.rowStart.push_back(0);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j)
      if (dense.block<3, 3>(3 * i, 3 * j).cwiseAbs().maxCoeff() > 0) {
        A.column.push_back(j);
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c) A.values.push_back(float(dense(3 * i + r, 3 * j + c)));
      }
    A.rowStart.push_back(int(A.column.size()));
  }
  return A;
}

}  // namespace

TEST(BlockSparseCg, SolvesAnSpdBlockSystemLikeADenseSolver) {
  // A random SPD matrix of 3x3 blocks with a sparse block pattern (a chain with skips).
  const int n = 40;
  std::mt19937 rng(11);
  std::normal_distribution<double> g;
  Eigen::MatrixXd dense;
  const repose::BlockSparseMatrix3f A = randomSpdBlocks(n, {1, 3}, 4.0, rng, dense);
  Eigen::MatrixXd asFloat = dense.cast<float>().cast<double>();  // the operator CG actually sees
  Eigen::VectorXd b(3 * n);
  for (int i = 0; i < 3 * n; ++i) b(i) = g(rng);
  Eigen::VectorXd y;
  A.multiply(b, y);
  EXPECT_LT((y - asFloat * b).norm(), 1e-12 * b.norm());
  Eigen::VectorXd x = Eigen::VectorXd::Zero(3 * n);
  const repose::BlockCgResult r = repose::blockJacobiCg(A, b, x, 1e-10, 1000);
  EXPECT_LE(r.relativeResidual, 1e-10);
  EXPECT_GT(r.iterations, 0);
  const Eigen::VectorXd exact = asFloat.ldlt().solve(b);
  EXPECT_LT((x - exact).norm(), 1e-8 * exact.norm());
  // A warm start at the solution needs no iteration.
  Eigen::VectorXd warm = exact;
  EXPECT_EQ(repose::blockJacobiCg(A, b, warm, 1e-6, 1000).iterations, 0);
  Eigen::VectorXd wrong(5);
  EXPECT_THROW(repose::blockJacobiCg(A, b, wrong, 1e-6, 10), std::invalid_argument);
}

// A low-rank term sum_r w_r g_r g_r^T beside the blocks (the coupling of region volumes): part of
// the operator that multiply() and both CGs see.
TEST(BlockSparseCg, LowRankTermIsPartOfTheOperator) {
  const int n = 30;
  std::mt19937 rng(5);
  std::normal_distribution<double> g;
  Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(3 * n, 3 * n);
  repose::BlockSparseMatrix3f A;
  A.rowStart.push_back(0);
  for (int i = 0; i < n; ++i) {
    for (int j : {i - 1, i, i + 1}) {
      if (j < 0 || j >= n) continue;
      A.column.push_back(j);
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) {
          const double v = i == j ? (r == c ? 3.0 : 0.0) : (r == c ? -1.0 : 0.0);
          A.values.push_back(float(v));
          dense(3 * i + r, 3 * j + c) = v;
        }
    }
    A.rowStart.push_back(int(A.column.size()));
  }
  // Two terms: the first over rows 0..19, the second over rows 10..29 (rows 10..19 hold both).
  repose::LowRankTerm3 L;
  L.weight = {50.0, 7.0};
  Eigen::MatrixXd G = Eigen::MatrixXd::Zero(3 * n, 2);
  L.rowStart.push_back(0);
  for (int i = 0; i < n; ++i) {
    for (int r = 0; r < 2; ++r) {
      if ((r == 0 && i >= 20) || (r == 1 && i < 10)) continue;
      L.term.push_back(r);
      for (int c = 0; c < 3; ++c) {
        const double v = g(rng);
        L.vector.push_back(v);
        G(3 * i + c, r) = v;
      }
    }
    L.rowStart.push_back(int(L.term.size()));
  }
  dense += G * Eigen::Vector2d(50.0, 7.0).asDiagonal() * G.transpose();
  A.lowRank = &L;
  Eigen::VectorXd b(3 * n);
  for (int i = 0; i < 3 * n; ++i) b(i) = g(rng);
  Eigen::VectorXd y;
  A.multiply(b, y);
  EXPECT_LT((y - dense * b).norm(), 1e-10 * (dense * b).norm());
  const Eigen::VectorXd exact = dense.ldlt().solve(b);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(3 * n);
  EXPECT_LE(repose::blockJacobiCg(A, b, x, 1e-11, 1000).relativeResidual, 1e-11);
  EXPECT_LT((x - exact).norm(), 1e-8 * exact.norm());
  struct Identity : repose::BlockPreconditioner {
    double apply(const Eigen::VectorXd& r, Eigen::VectorXd& z) const override {
      z = r;
      return r.squaredNorm();
    }
  } identity;
  x.setZero();
  EXPECT_LE(repose::preconditionedBlockCg(A, b, x, 1e-11, 1000, identity).relativeResidual, 1e-11);
  EXPECT_LT((x - exact).norm(), 1e-8 * exact.norm());
}

namespace {

// Linear elasticity stiffness (Lame lambda, mu) of a box mesh, restricted to the nodes off its x = 0
// face (which is clamped), as float blocks; positions gets those nodes' positions.
repose::BlockSparseMatrix3f clampedBoxStiffness(const Box& b, double lambda, double mu, Points& positions) {
  std::vector<int> dof(std::size_t(b.nodes.rows()), -1);
  int n = 0;
  for (Eigen::Index i = 0; i < b.nodes.rows(); ++i)
    if (b.nodes(i, 0) > 1e-9) dof[std::size_t(i)] = n++;
  positions.resize(n, 3);
  for (Eigen::Index i = 0; i < b.nodes.rows(); ++i)
    if (dof[std::size_t(i)] >= 0) positions.row(dof[std::size_t(i)]) = b.nodes.row(i);
  std::vector<std::map<int, Eigen::Matrix3d>> rows(static_cast<std::size_t>(n));
  for (Eigen::Index t = 0; t < b.tets.rows(); ++t) {
    Eigen::Matrix3d Dm;
    for (int k = 0; k < 3; ++k) Dm.col(k) = (b.nodes.row(b.tets(t, k + 1)) - b.nodes.row(b.tets(t, 0))).transpose();
    const double volume = Dm.determinant() / 6;
    Eigen::Matrix<double, 4, 3> g;
    g.bottomRows<3>() = Dm.inverse();
    g.row(0) = -g.bottomRows<3>().colwise().sum();
    for (int a = 0; a < 4; ++a)
      for (int c = 0; c < 4; ++c) {
        const int i = dof[std::size_t(b.tets(t, a))], j = dof[std::size_t(b.tets(t, c))];
        if (i < 0 || j < 0) continue;
        const Eigen::Vector3d ga = g.row(a).transpose(), gc = g.row(c).transpose();
        const Eigen::Matrix3d K = volume * (lambda * ga * gc.transpose() + mu * gc * ga.transpose() +
                                            mu * ga.dot(gc) * Eigen::Matrix3d::Identity());
        auto it = rows[std::size_t(i)].emplace(j, Eigen::Matrix3d::Zero()).first;
        it->second += K;
      }
  }
  repose::BlockSparseMatrix3f A;
  A.rowStart.push_back(0);
  for (const auto& row : rows) {
    for (const auto& [j, K] : row) {
      A.column.push_back(j);
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) A.values.push_back(float(K(r, c)));
    }
    A.rowStart.push_back(int(A.column.size()));
  }
  return A;
}

// The blocks of a symmetric matrix on and above the diagonal, as an upper-stored matrix.
repose::BlockSparseMatrix3f upperPart(const repose::BlockSparseMatrix3f& full) {
  repose::BlockSparseMatrix3f U;
  U.upper = true;
  U.rowStart.push_back(0);
  for (int i = 0; i < full.rows(); ++i) {
    for (int k = full.rowStart[std::size_t(i)]; k < full.rowStart[std::size_t(i) + 1]; ++k) {
      if (full.column[std::size_t(k)] < i) continue;
      U.column.push_back(full.column[std::size_t(k)]);
      U.values.insert(U.values.end(), full.values.begin() + 9 * k, full.values.begin() + 9 * (k + 1));
    }
    U.rowStart.push_back(int(U.column.size()));
  }
  return U;
}

}  // namespace

// Upper storage (the FEM's Newton matrices): the same operator from about half the blocks, also
// with couplings that reach across the threads' row ranges (j = i + n/2) and rows with no block.
TEST(BlockSparseCg, UpperStorageIsTheSameOperator) {
  const int n = 400;
  std::mt19937 rng(17);
  std::normal_distribution<double> g;
  Eigen::MatrixXd dense;
  const repose::BlockSparseMatrix3f A = randomSpdBlocks(n, {1, 7, n / 2}, 5.0, rng, dense);
  const repose::BlockSparseMatrix3f U = upperPart(A);
  EXPECT_TRUE(U.upper);
  EXPECT_LT(U.column.size(), 0.6 * double(A.column.size()));
  Eigen::VectorXd x(3 * n);
  for (int i = 0; i < 3 * n; ++i) x(i) = g(rng);
  Eigen::VectorXd yFull, yUpper;
  A.multiply(x, yFull);
  U.multiply(x, yUpper);
  EXPECT_LT((yUpper - yFull).norm(), 1e-12 * yFull.norm());
  const Eigen::MatrixXd asFloat = dense.cast<float>().cast<double>();
  EXPECT_LT((yUpper - asFloat * x).norm(), 1e-12 * yFull.norm());
  Eigen::VectorXd solution = Eigen::VectorXd::Zero(3 * n);
  EXPECT_LE(repose::blockJacobiCg(U, x, solution, 1e-10, 1000).relativeResidual, 1e-10);
  EXPECT_LT((solution - asFloat.ldlt().solve(x)).norm(), 1e-8 * solution.norm());
  // Empty rows (a node whose blocks all sit in earlier rows cannot exist, but the product must not
  // depend on it): the zero matrix of the same size gives zero.
  repose::BlockSparseMatrix3f empty;
  empty.upper = true;
  empty.rowStart.assign(std::size_t(n) + 1, 0);
  empty.multiply(x, yUpper);
  EXPECT_EQ(yUpper.size(), 3 * n);
  EXPECT_EQ(yUpper.cwiseAbs().maxCoeff(), 0.0);
}

/// size independent standard normal numbers.
Eigen::VectorXd gaussianVector(int size, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g;
  Eigen::VectorXd v(size);
  for (int i = 0; i < size; ++i) v(i) = g(rng);
  return v;
}

/// The operator CG sees (float blocks, full storage) as a dense double matrix.
Eigen::MatrixXd denseOperator(const repose::BlockSparseMatrix3f& A) {
  const int n = A.rows();
  Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(3 * n, 3 * n);
  for (int i = 0; i < n; ++i)
    for (int k = A.rowStart[std::size_t(i)]; k < A.rowStart[std::size_t(i) + 1]; ++k)
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c)
          dense(3 * i + r, 3 * A.column[std::size_t(k)] + c) = double(A.values[9 * std::size_t(k) + 3 * std::size_t(r) + c]);
  return dense;
}

TEST(TwoLevelPreconditioner, SolvesAnElasticitySystemLikeADenseSolver) {
  const Box b = makeBox(8, 4, 4, 1.0);
  Points positions;
  const repose::BlockSparseMatrix3f A = clampedBoxStiffness(b, 5.0, 1.0, positions);
  const int n = A.rows();
  const Eigen::VectorXd rhs = gaussianVector(3 * n, 5);
  const Eigen::VectorXd exact = denseOperator(A).ldlt().solve(rhs);
  repose::TwoLevelPreconditioner M;
  M.aggregate(A, positions, 20);
  EXPECT_GT(M.aggregates(), 4);
  EXPECT_LT(M.aggregates(), n / 5);
  M.update(A, positions);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(3 * n);
  const repose::BlockCgResult r = repose::preconditionedBlockCg(A, rhs, x, 1e-10, 1000, M);
  EXPECT_LE(r.relativeResidual, 1e-10);
  EXPECT_GT(r.iterations, 0);
  EXPECT_LT((x - exact).norm(), 1e-7 * exact.norm());
  // A warm start at the solution needs no iteration.
  Eigen::VectorXd warm = exact;
  EXPECT_EQ(repose::preconditionedBlockCg(A, rhs, warm, 1e-6, 1000, M).iterations, 0);
}

// An upper-stored matrix gives the same aggregates, the same coarse matrix (P^T A P from the stored
// blocks and their transposes) and so the same preconditioner and CG.
TEST(TwoLevelPreconditioner, UpperStorageGivesTheSamePreconditioner) {
  const Box b = makeBox(12, 4, 4, 1.0);
  Points positions;
  const repose::BlockSparseMatrix3f A = clampedBoxStiffness(b, 5.0, 1.0, positions);
  const repose::BlockSparseMatrix3f U = upperPart(A);
  const int n = A.rows();
  repose::TwoLevelPreconditioner full, upper;
  full.aggregate(A, positions, 20);
  upper.aggregate(U, positions, 20);
  ASSERT_EQ(upper.aggregates(), full.aggregates());
  ASSERT_EQ(upper.coarseSize(), full.coarseSize());
  EXPECT_GT(full.aggregates(), 4);
  full.update(A, positions);
  upper.update(U, positions);
  std::mt19937 rng(9);
  std::normal_distribution<double> g;
  Eigen::VectorXd r(3 * n), zFull, zUpper;
  for (int i = 0; i < 3 * n; ++i) r(i) = g(rng);
  const double rzFull = full.apply(r, zFull), rzUpper = upper.apply(r, zUpper);
  EXPECT_LT((zUpper - zFull).norm(), 1e-9 * zFull.norm());
  EXPECT_NEAR(rzUpper, rzFull, 1e-9 * std::abs(rzFull));
  Eigen::VectorXd xFull = Eigen::VectorXd::Zero(3 * n), xUpper = xFull;
  const repose::BlockCgResult cgFull = repose::preconditionedBlockCg(A, r, xFull, 1e-10, 1000, full);
  const repose::BlockCgResult cgUpper = repose::preconditionedBlockCg(U, r, xUpper, 1e-10, 1000, upper);
  EXPECT_LE(cgUpper.relativeResidual, 1e-10);
  EXPECT_LE(std::abs(cgUpper.iterations - cgFull.iterations), 1);
  EXPECT_LT((xUpper - xFull).norm(), 1e-8 * xFull.norm());
}

// The coarse space takes the smooth error that block Jacobi is slow on: far fewer iterations on a
// long clamped bar.
// A block-diagonal matrix plus a low-rank term: the fine level, which takes the term in by
// Woodbury's identity, is then the exact inverse, and CG converges in one iteration.
TEST(TwoLevelPreconditioner, LowRankTermJoinsTheFineLevelExactly) {
  const int n = 50;
  std::mt19937 rng(3);
  std::normal_distribution<double> g;
  repose::BlockSparseMatrix3f A;
  Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(3 * n, 3 * n);
  Points positions(n, 3);
  A.rowStart.push_back(0);
  for (int i = 0; i < n; ++i) {
    Eigen::Matrix3d B;
    for (int k = 0; k < 9; ++k) B(k / 3, k % 3) = g(rng);
    const Eigen::Matrix3d D = B * B.transpose() + Eigen::Matrix3d::Identity();
    A.column.push_back(i);
    for (int k = 0; k < 9; ++k) A.values.push_back(float(D(k / 3, k % 3)));
    dense.block<3, 3>(3 * i, 3 * i) = D.cast<float>().cast<double>();
    A.rowStart.push_back(i + 1);
    positions.row(i) << i, 0.5 * i, 0;
  }
  repose::LowRankTerm3 L;
  L.weight = {1e4, 30.0, 0.0};  // a stiff term, a soft one and an unused one
  Eigen::MatrixXd G = Eigen::MatrixXd::Zero(3 * n, 3);
  L.rowStart.push_back(0);
  for (int i = 0; i < n; ++i) {
    for (int r = 0; r < 3; ++r) {
      if ((r == 0 && i % 2) || (r == 1 && i < n / 3)) continue;
      L.term.push_back(r);
      for (int c = 0; c < 3; ++c) {
        L.vector.push_back(g(rng));
        G(3 * i + c, r) = L.vector.back();
      }
    }
    L.rowStart.push_back(int(L.term.size()));
  }
  dense += G * Eigen::Vector3d(1e4, 30.0, 0.0).asDiagonal() * G.transpose();
  A.lowRank = &L;
  repose::TwoLevelPreconditioner M;
  M.aggregate(A, positions, 10);
  M.updateFine(A);
  Eigen::VectorXd b(3 * n);
  for (int i = 0; i < 3 * n; ++i) b(i) = g(rng);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(3 * n);
  const repose::BlockCgResult r = repose::preconditionedBlockCg(A, b, x, 1e-9, 100, M);
  EXPECT_LE(r.iterations, 2);
  EXPECT_LT((x - dense.ldlt().solve(b)).norm(), 1e-7 * x.norm());
}

// A projected Newton Hessian is only semi-definite. With every block touching a slab of nodes
// zeroed, the slab's aggregates have rigid modes of zero energy and the coarse matrix is singular:
// it is factorized with a small shift, the preconditioner stays positive definite, and CG still
// solves a system with a right-hand side in the matrix's range.
TEST(TwoLevelPreconditioner, SingularCoarseMatrixIsShiftedNotRefused) {
  const Box b = makeBox(12, 4, 4, 1.0);
  Points positions;
  repose::BlockSparseMatrix3f A = clampedBoxStiffness(b, 5.0, 1.0, positions);
  const int n = A.rows();
  std::vector<char> slab(std::size_t(n), 0);
  for (int i = 0; i < n; ++i) slab[std::size_t(i)] = positions(i, 0) > 8.5;
  int zeroed = 0;
  for (int i = 0; i < n; ++i)
    for (int k = A.rowStart[std::size_t(i)]; k < A.rowStart[std::size_t(i) + 1]; ++k)
      if (slab[std::size_t(i)] || slab[std::size_t(A.column[std::size_t(k)])]) {
        std::fill_n(A.values.begin() + 9 * std::ptrdiff_t(k), 9, 0.0f);
        ++zeroed;
      }
  ASSERT_GT(zeroed, 0);
  repose::TwoLevelPreconditioner M;
  M.aggregate(A, positions, 20);
  ASSERT_NO_THROW(M.update(A, positions));
  EXPECT_TRUE(M.coarseUsed());
  EXPECT_GT(M.coarseShift(), 0.0);
  std::mt19937 rng(3);
  std::normal_distribution<double> g;
  Eigen::VectorXd r(3 * n), z;
  for (int trial = 0; trial < 5; ++trial) {
    for (int i = 0; i < 3 * n; ++i) r(i) = g(rng);
    M.apply(r, z);
    EXPECT_GT(r.dot(z), 0.0);
  }
  // A right-hand side in A's range (zero on the slab): CG reaches it.
  Eigen::VectorXd truth(3 * n), rhs;
  for (int i = 0; i < 3 * n; ++i) truth(i) = slab[std::size_t(i / 3)] ? 0.0 : g(rng);
  A.multiply(truth, rhs);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(3 * n), Ax;
  const repose::BlockCgResult result = repose::preconditionedBlockCg(A, rhs, x, 1e-8, 2000, M);
  EXPECT_LE(result.relativeResidual, 1e-8);
  A.multiply(x, Ax);
  EXPECT_LT((Ax - rhs).norm(), 1e-6 * rhs.norm());
  // The unchanged matrix needs no shift (it is reset on every update).
  const repose::BlockSparseMatrix3f K = clampedBoxStiffness(b, 5.0, 1.0, positions);
  M.update(K, positions);
  EXPECT_EQ(M.coarseShift(), 0.0);
}

// The coarse level of one matrix beside the block Jacobi of another (the next Newton matrix): an
// SPD preconditioner still, so CG reaches the new matrix's solution; and the old coarse correction
// still takes the smooth error that block Jacobi alone is slow on.
TEST(TwoLevelPreconditioner, KeptCoarseLevelServesTheNextMatrix) {
  const Box b = makeBox(20, 5, 5, 1.0);
  Points positions;
  const repose::BlockSparseMatrix3f first = clampedBoxStiffness(b, 5.0, 1.0, positions);
  const repose::BlockSparseMatrix3f next = clampedBoxStiffness(b, 8.0, 1.3, positions);
  const int n = next.rows();
  const Eigen::VectorXd rhs = gaussianVector(3 * n, 11);
  const Eigen::VectorXd exact = denseOperator(next).ldlt().solve(rhs);

  repose::TwoLevelPreconditioner fresh, kept;
  fresh.aggregate(next, positions, 30);
  fresh.update(next, positions);
  kept.aggregate(first, positions, 30);
  kept.update(first, positions);
  kept.updateFineKeepingCoarse(next);
  EXPECT_TRUE(kept.coarseUsed());
  Eigen::VectorXd z;
  for (unsigned trial = 0; trial < 5; ++trial) EXPECT_GT(kept.apply(gaussianVector(3 * n, 20 + trial), z), 0.0);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(3 * n);
  const repose::BlockCgResult withKept = repose::preconditionedBlockCg(next, rhs, x, 1e-10, 2000, kept);
  EXPECT_LE(withKept.relativeResidual, 1e-10);
  EXPECT_LT((x - exact).norm(), 1e-7 * exact.norm());
  x.setZero();
  const int withFresh = repose::preconditionedBlockCg(next, rhs, x, 1e-10, 2000, fresh).iterations;
  x.setZero();
  const int jacobi = repose::blockJacobiCg(next, rhs, x, 1e-10, 10000).iterations;
  std::printf("CG iterations: fresh coarse level %d, kept %d, block Jacobi %d\n", withFresh, withKept.iterations, jacobi);
  EXPECT_LT(withKept.iterations, jacobi / 2);
  // After updateFine() there is no coarse level to keep: block Jacobi alone.
  kept.updateFine(first);
  kept.updateFineKeepingCoarse(next);
  EXPECT_FALSE(kept.coarseUsed());
}

TEST(TwoLevelPreconditioner, IndefiniteCoarseMatrixFallsBackToBlockJacobi) {
  // A negated stiffness: Ac is negative definite, which no shift up to 1e-2 of its mean diagonal
  // repairs. The preconditioner is then block Jacobi alone instead of an error.
  const Box b = makeBox(12, 4, 4, 1.0);
  Points positions;
  repose::BlockSparseMatrix3f A = clampedBoxStiffness(b, 5.0, 1.0, positions);
  const int n = A.rows();
  for (float& v : A.values) v = -v;
  repose::TwoLevelPreconditioner M, jacobi;
  M.aggregate(A, positions, 20);
  jacobi.aggregate(A, positions, 20);
  ASSERT_NO_THROW(M.update(A, positions));
  EXPECT_FALSE(M.coarseUsed());
  jacobi.updateFine(A);
  std::mt19937 rng(5);
  std::normal_distribution<double> g;
  Eigen::VectorXd r(3 * n), z, zJacobi;
  for (int i = 0; i < 3 * n; ++i) r(i) = g(rng);
  EXPECT_EQ(M.apply(r, z), jacobi.apply(r, zJacobi));
  EXPECT_EQ((z - zJacobi).norm(), 0.0);
  // The next update with a definite matrix has its coarse level again.
  const repose::BlockSparseMatrix3f K = clampedBoxStiffness(b, 5.0, 1.0, positions);
  M.update(K, positions);
  EXPECT_TRUE(M.coarseUsed());
  M.apply(r, z);
  jacobi.updateFine(K);
  jacobi.apply(r, zJacobi);
  EXPECT_GT((z - zJacobi).norm(), 1e-6 * z.norm());
}

TEST(TwoLevelPreconditioner, NeedsFewerIterationsThanBlockJacobi) {
  const Box b = makeBox(40, 8, 8, 1.0);
  Points positions;
  const repose::BlockSparseMatrix3f A = clampedBoxStiffness(b, 10.0, 1.0, positions);
  const int n = A.rows();
  std::mt19937 rng(7);
  std::normal_distribution<double> g;
  Eigen::VectorXd rhs(3 * n);
  for (int i = 0; i < 3 * n; ++i) rhs(i) = g(rng);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(3 * n);
  const int jacobi = repose::blockJacobiCg(A, rhs, x, 1e-8, 10000).iterations;
  repose::TwoLevelPreconditioner M;
  M.aggregate(A, positions, 60);
  M.update(A, positions);
  x.setZero();
  const repose::BlockCgResult r = repose::preconditionedBlockCg(A, rhs, x, 1e-8, 10000, M);
  EXPECT_LE(r.relativeResidual, 1e-8);
  std::printf("CG iterations: block Jacobi %d, two-level %d (%d aggregates)\n", jacobi, r.iterations, M.aggregates());
  EXPECT_LT(r.iterations, jacobi / 4);
}

namespace {

// parallelFor() runners that split the work otherwise than the installed one: all of it in one call
// on this thread, or contiguous ranges on `workers` std::threads whatever the grain.
void serialRunner(std::size_t n, std::size_t, const repose::RangeBody& body) { body(0, n); }

repose::ParallelRunner threadRunner(std::size_t workers) {
  return [workers](std::size_t n, std::size_t, const repose::RangeBody& body) {
    const std::size_t chunk = (n + workers - 1) / workers;
    std::vector<std::thread> threads;
    for (std::size_t b = 0; b < n; b += chunk) threads.emplace_back([&body, b, e = std::min(n, b + chunk)] { body(b, e); });
    for (auto& t : threads) t.join();
  };
}

bool bitIdentical(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), sizeof(double) * std::size_t(a.size())) == 0;
}

}  // namespace

// Every sum of the block CGs and the two-level preconditioner is taken over chunks fixed by the
// sizes and added in chunk order: the solutions are the same bits on one thread and on several.
TEST(BlockSparseCg, SolutionsAreBitIdenticalForAnyThreadCount) {
  const Box b = makeBox(40, 8, 8, 1.0);
  Points positions;
  repose::BlockSparseMatrix3f U = upperPart(clampedBoxStiffness(b, 10.0, 1.0, positions));
  const int n = U.rows();
  std::mt19937 rng(23);
  std::normal_distribution<double> g;
  repose::LowRankTerm3 L;  // a region-volume-like coupling: one term over the far half, one over all
  L.weight = {3.0, 0.5};
  L.rowStart.push_back(0);
  for (int i = 0; i < n; ++i) {
    for (int r = 0; r < 2; ++r) {
      if (r == 0 && positions(i, 0) < 20.0) continue;
      L.term.push_back(r);
      for (int c = 0; c < 3; ++c) L.vector.push_back(0.1 * g(rng));
    }
    L.rowStart.push_back(int(L.term.size()));
  }
  U.lowRank = &L;
  Eigen::VectorXd rhs(3 * n);
  for (int i = 0; i < 3 * n; ++i) rhs(i) = g(rng);
  struct Run {
    Eigen::VectorXd jacobi, twoLevel;
    repose::BlockCgResult jacobiCg, twoLevelCg;
  };
  auto solve = [&](const repose::ParallelRunner& runner) {
    repose::setParallelRunner(runner);
    Run run;
    run.jacobi = Eigen::VectorXd::Zero(3 * n);
    run.jacobiCg = repose::blockJacobiCg(U, rhs, run.jacobi, 1e-9, 300);  // far from converged: enough bits
    repose::TwoLevelPreconditioner M;
    M.aggregate(U, positions, 60);
    M.update(U, positions);
    run.twoLevel = Eigen::VectorXd::Zero(3 * n);
    run.twoLevelCg = repose::preconditionedBlockCg(U, rhs, run.twoLevel, 1e-9, 10000, M);
    repose::setParallelRunner(repose::ParallelRunner());
    return run;
  };
  const Run serial = solve(serialRunner);
  EXPECT_GT(U.column.size(), std::size_t(2 * 8192));  // several chunks of the upper product too
  EXPECT_EQ(serial.jacobiCg.iterations, 300);
  EXPECT_LT(serial.jacobiCg.relativeResidual, 0.1);
  EXPECT_LE(serial.twoLevelCg.relativeResidual, 1e-9);
  EXPECT_GT(serial.twoLevelCg.iterations, 5);
  Eigen::VectorXd product;
  U.multiply(serial.twoLevel, product);
  EXPECT_LT((product - rhs).norm(), 1e-8 * rhs.norm());
  std::vector<std::pair<const char*, repose::ParallelRunner>> runners = {
      {"1 thread", threadRunner(1)}, {"2 threads", threadRunner(2)}, {"3 threads", threadRunner(3)},
      {"7 threads", threadRunner(7)}, {"default runner", repose::ParallelRunner()}};
  for (const auto& [name, runner] : runners) {
    SCOPED_TRACE(name);
    const Run run = solve(runner);
    EXPECT_EQ(run.jacobiCg.iterations, serial.jacobiCg.iterations);
    EXPECT_EQ(run.jacobiCg.relativeResidual, serial.jacobiCg.relativeResidual);
    EXPECT_TRUE(bitIdentical(run.jacobi, serial.jacobi)) << (run.jacobi - serial.jacobi).cwiseAbs().maxCoeff();
    EXPECT_EQ(run.twoLevelCg.iterations, serial.twoLevelCg.iterations);
    EXPECT_EQ(run.twoLevelCg.relativeResidual, serial.twoLevelCg.relativeResidual);
    EXPECT_TRUE(bitIdentical(run.twoLevel, serial.twoLevel)) << (run.twoLevel - serial.twoLevel).cwiseAbs().maxCoeff();
  }
}

// The upper-stored product in several row chunks, also when couplings reach far (a stride through
// the rows, so the chunks are merged to bound the spill buffers): the product summed serially, and
// the same bits however the threads split the chunks.
TEST(BlockSparseCg, ChunkedUpperProductMatchesASerialSum) {
  const int n = 8000;
  std::mt19937 rng(29);
  std::normal_distribution<double> g;
  repose::BlockSparseMatrix3f U;
  U.upper = true;
  U.rowStart.push_back(0);
  for (int i = 0; i < n; ++i) {
    std::set<int> columns = {i};
    for (int d : {1, 2})
      if (i + d < n) columns.insert(i + d);
    if (const int far = int((long long)i * 7919 % n); far > i) columns.insert(far);
    for (int j : columns) {
      U.column.push_back(j);
      for (int k = 0; k < 9; ++k) U.values.push_back(float(g(rng)));
    }
    U.rowStart.push_back(int(U.column.size()));
  }
  Eigen::VectorXd x(3 * n);
  for (int i = 0; i < 3 * n; ++i) x(i) = g(rng);
  Eigen::VectorXd expected = Eigen::VectorXd::Zero(3 * n);
  for (int i = 0; i < n; ++i)
    for (int k = U.rowStart[std::size_t(i)]; k < U.rowStart[std::size_t(i) + 1]; ++k) {
      const int j = U.column[std::size_t(k)];
      const Eigen::Matrix3d A =
          Eigen::Map<const Eigen::Matrix<float, 3, 3, Eigen::RowMajor>>(U.values.data() + 9 * std::size_t(k)).cast<double>();
      expected.segment<3>(3 * i) += A * x.segment<3>(3 * j);
      if (j != i) expected.segment<3>(3 * j) += A.transpose() * x.segment<3>(3 * i);
    }
  EXPECT_GT(U.column.size(), std::size_t(2 * 8192));
  Eigen::VectorXd serial, threaded;
  repose::setParallelRunner(serialRunner);
  U.multiply(x, serial);
  repose::setParallelRunner(threadRunner(3));
  U.multiply(x, threaded);
  repose::setParallelRunner(repose::ParallelRunner());
  EXPECT_LT((serial - expected).norm(), 1e-12 * expected.norm());
  EXPECT_TRUE(bitIdentical(serial, threaded));
}
