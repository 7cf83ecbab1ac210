#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "resample_pull.h"
#include "tet_boundary.h"
#include "box_tet_mesh.h"
#include "tet_mesh.h"

namespace {

using repose::ImageGrid;
using repose::Points;
using repose::Tets;

void boxMesh(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, const std::array<int, 3>& n, Points& V,
             Tets& T) {
  kuhnBoxMesh(lo, hi, n, V, T);
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

// Mesh whose nodes span voxel centres 1..dims-2: the grid minus its outer voxel layer, like the peeled
// body mask the real meshes are built from.
void peeledMesh(const ImageGrid& g, Points& V, Tets& T, int cellsPerAxis = 5) {
  boxMesh(Eigen::Vector3d(1, 1, 1), Eigen::Vector3d(g.dims[0] - 2, g.dims[1] - 2, g.dims[2] - 2),
          {cellsPerAxis, cellsPerAxis + 1, cellsPerAxis - 1}, V, T);
  for (Eigen::Index v = 0; v < V.rows(); ++v) V.row(v) = g.indexToPhysical(V.row(v).transpose()).transpose();
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
// A linear ramp of the rest index (exact under trilinear sampling) as a volume on g.
double ramp(const Eigen::Vector3d& r) { return 2.0 * r[0] - 3.0 * r[1] + 0.5 * r[2] + 7.0; }
repose::IntensityVolume rampVolume(const ImageGrid& g) {
  repose::IntensityVolume F;
  F.grid = g;
  F.data.resize(g.voxelCount());
  for (int k = 0; k < g.dims[2]; ++k)
    for (int j = 0; j < g.dims[1]; ++j)
      for (int i = 0; i < g.dims[0]; ++i) F.at(i, j, k) = float(ramp(Eigen::Vector3d(i, j, k)));
  return F;
}

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
  const repose::IntensityVolume F = rampVolume(g);
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

TEST(TetBoundary, BoxFacesAreExactlyTheSurfaceTriangles) {
  Points V;
  Tets T;
  const std::array<int, 3> n{3, 4, 5};
  boxMesh(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(3, 4, 5), n, V, T);
  const repose::TetBoundary B = repose::tetBoundary(T);
  ASSERT_EQ(B.boundaryFaceMask.size(), std::size_t(T.rows()));
  // Each unit square of the surface is split into two triangles.
  EXPECT_EQ(B.boundaryFaces, std::size_t(4 * (n[0] * n[1] + n[1] * n[2] + n[0] * n[2])));
  std::size_t onSurface = 0, tetsWithFace = 0;
  for (Eigen::Index t = 0; t < T.rows(); ++t) {
    tetsWithFace += B.boundaryFaceMask[t] != 0;
    for (int a = 0; a < 4; ++a) {
      // A face lies on the surface iff its three nodes share a coordinate at the box's min or max.
      bool surface = false;
      for (int c = 0; c < 3; ++c)
        for (double plane : {0.0, double(n[c])}) {
          bool all = true;
          for (int b = 0; b < 4; ++b)
            if (b != a) all = all && V(T(t, b), c) == plane;
          surface = surface || all;
        }
      onSurface += surface;
      EXPECT_EQ(bool((B.boundaryFaceMask[t] >> a) & 1), surface) << "tet " << t << " face " << a;
    }
  }
  EXPECT_EQ(onSurface, B.boundaryFaces);
  EXPECT_EQ(B.boundaryTets, tetsWithFace);
  // A tet touches the boundary iff one of its nodes lies on the box's surface.
  ASSERT_EQ(B.touchesBoundary.size(), std::size_t(T.rows()));
  std::size_t touching = 0;
  for (Eigen::Index t = 0; t < T.rows(); ++t) {
    bool any = false;
    for (int a = 0; a < 4; ++a)
      for (int c = 0; c < 3; ++c) any = any || V(T(t, a), c) == 0.0 || V(T(t, a), c) == double(n[c]);
    EXPECT_EQ(bool(B.touchesBoundary[std::size_t(t)]), any) << "tet " << t;
    touching += any;
  }
  EXPECT_GT(touching, B.boundaryTets);  // also tets with only an edge or a node on the surface
  EXPECT_LT(touching, std::size_t(T.rows()));
  Tets bad = T;
  bad(0, 0) = -1;
  EXPECT_THROW(repose::tetBoundary(bad), std::invalid_argument);
}

TEST(ResamplePull, ExtrapolationRestoresPeeledOuterLayerAtIdentity) {
  const ImageGrid g = testGrid();
  const repose::LabelVolume L = blockLabels(g);
  repose::IntensityVolume F;
  F.grid = g;
  F.data.resize(g.voxelCount());
  for (std::size_t v = 0; v < F.data.size(); ++v) F.data[v] = float(std::sin(0.37 * double(v)) * 100.0);
  Points V;
  Tets T;
  peeledMesh(g, V, T);
  const repose::TetBoundary B = repose::tetBoundary(T);
  repose::PullResampleReport rep;
  // Without extrapolation only the inner (dims - 2)^3 block is covered: the outer layer is lost.
  const repose::LabelVolume plain = repose::resampleLabelsPull(L, V, V, T, g, -1, &rep);
  const std::size_t inner = std::size_t(g.dims[0] - 2) * (g.dims[1] - 2) * (g.dims[2] - 2);
  EXPECT_EQ(rep.coveredVoxels, inner);
  EXPECT_EQ(rep.extrapolatedVoxels, 0u);
  EXPECT_EQ(plain.at(0, 5, 5), -1);
  repose::PullResampleOptions opt;
  opt.boundary = &B;
  const repose::LabelVolume O = repose::resampleLabelsPull(L, V, V, T, g, opt, -1, &rep);
  EXPECT_EQ(rep.coveredVoxels, inner);
  EXPECT_EQ(rep.extrapolatedVoxels, g.voxelCount() - inner);
  EXPECT_EQ(O.data, L.data);
  // The rest coverage is the inner block; sampling only outside it still restores the layer.
  const repose::MaskVolume C = repose::restMeshCoverage(g, V, T);
  std::size_t coveredAtRest = 0;
  for (const auto c : C.data) coveredAtRest += c;
  EXPECT_EQ(coveredAtRest, inner);
  opt.restCoverage = &C;
  EXPECT_EQ(repose::resampleLabelsPull(L, V, V, T, g, opt, -1, &rep).data, L.data);
  const repose::IntensityVolume G = repose::resampleIntensityPull(F, V, V, T, g, opt, -1000.f, &rep);
  EXPECT_EQ(rep.extrapolatedVoxels, g.voxelCount() - inner);
  for (std::size_t v = 0; v < F.data.size(); ++v) ASSERT_NEAR(G.data[v], F.data[v], 1e-3) << v;
  // Distance 0 turns the extension off.
  opt.extrapolationDistance = 0;
  const repose::LabelVolume off = repose::resampleLabelsPull(L, V, V, T, g, opt, -1, &rep);
  EXPECT_EQ(rep.extrapolatedVoxels, 0u);
  EXPECT_EQ(off.data, plain.data);
  // A boundary of another mesh is rejected.
  const repose::TetBoundary other = repose::tetBoundary(T.topRows(T.rows() - 1));
  opt.boundary = &other;
  EXPECT_THROW(repose::resampleLabelsPull(L, V, V, T, g, opt), std::invalid_argument);
}

TEST(ResamplePull, ExtrapolationMatchesRigidOracleIncludingOuterLayer) {
  const ImageGrid g = testGrid();
  const repose::LabelVolume L = blockLabels(g);
  Points V;
  Tets T;
  peeledMesh(g, V, T);
  const repose::TetBoundary B = repose::tetBoundary(T);
  const Rigid m = testMotion();
  const Points P = moved(V, m);
  const ImageGrid out = repose::posedOutputGrid(g, P, 4);
  repose::PullResampleOptions opt;
  opt.boundary = &B;
  repose::PullResampleReport rep;
  const repose::LabelVolume O = repose::resampleLabelsPull(L, V, P, T, out, opt, -7, &rep);
  std::size_t mismatches = 0, inside = 0, nearBoundary = 0, outerLayer = 0;
  for (int k = 0; k < out.dims[2]; ++k)
    for (int j = 0; j < out.dims[1]; ++j)
      for (int i = 0; i < out.dims[0]; ++i) {
        const Eigen::Vector3d x = m.R.transpose() * (out.indexToPhysical(Eigen::Vector3d(i, j, k)) - m.t);
        const Eigen::Vector3d r = g.physicalToIndex(x);
        double margin = 1e300, inner = 1e300;
        for (int a = 0; a < 3; ++a) {
          margin = std::min({margin, r[a] + 0.5, g.dims[a] - 0.5 - r[a]});
          inner = std::min({inner, r[a] - 1.0, g.dims[a] - 2.0 - r[a]});
        }
        if (std::abs(margin) < 1e-6) ++nearBoundary;
        const bool in = margin > 0;
        inside += in;
        outerLayer += in && inner < 0;
        const int expected = in ? nearestRest(L, x) : -7;
        mismatches += O.at(i, j, k) != expected;
      }
  EXPECT_GT(outerLayer, inside / 5);  // the test is about the outer layer
  EXPECT_LE(mismatches, out.voxelCount() / 10000 + nearBoundary);
  const std::size_t written = rep.coveredVoxels + rep.extrapolatedVoxels;
  EXPECT_LE(std::max(written, inside) - std::min(written, inside), nearBoundary + out.voxelCount() / 10000);
}

TEST(ResamplePull, ExtrapolationFollowsAnAffinePoseAndStaysConnectedToTheBody) {
  // A labelled grid meshed only from voxel centre 3 to dims - 4 (three layers peeled), posed by a
  // shear and stretch: every tet has the same affine map, so each extrapolated voxel must hold the
  // nearest rest label at the inverse image of its centre, and be reached from a covered voxel through
  // written voxels.
  const ImageGrid g = testGrid();
  const repose::LabelVolume L = blockLabels(g);
  Points V;
  Tets T;
  boxMesh(Eigen::Vector3d(3, 3, 3), Eigen::Vector3d(g.dims[0] - 4, g.dims[1] - 4, g.dims[2] - 4), {5, 6, 4}, V, T);
  for (Eigen::Index v = 0; v < V.rows(); ++v) V.row(v) = g.indexToPhysical(V.row(v).transpose()).transpose();
  if (g.direction.determinant() < 0) T.col(2).swap(T.col(3));
  Eigen::Matrix3d A;
  A << 1.3, 0.2, 0.0, 0.0, 0.9, 0.15, 0.1, 0.0, 1.1;
  const Eigen::Vector3d c(2.0, -1.0, 35.0);
  Points P(V.rows(), 3);
  for (Eigen::Index v = 0; v < V.rows(); ++v) P.row(v) = (A * (V.row(v).transpose() - c) + c).transpose();
  const ImageGrid out = repose::posedOutputGrid(g, P, 6);
  const repose::TetBoundary B = repose::tetBoundary(T);
  repose::PullResampleOptions opt;
  opt.boundary = &B;
  repose::PullResampleReport rep, plainRep;
  const repose::LabelVolume O = repose::resampleLabelsPull(L, V, P, T, out, opt, 0, &rep);
  const repose::LabelVolume covered = repose::resampleLabelsPull(L, V, P, T, out, 0, &plainRep);
  EXPECT_EQ(rep.coveredVoxels, plainRep.coveredVoxels);
  ASSERT_GT(rep.extrapolatedVoxels, rep.coveredVoxels / 10);
  const Eigen::Matrix3d Ainv = A.inverse();
  std::size_t written = 0, mismatches = 0;
  std::vector<std::uint8_t> reached(out.voxelCount(), 0);
  std::vector<std::size_t> queue;
  for (std::size_t v = 0; v < O.data.size(); ++v) {
    if (O.data[v] == 0) continue;
    ++written;
    const int i = int(v % std::size_t(out.dims[0])), j = int(v / std::size_t(out.dims[0]) % std::size_t(out.dims[1])),
              k = int(v / (std::size_t(out.dims[0]) * std::size_t(out.dims[1])));
    const Eigen::Vector3d x = Ainv * (out.indexToPhysical(Eigen::Vector3d(i, j, k)) - c) + c;
    mismatches += O.data[v] != nearestRest(L, x);
    if (covered.data[v] != 0) {
      EXPECT_EQ(O.data[v], covered.data[v]);  // extrapolation never overwrites a covered voxel
      reached[v] = 1;
      queue.push_back(v);
    }
  }
  // Nearest-label ties on voxel borders may go either way.
  EXPECT_LE(mismatches, written / 200);
  const std::size_t sx = 1, sy = std::size_t(out.dims[0]), sz = sy * std::size_t(out.dims[1]);
  for (std::size_t q = 0; q < queue.size(); ++q) {
    const std::size_t v = queue[q];
    for (const std::size_t w : {v - sx, v + sx, v - sy, v + sy, v - sz, v + sz})
      if (w < O.data.size() && !reached[w] && O.data[w] != 0) {
        reached[w] = 1;
        queue.push_back(w);
      }
  }
  EXPECT_EQ(queue.size(), written);  // no extrapolated voxel is detached from the body
}

TEST(ResamplePull, ExtrapolationNeverPaintsBackground) {
  // Two boxes with a background gap (i = 11, 12) between them at rest.
  ImageGrid g;
  g.dims = {24, 10, 10};
  g.origin = {5, -3, 2};
  repose::LabelVolume L;
  L.grid = g;
  L.data.assign(g.voxelCount(), 0);
  for (int k = 0; k < 10; ++k)
    for (int j = 0; j < 10; ++j)
      for (int i = 0; i < 24; ++i) L.at(i, j, k) = i <= 10 ? 3 : i >= 13 ? 5 : 0;
  // Peeled meshes of both boxes; A's tets come first, so A's extension would win any contest.
  Points VA, VB;
  Tets TA, TB;
  boxMesh(Eigen::Vector3d(1, 1, 1), Eigen::Vector3d(9, 8, 8), {4, 3, 3}, VA, TA);
  boxMesh(Eigen::Vector3d(14, 1, 1), Eigen::Vector3d(22, 8, 8), {4, 3, 3}, VB, TB);
  Points V(VA.rows() + VB.rows(), 3);
  V << VA, VB;
  Tets T(TA.rows() + TB.rows(), 4);
  T << TA, (TB.array() + int(VA.rows())).matrix();
  for (Eigen::Index v = 0; v < V.rows(); ++v) V.row(v) = g.indexToPhysical(V.row(v).transpose()).transpose();
  const repose::TetBoundary B = repose::tetBoundary(T);
  repose::PullResampleOptions opt;
  opt.boundary = &B;  // d = 2 voxels: the extensions overlap across the gap
  repose::PullResampleReport rep;
  const repose::LabelVolume O = repose::resampleLabelsPull(L, V, V, T, g, opt, 0, &rep);
  EXPECT_EQ(O.data, L.data);
  std::size_t nonzero = 0;
  for (const auto v : L.data) nonzero += v != 0;
  EXPECT_EQ(rep.coveredVoxels + rep.extrapolatedVoxels, nonzero);  // no background written by the extension
  // Move A by +2 voxels along i: its extension now reaches i = 13, where it samples the rest gap
  // (background) and must leave the voxel to B's extension.
  Points P = V;
  for (Eigen::Index v = 0; v < VA.rows(); ++v) P.row(v) += 2.0 * g.direction.col(0).transpose();
  const repose::LabelVolume Q = repose::resampleLabelsPull(L, V, P, T, g, opt, 0, &rep);
  for (int k = 0; k < 10; ++k)
    for (int j = 0; j < 10; ++j)
      for (int i = 0; i < 24; ++i)
        ASSERT_EQ(Q.at(i, j, k), i < 2 ? 0 : i <= 12 ? 3 : 5) << i << " " << j << " " << k;
}

TEST(ResamplePull, RestCoverageKeepsExtensionsOutOfNeighbourInteriors) {
  // An "arm" B resting against a "torso" A (labels touch, meshes peeled apart), then moved away by 10,
  // far enough that the voxels next to A are extrapolated from A alone.
  ImageGrid g;
  g.dims = {44, 8, 8};
  repose::LabelVolume L;
  L.grid = g;
  L.data.assign(g.voxelCount(), 0);
  for (int k = 0; k < 8; ++k)
    for (int j = 0; j < 8; ++j)
      for (int i = 0; i < 44; ++i) L.at(i, j, k) = i <= 10 ? 3 : i <= 26 ? 5 : 0;
  Points VA, VB;
  Tets TA, TB;
  boxMesh(Eigen::Vector3d(1, 1, 1), Eigen::Vector3d(9, 6, 6), {4, 3, 3}, VA, TA);
  boxMesh(Eigen::Vector3d(12, 1, 1), Eigen::Vector3d(25, 6, 6), {6, 3, 3}, VB, TB);
  Points V(VA.rows() + VB.rows(), 3);
  V << VA, VB;
  Tets T(TA.rows() + TB.rows(), 4);
  T << TA, (TB.array() + int(VA.rows())).matrix();
  Points P = V;
  P.bottomRows(VB.rows()).col(0).array() += 10.0;
  const repose::TetBoundary B = repose::tetBoundary(T);
  const repose::MaskVolume C = repose::restMeshCoverage(g, V, T);
  repose::PullResampleOptions opt;
  opt.boundary = &B;
  opt.extrapolationDistance = 6.0;  // reaches 6 voxels: across the contact deep into the other part
  const repose::LabelVolume without = repose::resampleLabelsPull(L, V, P, T, g, opt, 0);
  opt.restCoverage = &C;
  const repose::LabelVolume with = repose::resampleLabelsPull(L, V, P, T, g, opt, 0);
  for (int k = 2; k <= 5; ++k)
    for (int j = 2; j <= 5; ++j) {
      // Posed i = 14: A's extrapolation samples rest i = 14, deep inside B (which has moved away).
      EXPECT_EQ(without.at(14, j, k), 5);
      EXPECT_NE(with.at(14, j, k), 5) << j << " " << k;
      EXPECT_EQ(with.at(10, j, k), 3);  // A's own skin layer is still restored
      EXPECT_EQ(with.at(21, j, k), 5);  // and B's on both sides, moved along with B
      EXPECT_EQ(with.at(36, j, k), 5);
      EXPECT_EQ(with.at(37, j, k), 0);  // rest background beyond B stays background
    }
  repose::MaskVolume wrong = C;
  wrong.data.pop_back();
  opt.restCoverage = &wrong;
  EXPECT_THROW(repose::resampleLabelsPull(L, V, P, T, g, opt, 0), std::invalid_argument);
}

TEST(ResamplePull, RestDistanceGivesEachSideOfACutItsOwnHalf) {
  // A "hand" B pressed against a "thigh" A, their tissue welded at rest (labels 3 | 7 7 7 7 | 5: the
  // cut of four voxels between the meshes is tissue 7), then moved apart by 12 voxels. Each mesh's
  // extrapolation may take back its own side of the cut; without the rest distances both take it
  // all and the cut's tissue is doubled.
  ImageGrid g;
  g.dims = {48, 8, 8};
  repose::LabelVolume L;
  L.grid = g;
  L.data.assign(g.voxelCount(), 0);
  for (int k = 0; k < 8; ++k)
    for (int j = 0; j < 8; ++j)
      for (int i = 0; i < 48; ++i) L.at(i, j, k) = i <= 10 ? 3 : i <= 14 ? 7 : i <= 30 ? 5 : 0;
  Points VA, VB;
  Tets TA, TB;
  boxMesh(Eigen::Vector3d(1, 1, 1), Eigen::Vector3d(10.5, 6, 6), {4, 3, 3}, VA, TA);
  boxMesh(Eigen::Vector3d(14.5, 1, 1), Eigen::Vector3d(29, 6, 6), {6, 3, 3}, VB, TB);
  Points V(VA.rows() + VB.rows(), 3);
  V << VA, VB;
  Tets T(TA.rows() + TB.rows(), 4);
  T << TA, (TB.array() + int(VA.rows())).matrix();
  Points P = V;
  P.bottomRows(VB.rows()).col(0).array() += 12.0;
  const repose::TetBoundary B = repose::tetBoundary(T);
  const repose::MaskVolume C = repose::restMeshCoverage(g, V, T);
  const repose::MaskVolume D = repose::restMeshDistance(C);
  EXPECT_EQ(D.at(5, 3, 3), 0);    // covered
  EXPECT_EQ(D.at(11, 3, 3), 4);   // one voxel from A's last covered voxel (10), in quarters
  EXPECT_EQ(D.at(12, 3, 3), 8);   // two from A's and from B's first (15)
  EXPECT_EQ(D.at(14, 3, 3), 4);
  repose::PullResampleOptions opt;
  opt.boundary = &B;
  opt.extrapolationDistance = 5.0;  // reaches across the whole cut
  opt.restCoverage = &C;
  auto layer = [&](const repose::LabelVolume& O) {
    std::size_t n = 0;
    for (int i = 0; i < 48; ++i) n += O.at(i, 3, 3) == 7;
    return n;
  };
  const repose::LabelVolume both = repose::resampleLabelsPull(L, V, P, T, g, opt, 0);
  opt.restDistance = &D;
  const repose::LabelVolume own = repose::resampleLabelsPull(L, V, P, T, g, opt, 0);
  EXPECT_GT(layer(both), 5u);  // the doubled cut: A's and B's copies
  EXPECT_EQ(layer(own), 4u);   // two voxels each side, as at rest
  for (int i = 11; i <= 12; ++i) EXPECT_EQ(own.at(i, 3, 3), 7) << i;   // A's half, in place
  for (int i = 25; i <= 26; ++i) EXPECT_EQ(own.at(i, 3, 3), 7) << i;   // B's half, moved with B
  EXPECT_EQ(own.at(13, 3, 3), 0);
  EXPECT_EQ(own.at(24, 3, 3), 0);
  repose::MaskVolume wrong = D;
  wrong.data.pop_back();
  opt.restDistance = &wrong;
  EXPECT_THROW(repose::resampleLabelsPull(L, V, P, T, g, opt, 0), std::invalid_argument);
}

TEST(ResamplePull, SubExtentEqualsThatPartOfTheFullResample) {
  // Rigidly moved peeled mesh with extrapolation and rest coverage, so the sub-extent must reproduce
  // the extension's clean-up (dropped fragments, filled pinholes) at its borders too.
  const ImageGrid g = testGrid();
  const repose::LabelVolume L = blockLabels(g);
  repose::IntensityVolume F;
  F.grid = g;
  F.data.resize(g.voxelCount());
  for (std::size_t v = 0; v < F.data.size(); ++v) F.data[v] = float(std::sin(0.37 * double(v)) * 100.0);
  Points V;
  Tets T;
  peeledMesh(g, V, T, 6);
  const repose::TetBoundary B = repose::tetBoundary(T);
  const repose::MaskVolume C = repose::restMeshCoverage(g, V, T);
  const Points P = moved(V, testMotion());
  const ImageGrid out = repose::posedOutputGrid(g, P, 3);
  repose::PullResampleOptions opt;
  opt.boundary = &B;
  opt.restCoverage = &C;
  repose::PullResampleReport fullRep;
  const repose::LabelVolume full = repose::resampleLabelsPull(L, V, P, T, out, opt, -3, &fullRep);
  const repose::IntensityVolume fullF = repose::resampleIntensityPull(F, V, P, T, out, opt, -50.f);
  ASSERT_GT(fullRep.extrapolatedVoxels, 0u);
  const int nx = out.dims[0], ny = out.dims[1], nz = out.dims[2];
  const std::array<int, 6> extents[] = {
      {0, nx - 1, 0, ny - 1, nz / 2, nz / 2},              // one axial slice
      {nx / 3, nx / 3, 0, ny - 1, 0, nz - 1},              // one sagittal slice
      {4, nx - 7, ny / 2 - 3, ny / 2 + 4, 5, nz - 9},      // an interior block
      {0, 2, 0, ny - 1, nz - 3, nz - 1},                   // a corner block
      {0, nx - 1, 0, ny - 1, 0, nz - 1}};                  // everything
  for (const auto& e : extents) {
    repose::PullResampleOptions sub = opt;
    sub.outputExtent = e;
    repose::PullResampleReport rep;
    const repose::LabelVolume part = repose::resampleLabelsPull(L, V, P, T, out, sub, -3, &rep);
    const repose::IntensityVolume partF = repose::resampleIntensityPull(F, V, P, T, out, sub, -50.f);
    const ImageGrid pg = repose::extentGrid(out, e);
    ASSERT_TRUE(part.grid.sameGridAs(pg));
    EXPECT_LT((pg.origin - out.indexToPhysical(Eigen::Vector3d(e[0], e[2], e[4]))).norm(), 1e-9);
    ASSERT_EQ(part.data.size(), pg.voxelCount());
    EXPECT_EQ(rep.outputVoxels, pg.voxelCount());
    std::size_t covered = 0, mismatches = 0, mismatchesF = 0;
    for (int k = e[4]; k <= e[5]; ++k)
      for (int j = e[2]; j <= e[3]; ++j)
        for (int i = e[0]; i <= e[1]; ++i) {
          const int a = part.at(i - e[0], j - e[2], k - e[4]);
          mismatches += a != full.at(i, j, k);
          mismatchesF += partF.at(i - e[0], j - e[2], k - e[4]) != fullF.at(i, j, k);
          covered += a != -3;
        }
    EXPECT_EQ(mismatches, 0u) << e[0] << " " << e[1] << " " << e[2] << " " << e[3] << " " << e[4] << " " << e[5];
    EXPECT_EQ(mismatchesF, 0u);
    EXPECT_EQ(rep.coveredVoxels + rep.extrapolatedVoxels, covered);  // block labels are never background
  }
  // Slabs partition the grid: their counts add up to the full resample's.
  std::size_t coveredSum = 0, extrapolatedSum = 0;
  for (int k0 = 0; k0 < nz; k0 += 7) {
    repose::PullResampleOptions sub = opt;
    sub.outputExtent = std::array<int, 6>{0, nx - 1, 0, ny - 1, k0, std::min(nz - 1, k0 + 6)};
    repose::PullResampleReport rep;
    repose::resampleLabelsPull(L, V, P, T, out, sub, -3, &rep);
    coveredSum += rep.coveredVoxels;
    extrapolatedSum += rep.extrapolatedVoxels;
  }
  EXPECT_EQ(coveredSum, fullRep.coveredVoxels);
  EXPECT_EQ(extrapolatedSum, fullRep.extrapolatedVoxels);
  // Extents outside the grid or empty are rejected.
  for (const std::array<int, 6>& bad : {std::array<int, 6>{0, nx, 0, 0, 0, 0}, std::array<int, 6>{-1, 0, 0, 0, 0, 0},
                                        std::array<int, 6>{3, 2, 0, 0, 0, 0}}) {
    repose::PullResampleOptions sub = opt;
    sub.outputExtent = bad;
    EXPECT_THROW(repose::resampleLabelsPull(L, V, P, T, out, sub, -3), std::invalid_argument);
  }
}

// The posed grid: on the rest lattice; holding the rest extent while the body stays near it, the
// body alone (with its own margin) once it has travelled away; a voxel limit with a readable error.
TEST(PosedOutputGrid, BoundedToTheBodyOnTheRestLattice) {
  const ImageGrid g = testGrid();
  Points V;
  Tets T;
  peeledMesh(g, V, T);
  auto onLattice = [&](const ImageGrid& out) {
    const Eigen::Vector3d first = g.physicalToIndex(out.origin);
    return (first - first.array().round().matrix()).norm() < 1e-9 && out.spacing == g.spacing &&
           out.direction == g.direction;
  };
  // In place: the rest extent plus the padding.
  const ImageGrid inPlace = repose::posedOutputGrid(g, V, 2);
  EXPECT_TRUE(onLattice(inPlace));
  EXPECT_EQ(inPlace.dims, (std::array<int, 3>{g.dims[0] + 4, g.dims[1] + 4, g.dims[2] + 4}));
  // Moved far (a walk): the body's box, with bodyPaddingVoxels, not the rest extent and the walk.
  Points far = V;
  far.col(1).array() += 5000.0;  // along i (the direction swaps i and j)
  repose::PosedGridOptions options;
  options.paddingVoxels = 2;
  options.bodyPaddingVoxels = 5;
  const ImageGrid walked = repose::posedOutputGrid(g, far, options);
  EXPECT_TRUE(onLattice(walked));
  EXPECT_EQ(walked.dims, (std::array<int, 3>{g.dims[0] - 2 + 10, g.dims[1] - 2 + 10, g.dims[2] - 2 + 10}));
  EXPECT_LT(walked.voxelCount(), 2 * inPlace.voxelCount());
  // Its voxel centres hold the moved body exactly where the rest voxels' centres moved to.
  const Eigen::Vector3d shifted = walked.physicalToIndex(g.indexToPhysical(Eigen::Vector3d(1, 1, 1)) +
                                                         Eigen::Vector3d(0, 5000, 0));
  EXPECT_LT((shifted - Eigen::Vector3d(5, 5, 5)).norm(), 1e-9);
  // A small move keeps the rest extent (same voxel indices for unmoved anatomy) ...
  Points near = V;
  near.col(1).array() += 4.0;
  const ImageGrid nudged = repose::posedOutputGrid(g, near, options);
  EXPECT_EQ(nudged.origin, inPlace.origin);
  // ... unless restExtentFactor 0 asks for the body alone.
  options.restExtentFactor = 0;
  EXPECT_EQ(repose::posedOutputGrid(g, V, options).dims,
            (std::array<int, 3>{g.dims[0] - 2 + 10, g.dims[1] - 2 + 10, g.dims[2] - 2 + 10}));
  // The limit: a one-line error with the size and the body's span.
  options.maxVoxels = 1000;
  try {
    repose::posedOutputGrid(g, far, options);
    ADD_FAILURE() << "expected the voxel limit to be enforced";
  } catch (const std::invalid_argument& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("would have 38760 voxels (38 x 34 x 30 of 0.8 mm), more than the limit of 1000 voxels"),
              std::string::npos)
        << message;
    EXPECT_NE(message.find("the posed body spans 27 x 29 x 15 mm"), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos);
  }
  options.maxVoxels = double(walked.voxelCount());
  options.restExtentFactor = 2;
  EXPECT_NO_THROW(repose::posedOutputGrid(g, far, options));
  EXPECT_EQ(repose::extrapolationReachVoxels(g, -1), 4 + 2);  // 2 x 1.25 mm over 0.8 mm, + 2
  EXPECT_EQ(repose::extrapolationReachVoxels(g, 0), 0);
}

// The displacement field of an affine pose is known everywhere the map reaches: u(x) = A^-1 (x - c) + c - x,
// covered and extrapolated voxels alike; elsewhere 0. Sampling the rest image through it (trilinear, as
// a warp filter would) gives the posed image the pull wrote.
TEST(ResamplePull, DisplacementFieldIsTheMapTheIntensityPullSamplesThrough) {
  const ImageGrid g = testGrid();
  const repose::IntensityVolume F = rampVolume(g);
  Points V;
  Tets T;
  peeledMesh(g, V, T);
  Eigen::Matrix3d A;
  A << 1.3, 0.2, 0.0, 0.0, 0.9, 0.15, 0.1, 0.0, 1.1;
  const Eigen::Vector3d c(2.0, -1.0, 35.0);
  Points P(V.rows(), 3);
  for (Eigen::Index v = 0; v < V.rows(); ++v) P.row(v) = (A * (V.row(v).transpose() - c) + c).transpose();
  const ImageGrid out = repose::posedOutputGrid(g, P, 4);
  const repose::TetBoundary B = repose::tetBoundary(T);
  repose::PullResampleOptions opt;
  opt.boundary = &B;
  repose::PullResampleReport rep;
  const float background = -999.f;
  const repose::IntensityVolume O = repose::resampleIntensityPull(F, V, P, T, out, opt, background, &rep);
  std::vector<float> u(3 * out.voxelCount(), 7.f);
  repose::displacementPullInto(g, V, P, T, out, opt, u.data());
  ASSERT_GT(rep.extrapolatedVoxels, 0u);
  const Eigen::Matrix3d Ainv = A.inverse();
  std::size_t mapped = 0, zero = 0;
  double worstMap = 0, worstSample = 0;
  for (int k = 0; k < out.dims[2]; ++k)
    for (int j = 0; j < out.dims[1]; ++j)
      for (int i = 0; i < out.dims[0]; ++i) {
        const std::size_t v = out.linearIndex(i, j, k);
        const Eigen::Vector3d x = out.indexToPhysical(Eigen::Vector3d(i, j, k));
        const Eigen::Vector3d d(u[3 * v], u[3 * v + 1], u[3 * v + 2]);
        if (O.data[v] == background) {
          // Not reached (or reached outside the rest grid, where the image is background too).
          zero += d.isZero();
          continue;
        }
        ++mapped;
        worstMap = std::max(worstMap, (d - (Ainv * (x - c) + c - x)).norm());
        // The ramp is linear: trilinear sampling at the field's rest point is exact (edge voxels
        // replicated within half a voxel of the grid, as the pull samples).
        Eigen::Vector3d r = g.physicalToIndex(x + d);
        for (int a = 0; a < 3; ++a) r[a] = std::min(std::max(r[a], 0.0), double(g.dims[a] - 1));
        worstSample = std::max(worstSample, std::abs(double(O.data[v]) - ramp(r)));
      }
  EXPECT_GT(mapped, g.voxelCount() / 2);
  EXPECT_GT(zero, 0u);
  EXPECT_LT(worstMap, 2e-3) << "mm, float positions";    // pinholes (mean of neighbours) are exact for an affine map
  EXPECT_LT(worstSample, 2e-2) << "ramp units";
}
