#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <random>

#include "barycentric_binding.h"
#include "tet_locator.h"
#include "box_tet_mesh.h"
#include "tet_mesh.h"

namespace {

using repose::Points;
using repose::Tets;

void boxMesh(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, const std::array<int, 3>& n, Points& V,
             Tets& T) {
  kuhnBoxMesh(lo, hi, n, V, T);
}

// A mildly irregular mesh: the box lattice with interior nodes jittered (tets stay positive).
void jitteredMesh(Points& V, Tets& T) {
  boxMesh(Eigen::Vector3d(-2, -1, 0), Eigen::Vector3d(3, 2, 4), {6, 5, 7}, V, T);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.08, 0.08);
  for (Eigen::Index v = 0; v < V.rows(); ++v) {
    const Eigen::RowVector3d x = V.row(v);
    const bool boundary = x.x() < -1.99 || x.x() > 2.99 || x.y() < -0.99 || x.y() > 1.99 || x.z() < 0.01 ||
                          x.z() > 3.99;
    if (!boundary) V.row(v) += Eigen::RowVector3d(u(rng), u(rng), u(rng));
  }
}

Points randomPoints(int n, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  Points P(n, 3);
  for (int p = 0; p < n; ++p)
    P.row(p) = (lo + (hi - lo).cwiseProduct(Eigen::Vector3d(u(rng), u(rng), u(rng)))).transpose();
  return P;
}

}  // namespace

TEST(Binding, RoundTripInsideMesh) {
  Points V;
  Tets T;
  jitteredMesh(V, T);
  const Points P = randomPoints(5000, {-1.9, -0.9, 0.1}, {2.9, 1.9, 3.9}, 1);
  const repose::Binding b = repose::bindPoints(V, T, P);
  EXPECT_EQ(b.outsideCount, 0u);
  ASSERT_EQ(b.tet.size(), 5000u);
  for (int p = 0; p < 5000; ++p) {
    EXPECT_NEAR(b.bary.row(p).sum(), 1.0f, 1e-5f);
    EXPECT_GE(b.bary.row(p).minCoeff(), -1e-5f);
  }
  Points Q;
  repose::applyBinding(b, T, V, Q);
  EXPECT_LT((Q - P).cwiseAbs().maxCoeff(), 1e-5);
}

TEST(Binding, RigidMotionMovesPointsRigidly) {
  Points V;
  Tets T;
  jitteredMesh(V, T);
  const Points P = randomPoints(2000, {-1.9, -0.9, 0.1}, {2.9, 1.9, 3.9}, 2);
  const repose::Binding b = repose::bindPoints(V, T, P);
  const Eigen::Matrix3d R = Eigen::AngleAxisd(1.1, Eigen::Vector3d(-1, 2, 0.5).normalized()).toRotationMatrix();
  const Eigen::RowVector3d t(10, -3, 4);
  const Points Vm = (V * R.transpose()).rowwise() + t;
  Points Q;
  repose::applyBinding(b, T, Vm, Q);
  const Points expected = (P * R.transpose()).rowwise() + t;
  EXPECT_LT((Q - expected).cwiseAbs().maxCoeff(), 1e-5);
}

TEST(Binding, OutsidePointsBindToNearestTetAndFollowAffineMaps) {
  Points V;
  Tets T;
  boxMesh(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(4, 3, 5), {4, 3, 5}, V, T);
  // Points around the box, some far, plus a few inside.
  Points P(8, 3);
  P << -0.5, 1.5, 2.5,   // near face x=0
      4.7, 2.9, 4.9,     // near corner
      2.0, -1.0, 6.0,    // near an edge
      10, 10, 10,        // far
      1.2, 1.3, 1.4,     // inside
      3.9, 0.1, 2.2,     // inside
      2.0, 1.5, -3.0,    // below
      -5, -6, 20;        // far
  const repose::Binding b = repose::bindPoints(V, T, P);
  EXPECT_EQ(b.outsideCount, 6u);
  const repose::TetLocator loc(V, T);
  // The bound tet is among the nearest (within the locator's 5 % tie band), and no tet as near
  // extrapolates with smaller barycentric coordinates.
  for (int p = 0; p < P.rows(); ++p) {
    const Eigen::Vector3d x = P.row(p).transpose();
    const double d = loc.distanceToTet(b.tet[p], x);
    double brute = 1e300;
    for (int t = 0; t < T.rows(); ++t) brute = std::min(brute, loc.distanceToTet(t, x));
    // Distance to the box, computed directly.
    const Eigen::Vector3d lo(0, 0, 0), hi(4, 3, 5);
    EXPECT_NEAR(brute, (lo - x).cwiseMax(x - hi).cwiseMax(0.0).norm(), 1e-9) << "point " << p;
    EXPECT_GE(d, brute - 1e-12) << "point " << p;
    EXPECT_LE(d, brute * 1.05 + 1e-6) << "point " << p;
    const double conditioning = loc.barycentric(b.tet[p], x).cwiseAbs().maxCoeff();
    for (int t = 0; t < T.rows(); ++t)
      if (loc.distanceToTet(t, x) <= brute * 1.05 + 1e-6 - 1e-9 && brute > 0)
        EXPECT_LE(conditioning, loc.barycentric(t, x).cwiseAbs().maxCoeff() + 1e-9) << "point " << p << " tet " << t;
  }
  // Under an affine map of the nodes, every bound point (inside or extrapolated) follows it exactly.
  Eigen::Matrix3d A;
  A << 1.2, 0.3, -0.1, 0.05, 0.9, 0.2, -0.3, 0.1, 1.4;
  const Eigen::RowVector3d t(1, 2, -3);
  const Points Va = (V * A.transpose()).rowwise() + t;
  Points Q;
  repose::applyBinding(b, T, Va, Q);
  const Points expected = (P * A.transpose()).rowwise() + t;
  EXPECT_LT((Q - expected).cwiseAbs().maxCoeff(), 1e-4);  // float barycentrics, |x| up to ~25
}

TEST(Binding, LocatorAgreesWithBruteForce) {
  Points V;
  Tets T;
  jitteredMesh(V, T);
  const repose::TetLocator loc(V, T);
  const Points P = randomPoints(500, {-3, -2, -1}, {4, 3, 5}, 3);
  for (int p = 0; p < P.rows(); ++p) {
    const Eigen::Vector3d x = P.row(p).transpose();
    bool insideBrute = false;
    double brute = 1e300;
    for (int t = 0; t < T.rows(); ++t) {
      insideBrute = insideBrute || loc.barycentric(t, x).minCoeff() >= 0;
      brute = std::min(brute, loc.distanceToTet(t, x));
    }
    repose::TetLocator::Hit hit;
    const bool inside = loc.findContaining(x, hit);
    if (insideBrute) EXPECT_TRUE(inside) << p;
    if (inside) EXPECT_GE(hit.bary.minCoeff(), -1e-9);
    const repose::TetLocator::Hit near = loc.findNearest(x);
    EXPECT_GE(near.distance, brute - 1e-12) << p;
    EXPECT_LE(near.distance, brute * 1.05 + 1e-6) << p;
    EXPECT_LT((loc.barycentric(near.tet, x) - near.bary).norm(), 1e-12);
  }
}

TEST(Binding, BadInputThrows) {
  Points V;
  Tets T;
  boxMesh(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 1, 1), {1, 1, 1}, V, T);
  Tets bad = T;
  bad(0, 1) = 99;
  const Points P = randomPoints(3, {0, 0, 0}, {1, 1, 1}, 4);
  EXPECT_THROW(repose::bindPoints(V, bad, P), std::invalid_argument);
  EXPECT_THROW(repose::bindPoints(V, Tets(0, 4), P), std::invalid_argument);
  repose::Binding b = repose::bindPoints(V, T, P);
  b.tet[1] = 1000;
  Points Q;
  EXPECT_THROW(repose::applyBinding(b, T, V, Q), std::invalid_argument);
}

// The float node-id path (what the surface deformer runs per pose) matches the double path.
TEST(Binding, NodeBindingMatchesApplyBinding) {
  Points V;
  Tets T;
  jitteredMesh(V, T);
  const Points P = randomPoints(3000, {-2.5, -1.5, -0.5}, {3.5, 2.5, 4.5}, 5);  // some outside
  const repose::Binding b = repose::bindPoints(V, T, P);
  EXPECT_GT(b.outsideCount, 0u);
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 1, -2).normalized()).toRotationMatrix();
  Points Vm = (V * R.transpose()).rowwise() + Eigen::RowVector3d(100, -50, 20);
  for (Eigen::Index v = 0; v < Vm.rows(); v += 3) Vm.row(v) *= 1.01;  // non-affine too
  Points Q;
  repose::applyBinding(b, T, Vm, Q);
  const repose::NodeBinding nb = repose::makeNodeBinding(b, T);
  ASSERT_EQ(nb.pointCount(), 3000u);
  std::vector<float> fromDouble(3 * 3000), fromFloat(3 * 3000);
  repose::applyBinding(nb, Vm.data(), std::size_t(Vm.rows()), fromDouble.data());
  const std::vector<float> Vf(Vm.data(), Vm.data() + Vm.size());
  repose::applyBinding(nb, Vf.data(), std::size_t(Vm.rows()), fromFloat.data());
  double errD = 0, errF = 0;
  for (int p = 0; p < 3000; ++p)
    for (int c = 0; c < 3; ++c) {
      errD = std::max(errD, std::abs(fromDouble[3 * p + c] - Q(p, c)));
      errF = std::max(errF, std::abs(fromFloat[3 * p + c] - Q(p, c)));
    }
  EXPECT_LT(errD, 2e-5);  // float rounding at |x| ~ 100
  EXPECT_LT(errF, 5e-5);
}

TEST(Binding, NodeBindingBadInputThrows) {
  Points V;
  Tets T;
  boxMesh(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 1, 1), {2, 2, 2}, V, T);
  const Points P = randomPoints(10, {0, 0, 0}, {1, 1, 1}, 6);
  repose::Binding b = repose::bindPoints(V, T, P);
  const repose::NodeBinding nb = repose::makeNodeBinding(b, T);
  std::vector<float> out(30);
  // Posed mesh with fewer nodes than the binding uses.
  EXPECT_THROW(repose::applyBinding(nb, V.data(), std::size_t(nb.maxNode), out.data()), std::invalid_argument);
  EXPECT_NO_THROW(repose::applyBinding(nb, V.data(), std::size_t(V.rows()), out.data()));
  b.tet[3] = int(T.rows());
  EXPECT_THROW(repose::makeNodeBinding(b, T), std::invalid_argument);
}
