// The linear corotational model (Mueller & Gross): known solutions and invariants.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "corotational_test_meshes.h"

namespace {

using repose::CorotationalOptions;
using repose::CorotationalReport;
using repose::Points;
using repose::Tets;

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
  const std::vector<int> fixed = boundaryFixed(b);
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

}  // namespace
