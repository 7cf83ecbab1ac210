// Posing arbitrary meshes through the tet deformation field: binding, moving, caching.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <unistd.h>

#include "barycentric_binding.h"
#include "tet_locator.h"
#include "box_tet_mesh.h"
#include "tet_mesh.h"

namespace {

using repose::Points;
using repose::Tets;

// Box lattice with interior nodes jittered (tets stay positive).
void jitteredBox(const std::array<int, 3>& n, Points& V, Tets& T, unsigned seed = 5) {
  kuhnBoxMesh(Eigen::Vector3d(-20, -10, 0), Eigen::Vector3d(30, 15, 60), n, V, T, 0.15, seed);
}

// Barycentric coordinates by solving the 3x3 system directly (independent of the locator's formula).
Eigen::Vector4d handBarycentric(const Points& V, const Tets& T, int t, const Eigen::Vector3d& x) {
  Eigen::Matrix3d A;
  for (int a = 0; a < 3; ++a) A.col(a) = (V.row(T(t, a + 1)) - V.row(T(t, 0))).transpose();
  const Eigen::Vector3d l = A.fullPivLu().solve(x - V.row(T(t, 0)).transpose());
  return Eigen::Vector4d(1 - l.sum(), l[0], l[1], l[2]);
}

Eigen::Vector3d handMap(const Points& posed, const Tets& T, int t, const Eigen::Vector4d& l) {
  Eigen::Vector3d y = Eigen::Vector3d::Zero();
  for (int a = 0; a < 4; ++a) y += l[a] * posed.row(T(t, a)).transpose();
  return y;
}

// A smooth non-affine deformation (bend about y plus a twist), so tets deform differently.
Points bend(const Points& V) {
  Points P(V.rows(), 3);
  for (Eigen::Index v = 0; v < V.rows(); ++v) {
    const Eigen::Vector3d x = V.row(v).transpose();
    const double a = 0.01 * x.z(), b = 0.004 * x.z();
    const Eigen::Matrix3d R = (Eigen::AngleAxisd(a, Eigen::Vector3d::UnitY()) * Eigen::AngleAxisd(b, Eigen::Vector3d::UnitZ()))
                                  .toRotationMatrix();
    P.row(v) = (R * x + Eigen::Vector3d(0.02 * x.z() * x.z(), 0, 0)).transpose();
  }
  return P;
}

std::vector<float> pose(const repose::Binding& b, const Tets& T, const Points& posedNodes) {
  const repose::NodeBinding nb = repose::makeNodeBinding(b, T);
  std::vector<float> out(3 * b.tet.size());
  repose::applyBinding(nb, posedNodes.data(), std::size_t(posedNodes.rows()), out.data());
  return out;
}

std::string tempPath(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("repose_test_" + std::to_string(::getpid()) + "_" + name)).string();
}

}  // namespace

TEST(MeshPosing, InsideVerticesFollowTheBarycentricMapByHand) {
  Points V;
  Tets T;
  jitteredBox({6, 5, 9}, V, T);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.02, 0.98);
  Points P(3000, 3);
  for (int p = 0; p < P.rows(); ++p)
    P.row(p) << -20 + 50 * u(rng), -10 + 25 * u(rng), 60 * u(rng);
  const repose::TetLocator locator(V, T);
  const repose::Binding b = repose::bindPoints(locator, P);
  EXPECT_EQ(b.outsideCount, 0u);
  const Points posed = bend(V);
  const std::vector<float> got = pose(b, T, posed);
  for (int p = 0; p < P.rows(); ++p) {
    const Eigen::Vector3d x = P.row(p).transpose();
    // By hand: the containing tet by brute force, its barycentric map applied to the posed nodes.
    int containing = -1;
    for (int t = 0; t < T.rows() && containing < 0; ++t)
      if (handBarycentric(V, T, t, x).minCoeff() >= -1e-9) containing = t;
    ASSERT_GE(containing, 0);
    const Eigen::Vector3d expected = handMap(posed, T, containing, handBarycentric(V, T, containing, x));
    for (int a = 0; a < 3; ++a) ASSERT_NEAR(got[3 * p + a], expected[a], 2e-4) << "vertex " << p;
  }
  // The same binding again (threading must not change it).
  const repose::Binding again = repose::bindPoints(locator, P);
  EXPECT_EQ(again.tet, b.tet);
}

TEST(MeshPosing, OutsideVertexUsesTheNearestTetAndMovesRigidly) {
  Points V;
  Tets T;
  jitteredBox({5, 4, 8}, V, T);
  const repose::TetLocator locator(V, T);
  // Near a face, near an edge, near a corner, far away (beyond the locator's grid) on every side.
  Points P(7, 3);
  P << 5, 2, -3, 33, 18, 30, -25, -14, -4, 400, 3, 30, -300, -250, 90, 10, 5, 700, 0, 0, -1000;
  const repose::Binding b = repose::bindPoints(locator, P);
  EXPECT_EQ(b.outsideCount, 7u);
  // Brute-force nearest distance over all tets.
  for (int p = 0; p < P.rows(); ++p) {
    const Eigen::Vector3d x = P.row(p).transpose();
    double brute = 1e300;
    for (int t = 0; t < T.rows(); ++t) brute = std::min(brute, locator.distanceToTet(t, x));
    const double d = locator.distanceToTet(b.tet[std::size_t(p)], x);
    EXPECT_GE(d, brute - 1e-9) << p;
    EXPECT_LE(d, 1.05 * brute + 1e-6) << p;
    // Extrapolated barycentric coordinates of the nearest tet, as solved by hand.
    const Eigen::Vector4d l = handBarycentric(V, T, b.tet[std::size_t(p)], x);
    EXPECT_LT((l.cast<float>().transpose() - b.bary.row(p)).cwiseAbs().maxCoeff(), 1e-4 * (1 + l.cwiseAbs().maxCoeff()));
    EXPECT_LT(l.minCoeff(), 0) << "an outside vertex has a negative barycentric coordinate";
  }
  // Unposed: every vertex stays where it was. Rigidly moved mesh: every vertex moves rigidly with it.
  std::vector<float> same = pose(b, T, V);
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.7, Eigen::Vector3d(0.3, -1, 0.5).normalized()).toRotationMatrix();
  const Eigen::RowVector3d t(12, -40, 7);
  const Points moved = (V * R.transpose()).rowwise() + t;
  const std::vector<float> got = pose(b, T, moved);
  for (int p = 0; p < P.rows(); ++p) {
    const Eigen::Vector3d x = P.row(p).transpose();
    const Eigen::Vector3d expected = R * x + t.transpose();
    const double tol = 2e-6 * (1 + x.norm()) * 100;  // float weights, coordinates up to 1000 mm
    for (int a = 0; a < 3; ++a) {
      EXPECT_NEAR(same[3 * std::size_t(p) + a], x[a], tol) << p;
      EXPECT_NEAR(got[3 * std::size_t(p) + a], expected[a], tol) << p;
    }
  }
}

// Near the box and far beyond the locator's grid: the tet found is within 5 % of the nearest distance.
TEST(MeshPosing, NearestAgreesWithBruteForceEverywhere) {
  Points V;
  Tets T;
  jitteredBox({4, 4, 6}, V, T, 9);
  const repose::TetLocator locator(V, T);
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int p = 0; p < 400; ++p) {
    const double scale = p < 200 ? 60 : 2000;  // near the box and far beyond its grid
    const Eigen::Vector3d x(5 + scale * u(rng), 2.5 + scale * u(rng), 30 + scale * u(rng));
    double brute = 1e300;
    for (int t = 0; t < T.rows(); ++t) brute = std::min(brute, locator.distanceToTet(t, x));
    const repose::TetLocator::Hit hit = locator.findNearest(x);
    ASSERT_GE(hit.tet, 0);
    EXPECT_GE(hit.distance, brute - 1e-9) << p;
    EXPECT_LE(hit.distance, 1.05 * brute + 1e-6) << p;
    EXPECT_LT((locator.barycentric(hit.tet, x) - hit.bary).norm(), 1e-12) << p;
    EXPECT_NEAR(hit.bary.sum(), 1.0, 1e-9) << p;
  }
}

TEST(MeshPosing, BindingCacheRoundTripAndInvalidation) {
  Points V;
  Tets T;
  jitteredBox({3, 3, 4}, V, T);
  Points P(50, 3);
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(-30, 70);
  for (int p = 0; p < P.rows(); ++p) P.row(p) << u(rng), u(rng), u(rng);
  const repose::Binding b = repose::bindPoints(V, T, P);
  const std::uint64_t ph = repose::contentHash(P.data(), std::size_t(P.size()) * sizeof(double));
  const std::uint64_t mh = repose::contentHash(V.data(), std::size_t(V.size()) * sizeof(double));
  const std::string path = tempPath("binding.bin");
  const std::size_t nV = std::size_t(V.rows()), nT = std::size_t(T.rows()), nP = std::size_t(P.rows());
  repose::writeBindingCache(path, b, ph, mh, nV, nT);
  repose::Binding r;
  ASSERT_TRUE(repose::readBindingCache(path, ph, mh, nP, nV, nT, r));
  EXPECT_EQ(r.tet, b.tet);
  EXPECT_EQ(r.bary, b.bary);
  EXPECT_EQ(r.outsideCount, b.outsideCount);
  EXPECT_EQ(std::filesystem::file_size(path), 64 + nP * 20);  // header + int32 tet + 4 float weights
  // Another mesh, other points, another count: not used.
  repose::Binding unused;
  EXPECT_FALSE(repose::readBindingCache(path, ph, mh + 1, nP, nV, nT, unused));
  EXPECT_FALSE(repose::readBindingCache(path, ph + 1, mh, nP, nV, nT, unused));
  EXPECT_FALSE(repose::readBindingCache(path, ph, mh, nP, nV, nT + 1, unused));
  EXPECT_FALSE(repose::readBindingCache(path + ".missing", ph, mh, nP, nV, nT, unused));
  EXPECT_TRUE(unused.tet.empty());
  // A truncated file is not used.
  std::filesystem::resize_file(path, std::filesystem::file_size(path) - 4);
  EXPECT_FALSE(repose::readBindingCache(path, ph, mh, nP, nV, nT, unused));
  std::remove(path.c_str());
  // The key changes with any coordinate.
  Points Q = P;
  Q(17, 1) = std::nextafter(Q(17, 1), 1e9);
  EXPECT_NE(repose::contentHash(Q.data(), std::size_t(Q.size()) * sizeof(double)), ph);
  EXPECT_THROW(repose::writeBindingCache("/nonexistent-dir/b.bin", b, ph, mh, nV, nT), std::runtime_error);
}
