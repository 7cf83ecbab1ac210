#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "resample_pull.h"
#include "tet_mesh.h"

namespace {

using repose::ImageGrid;
using repose::Points;
using repose::Tets;

// Box [lo, hi] split into n cubes per axis, each cut into 6 Kuhn tets (conforming faces), positively oriented.
void boxMesh(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, const std::array<int, 3>& n, Points& V,
             Tets& T) {
  const int sx = n[0] + 1, sy = n[1] + 1, sz = n[2] + 1;
  V.resize(std::size_t(sx) * sy * sz, 3);
  auto id = [&](int i, int j, int k) { return (k * sy + j) * sx + i; };
  for (int k = 0; k < sz; ++k)
    for (int j = 0; j < sy; ++j)
      for (int i = 0; i < sx; ++i) {
        const Eigen::Vector3d f(double(i) / n[0], double(j) / n[1], double(k) / n[2]);
        V.row(id(i, j, k)) = (lo + (hi - lo).cwiseProduct(f)).transpose();
      }
  const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  T.resize(std::size_t(n[0]) * n[1] * n[2] * 6, 4);
  int t = 0;
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i)
        for (const auto& p : perms) {
          int c[3] = {i, j, k};
          int row[4];
          row[0] = id(c[0], c[1], c[2]);
          for (int s = 0; s < 3; ++s) {
            ++c[p[s]];
            row[s + 1] = id(c[0], c[1], c[2]);
          }
          const double vol = repose::tetVolume(V.row(row[0]).transpose(), V.row(row[1]).transpose(),
                                               V.row(row[2]).transpose(), V.row(row[3]).transpose());
          if (vol < 0) std::swap(row[2], row[3]);
          T.row(t++) << row[0], row[1], row[2], row[3];
        }
}

ImageGrid testGrid() {
  ImageGrid g;
  g.dims = {30, 26, 22};
  g.origin = {-12.0, 5.0, 30.0};
  g.spacing = {1.0, 1.25, 0.8};
  // A left-handed direction (axes permuted) to exercise orientation handling.
  g.direction << 0, 1, 0, 1, 0, 0, 0, 0, 1;
  return g;
}

// Mesh covering the rest grid's voxel footprints [-0.5, dims-0.5] in index space.
void gridMesh(const ImageGrid& g, Points& V, Tets& T, int cellsPerAxis = 8) {
  boxMesh(Eigen::Vector3d(-0.5, -0.5, -0.5),
          Eigen::Vector3d(g.dims[0] - 0.5, g.dims[1] - 0.5, g.dims[2] - 0.5),
          {cellsPerAxis, cellsPerAxis + 1, cellsPerAxis - 1}, V, T);
  for (Eigen::Index v = 0; v < V.rows(); ++v) V.row(v) = g.indexToPhysical(V.row(v).transpose()).transpose();
  // A left-handed direction flips orientation: keep tets positive in physical space.
  if (g.direction.determinant() < 0) T.col(2).swap(T.col(3));
}

repose::LabelVolume blockLabels(const ImageGrid& g) {
  repose::LabelVolume L;
  L.grid = g;
  L.data.resize(g.voxelCount());
  for (int k = 0; k < g.dims[2]; ++k)
    for (int j = 0; j < g.dims[1]; ++j)
      for (int i = 0; i < g.dims[0]; ++i) L.at(i, j, k) = 1 + (i / 3 + 3 * (j / 4) + 7 * (k / 5)) % 13;
  return L;
}

// Nearest voxel by the same footprint rule as the resampler; -1 outside.
int nearestRest(const repose::LabelVolume& L, const Eigen::Vector3d& x) {
  const Eigen::Vector3d r = L.grid.physicalToIndex(x);
  int idx[3];
  for (int a = 0; a < 3; ++a) {
    if (!(r[a] >= -0.5 && r[a] < L.grid.dims[a] - 0.5)) return -1;
    idx[a] = int(std::floor(r[a] + 0.5));
  }
  return L.at(idx[0], idx[1], idx[2]);
}

struct Rigid {
  Eigen::Matrix3d R;
  Eigen::Vector3d t;
};
Rigid testMotion() {
  Rigid m;
  m.R = Eigen::AngleAxisd(30.0 * M_PI / 180.0, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  m.t = Eigen::Vector3d(3.3, -7.1, 2.2);
  return m;
}
Points moved(const Points& V, const Rigid& m) {
  Points P(V.rows(), 3);
  for (Eigen::Index v = 0; v < V.rows(); ++v) P.row(v) = (m.R * V.row(v).transpose() + m.t).transpose();
  return P;
}

}  // namespace

TEST(ResamplePull, RigidMotionMatchesDirectNearestSampling) {
  const ImageGrid g = testGrid();
  const repose::LabelVolume L = blockLabels(g);
  Points V, P;
  Tets T;
  gridMesh(g, V, T);
  const Rigid m = testMotion();
  P = moved(V, m);
  const ImageGrid out = repose::posedOutputGrid(g, P, 2);
  repose::PullResampleReport rep;
  const repose::LabelVolume O = repose::resampleLabelsPull(L, V, P, T, out, -7, &rep);
  ASSERT_EQ(O.data.size(), out.voxelCount());
  EXPECT_EQ(rep.outputVoxels, out.voxelCount());
  EXPECT_EQ(rep.invertedTets, 0u);

  std::size_t mismatches = 0, inside = 0, nearBoundary = 0;
  for (int k = 0; k < out.dims[2]; ++k)
    for (int j = 0; j < out.dims[1]; ++j)
      for (int i = 0; i < out.dims[0]; ++i) {
        const Eigen::Vector3d y = out.indexToPhysical(Eigen::Vector3d(i, j, k));
        const Eigen::Vector3d x = m.R.transpose() * (y - m.t);
        const Eigen::Vector3d r = g.physicalToIndex(x);
        // Inside the posed box = rest point inside the footprint box.
        double margin = 1e300;
        for (int a = 0; a < 3; ++a) margin = std::min({margin, r[a] + 0.5, g.dims[a] - 0.5 - r[a]});
        if (std::abs(margin) < 1e-6) ++nearBoundary;
        const bool in = margin > 0;
        inside += in;
        const int expected = in ? nearestRest(L, x) : -7;
        mismatches += (O.at(i, j, k) != (expected < 0 ? -7 : expected));
      }
  EXPECT_GT(inside, g.voxelCount() / 2);
  // No cracks: every output voxel centre inside the posed box is covered.
  EXPECT_LE(std::max(rep.coveredVoxels, inside) - std::min(rep.coveredVoxels, inside), nearBoundary);
  EXPECT_LE(mismatches, out.voxelCount() / 10000 + nearBoundary);
}

TEST(ResamplePull, IdentityPoseReproducesInputOnOriginalLattice) {
  const ImageGrid g = testGrid();
  const repose::LabelVolume L = blockLabels(g);
  repose::IntensityVolume F;
  F.grid = g;
  F.data.resize(g.voxelCount());
  for (std::size_t v = 0; v < F.data.size(); ++v) F.data[v] = float(std::sin(0.37 * double(v)) * 100.0);
  Points V;
  Tets T;
  gridMesh(g, V, T, 5);
  // Same grid as output.
  repose::PullResampleReport rep;
  const repose::LabelVolume O = repose::resampleLabelsPull(L, V, V, T, g, 0, &rep);
  EXPECT_EQ(O.data, L.data);
  EXPECT_EQ(rep.coveredVoxels, g.voxelCount());
  const repose::IntensityVolume G = repose::resampleIntensityPull(F, V, V, T, g, -1000.f, &rep);
  for (std::size_t v = 0; v < F.data.size(); ++v) ASSERT_NEAR(G.data[v], F.data[v], 1e-3) << v;
  // Padded output grid: the original lattice is a sub-lattice of it.
  const ImageGrid out = repose::posedOutputGrid(g, V, 3);
  const repose::LabelVolume Q = repose::resampleLabelsPull(L, V, V, T, out, -1, &rep);
  EXPECT_EQ(rep.coveredVoxels, g.voxelCount());
  const Eigen::Vector3d off = out.physicalToIndex(g.origin);
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(off[a], std::round(off[a]), 1e-9);
  for (int k = 0; k < g.dims[2]; ++k)
    for (int j = 0; j < g.dims[1]; ++j)
      for (int i = 0; i < g.dims[0]; ++i)
        ASSERT_EQ(Q.at(i + int(std::round(off[0])), j + int(std::round(off[1])), k + int(std::round(off[2]))),
                  L.at(i, j, k));
}

TEST(ResamplePull, TrilinearOfLinearRampIsExact) {
  const ImageGrid g = testGrid();
  repose::IntensityVolume F;
  F.grid = g;
  F.data.resize(g.voxelCount());
  auto ramp = [](const Eigen::Vector3d& r) { return 2.0 * r[0] - 3.0 * r[1] + 0.5 * r[2] + 7.0; };
  for (int k = 0; k < g.dims[2]; ++k)
    for (int j = 0; j < g.dims[1]; ++j)
      for (int i = 0; i < g.dims[0]; ++i) F.at(i, j, k) = float(ramp(Eigen::Vector3d(i, j, k)));
  Points V;
  Tets T;
  gridMesh(g, V, T);
  const Rigid m = testMotion();
  const Points P = moved(V, m);
  const ImageGrid out = repose::posedOutputGrid(g, P, 1);
  const repose::IntensityVolume O = repose::resampleIntensityPull(F, V, P, T, out, -999.f);
  std::size_t checked = 0;
  for (int k = 0; k < out.dims[2]; ++k)
    for (int j = 0; j < out.dims[1]; ++j)
      for (int i = 0; i < out.dims[0]; ++i) {
        const Eigen::Vector3d x = m.R.transpose() * (out.indexToPhysical(Eigen::Vector3d(i, j, k)) - m.t);
        const Eigen::Vector3d r = g.physicalToIndex(x);
        bool interior = true, outside = false;
        for (int a = 0; a < 3; ++a) {
          interior = interior && r[a] > 1e-6 && r[a] < g.dims[a] - 1 - 1e-6;
          outside = outside || r[a] < -0.5 - 1e-6 || r[a] > g.dims[a] - 0.5 + 1e-6;
        }
        if (interior) {
          ASSERT_NEAR(O.at(i, j, k), ramp(r), 1e-3);
          ++checked;
        } else if (outside) {
          ASSERT_EQ(O.at(i, j, k), -999.f);
        }
      }
  EXPECT_GT(checked, g.voxelCount() / 2);
}

TEST(ResamplePull, InvertedTetsAreCountedAndSkipped) {
  const ImageGrid g = testGrid();
  const repose::LabelVolume L = blockLabels(g);
  Points V;
  Tets T;
  gridMesh(g, V, T, 4);
  // Mirror: every tet inverted, nothing covered.
  Points M = V;
  M.col(0) = -M.col(0);
  repose::PullResampleReport rep;
  const ImageGrid outM = repose::posedOutputGrid(g, M, 0);
  repose::resampleLabelsPull(L, V, M, T, outM, 0, &rep);
  EXPECT_EQ(rep.invertedTets, std::size_t(T.rows()));
  EXPECT_EQ(rep.coveredVoxels, 0u);
  // Push one interior node through its neighbours: count inverted tets independently.
  Points P = V;
  const int node = (2 * 6 + 2) * 5 + 2;  // interior node (2,2,2) of the 5x6x4-node lattice
  P.row(node) += (V.row(node + 1) - V.row(node)) * 2.5;
  std::size_t expected = 0;
  for (Eigen::Index t = 0; t < T.rows(); ++t)
    expected += repose::tetVolume(P.row(T(t, 0)).transpose(), P.row(T(t, 1)).transpose(), P.row(T(t, 2)).transpose(),
                                  P.row(T(t, 3)).transpose()) <= 0;
  ASSERT_GT(expected, 0u);
  repose::resampleLabelsPull(L, V, P, T, repose::posedOutputGrid(g, P, 1), 0, &rep);
  EXPECT_EQ(rep.invertedTets, expected);
}

TEST(ResamplePull, BadInputThrows) {
  const ImageGrid g = testGrid();
  repose::LabelVolume L = blockLabels(g);
  Points V;
  Tets T;
  gridMesh(g, V, T, 3);
  Points P = V.topRows(V.rows() - 1);
  EXPECT_THROW(repose::resampleLabelsPull(L, V, P, T, g), std::invalid_argument);
  Tets bad = T;
  bad(0, 0) = int(V.rows());
  EXPECT_THROW(repose::resampleLabelsPull(L, V, V, bad, g), std::invalid_argument);
  L.data.pop_back();
  EXPECT_THROW(repose::resampleLabelsPull(L, V, V, T, g), std::invalid_argument);
}
