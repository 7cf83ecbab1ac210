// Volumetrization: body mask, outer-layer peel, TetGen tetrahedralization, bone tagging.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <map>
#include <numeric>
#include <random>
#include <cmath>
#include <set>
#include <stdexcept>

#include "body_mask.h"
#include "box_tet_mesh.h"
#include "mesh_ordering.h"
#include "mesh_tagging.h"
#include "tet_mesher.h"

using namespace repose;

namespace {

ImageGrid makeGrid(int nx, int ny, int nz) {
  ImageGrid g;
  g.dims = {nx, ny, nz};
  g.origin = {5, -3, 12};
  g.spacing = {1.0, 1.5, 2.0};
  g.direction << -1, 0, 0, 0, -1, 0, 0, 0, 1;
  return g;
}

LabelVolume makeLabels(const ImageGrid& g) {
  LabelVolume v;
  v.grid = g;
  v.data.assign(g.voxelCount(), 0);
  return v;
}

std::size_t countOnes(const MaskVolume& m) {
  std::size_t n = 0;
  for (auto x : m.data) n += x ? 1 : 0;
  return n;
}

// Closed axis-aligned box surface: 8 points, 12 outward triangles.
void addBox(Points& V, Triangles& F, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  const int base = int(V.rows());
  V.conservativeResize(base + 8, 3);
  for (int c = 0; c < 8; ++c)
    V.row(base + c) << ((c & 1) ? hi.x() : lo.x()), ((c & 2) ? hi.y() : lo.y()), ((c & 4) ? hi.z() : lo.z());
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  const int f0 = int(F.rows());
  F.conservativeResize(f0 + 12, 3);
  for (int q = 0; q < 6; ++q) {
    F.row(f0 + 2 * q) << base + quads[q][0], base + quads[q][1], base + quads[q][2];
    F.row(f0 + 2 * q + 1) << base + quads[q][0], base + quads[q][2], base + quads[q][3];
  }
}

void expectPositive(const TetMesh& m) {
  for (Eigen::Index t = 0; t < m.tets.rows(); ++t)
    ASSERT_GT(tetVolume(m.nodes.row(m.tets(t, 0)), m.nodes.row(m.tets(t, 1)), m.nodes.row(m.tets(t, 2)),
                        m.nodes.row(m.tets(t, 3))),
              0.0)
        << "tet " << t;
}

bool hasNode(const TetMesh& m, const Eigen::Vector3d& p, double tol = 1e-9) {
  for (Eigen::Index v = 0; v < m.nodes.rows(); ++v)
    if ((m.nodes.row(v).transpose() - p).norm() < tol) return true;
  return false;
}

/// The box from lo to hi with each face split into n x n squares of two triangles: many coplanar
/// facets, whose shared edges TetGen's constrained Delaunay stage splits.
void latticeBox(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, int n, Points& V, Triangles& F) {
  std::map<std::array<int, 3>, int> index;
  std::vector<Eigen::Vector3d> points;
  auto vertex = [&](const std::array<int, 3>& ijk) {
    auto inserted = index.emplace(ijk, int(points.size()));
    if (inserted.second)
      points.push_back(lo + Eigen::Vector3d(ijk[0], ijk[1], ijk[2]).cwiseProduct(hi - lo) / n);
    return inserted.first->second;
  };
  std::vector<Eigen::RowVector3i> triangles;
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side <= 1; ++side)
      for (int a = 0; a < n; ++a)
        for (int b = 0; b < n; ++b) {
          int q[4];
          const int da[4] = {0, 1, 1, 0}, db[4] = {0, 0, 1, 1};
          for (int c = 0; c < 4; ++c) {
            std::array<int, 3> ijk;
            ijk[axis] = side * n;
            ijk[(axis + 1) % 3] = a + da[c];
            ijk[(axis + 2) % 3] = b + db[c];
            q[c] = vertex(ijk);
          }
          if (side == 0) std::swap(q[1], q[3]);  // outward
          triangles.emplace_back(q[0], q[1], q[2]);
          triangles.emplace_back(q[0], q[2], q[3]);
        }
  V.resize(Eigen::Index(points.size()), 3);
  for (std::size_t i = 0; i < points.size(); ++i) V.row(Eigen::Index(i)) = points[i].transpose();
  F.resize(Eigen::Index(triangles.size()), 3);
  for (std::size_t i = 0; i < triangles.size(); ++i) F.row(Eigen::Index(i)) = triangles[i];
}

}  // namespace

TEST(BodyMask, HollowBallIsFilled) {
  const auto g = makeGrid(24, 24, 24);
  auto labels = makeLabels(g);
  std::size_t shell = 0, ball = 0;
  for (int k = 0; k < 24; ++k)
    for (int j = 0; j < 24; ++j)
      for (int i = 0; i < 24; ++i) {
        const double r = std::sqrt((i - 11.5) * (i - 11.5) + (j - 11.5) * (j - 11.5) + (k - 11.5) * (k - 11.5));
        if (r <= 9) ++ball;
        if (r <= 9 && r > 6) {
          labels.at(i, j, k) = 3;
          ++shell;
        }
      }
  const auto mask = bodyMask(labels, nullptr, {});
  EXPECT_EQ(countOnes(mask), ball);
  EXPECT_TRUE(mask.grid.sameGridAs(g));
  BodyMaskOptions noFill;
  noFill.fillHoles = false;
  EXPECT_EQ(countOnes(bodyMask(labels, nullptr, noFill)), shell);
}

TEST(BodyMask, SliceFillClosesCavityOpenAlongK) {
  // A tube along k, open at both ends: no 3-D hole, but each k-slice has a hole.
  const auto g = makeGrid(12, 12, 8);
  auto labels = makeLabels(g);
  for (int k = 0; k < 8; ++k)
    for (int j = 2; j < 10; ++j)
      for (int i = 2; i < 10; ++i)
        if (i == 2 || i == 9 || j == 2 || j == 9) labels.at(i, j, k) = 1;
  EXPECT_EQ(countOnes(bodyMask(labels, nullptr, {})), std::size_t(8 * 8 * 8));
}

TEST(BodyMask, KeepsLargestComponent) {
  const auto g = makeGrid(20, 10, 10);
  auto labels = makeLabels(g);
  for (int k = 2; k < 6; ++k)
    for (int j = 2; j < 6; ++j) {
      for (int i = 1; i < 4; ++i) labels.at(i, j, k) = 5;   // 48 voxels
      for (int i = 6; i < 14; ++i) labels.at(i, j, k) = 7;  // 128 voxels
    }
  labels.at(18, 8, 8) = 2;  // diagonal-free single voxel
  const auto mask = bodyMask(labels, nullptr, {});
  EXPECT_EQ(countOnes(mask), std::size_t(128));
  EXPECT_EQ(mask.at(6, 2, 2), 1);
  EXPECT_EQ(mask.at(1, 2, 2), 0);
  BodyMaskOptions all;
  all.keepLargestComponent = false;
  EXPECT_EQ(countOnes(bodyMask(labels, nullptr, all)), std::size_t(48 + 128 + 1));
}

TEST(BodyMask, UnitesCtAboveThreshold) {
  const auto g = makeGrid(16, 8, 8);
  auto labels = makeLabels(g);
  IntensityVolume ct;
  ct.grid = g;
  ct.data.assign(g.voxelCount(), -1000.f);
  for (int k = 2; k < 6; ++k)
    for (int j = 2; j < 6; ++j) {
      for (int i = 2; i < 6; ++i) labels.at(i, j, k) = 1;
      for (int i = 6; i < 10; ++i) ct.at(i, j, k) = 40.f;     // soft tissue, unlabelled
      for (int i = 10; i < 12; ++i) ct.at(i, j, k) = -600.f;  // below threshold
    }
  BodyMaskOptions opt;
  opt.bodyThreshold = -500;
  const auto mask = bodyMask(labels, &ct, opt);
  EXPECT_EQ(countOnes(mask), std::size_t(8 * 4 * 4));
  EXPECT_EQ(mask.at(9, 3, 3), 1);
  EXPECT_EQ(mask.at(10, 3, 3), 0);
  opt.bodyThreshold = -700;
  EXPECT_EQ(countOnes(bodyMask(labels, &ct, opt)), std::size_t(10 * 4 * 4));
}

TEST(BodyMask, BadInputThrows) {
  const auto g = makeGrid(8, 8, 8);
  auto labels = makeLabels(g);
  EXPECT_THROW(bodyMask(labels, nullptr, {}), std::invalid_argument);  // empty
  labels.at(3, 3, 3) = 1;
  IntensityVolume ct;
  ct.grid = g;
  ct.grid.spacing.x() = 1.1;
  ct.data.assign(g.voxelCount(), 0.f);
  EXPECT_THROW(bodyMask(labels, &ct, {}), std::invalid_argument);
  ct.grid = g;
  ct.grid.direction = Eigen::Matrix3d::Identity();
  EXPECT_THROW(bodyMask(labels, &ct, {}), std::invalid_argument);
  ct.grid = g;
  ct.data.resize(10);
  EXPECT_THROW(bodyMask(labels, &ct, {}), std::invalid_argument);
  labels.data.resize(5);
  EXPECT_THROW(bodyMask(labels, nullptr, {}), std::invalid_argument);
}

namespace {
// Two 6x6x6 boxes along i starting at i0=2, separated by `gap` voxels.
MaskVolume twoBoxes(int gap) {
  MaskVolume m;
  m.grid = makeGrid(24, 10, 10);
  m.data.assign(m.grid.voxelCount(), 0);
  for (int k = 2; k < 8; ++k)
    for (int j = 2; j < 8; ++j)
      for (int i = 0; i < 6; ++i) {
        m.at(2 + i, j, k) = 1;
        m.at(8 + gap + i, j, k) = 1;
      }
  return m;
}
}  // namespace

TEST(PeelOuterLayer, ErodesOneLayerAndWidensGaps) {
  const auto sep = peelOuterLayer(twoBoxes(1));
  EXPECT_EQ(countOnes(sep), std::size_t(2 * 4 * 4 * 4));
  // The one-voxel gap (i=8) grows to three voxels (i=7..9).
  for (int i = 7; i <= 9; ++i) EXPECT_EQ(sep.at(i, 4, 4), 0) << i;
  EXPECT_EQ(sep.at(6, 4, 4), 1);
  EXPECT_EQ(sep.at(10, 4, 4), 1);
  EXPECT_EQ(sep.at(3, 4, 4), 1);
  EXPECT_EQ(sep.at(2, 4, 4), 0);

  // Touching boxes form one 12x6x6 box: the contact face is interior and stays.
  const auto touching = peelOuterLayer(twoBoxes(0));
  EXPECT_EQ(countOnes(touching), std::size_t(10 * 4 * 4));
  EXPECT_EQ(touching.at(7, 4, 4), 1);
  EXPECT_EQ(touching.at(8, 4, 4), 1);

  // Voxels on the image border are outer layer.
  MaskVolume full;
  full.grid = makeGrid(5, 5, 5);
  full.data.assign(125, 1);
  EXPECT_EQ(countOnes(peelOuterLayer(full)), std::size_t(27));
}

TEST(PeelOuterLayer, BoneVoxelsAreKept) {
  MaskVolume mask = twoBoxes(1);
  LabelVolume labels = makeLabels(mask.grid);
  for (std::size_t v = 0; v < mask.data.size(); ++v) labels.data[v] = mask.data[v] ? 1 : 0;
  labels.at(2, 4, 4) = 7;  // a bone voxel on the first box's outer layer
  labels.at(3, 4, 4) = 7;
  labels.at(9, 4, 4) = 8;  // label 8 is tissue
  MaskVolume peeled = peelOuterLayer(mask);
  ASSERT_EQ(peeled.at(2, 4, 4), 0);
  keepBoneVoxels(peeled, labels, std::vector<int>{-1, -1, -1, -1, -1, -1, -1, 0});
  EXPECT_EQ(peeled.at(2, 4, 4), 1);
  EXPECT_EQ(peeled.at(9, 4, 4), 0);
  EXPECT_EQ(countOnes(peeled), std::size_t(2 * 4 * 4 * 4 + 1));
  LabelVolume other = labels;
  other.grid.dims = {23, 10, 10};
  EXPECT_THROW(keepBoneVoxels(peeled, other, {}), std::invalid_argument);
}

TEST(TetMesher, CubeWithSeeds) {
  Points V(0, 3);
  Triangles F(0, 3);
  addBox(V, F, {-10, -5, 0}, {10, 15, 20});
  Points seeds(3, 3);
  seeds << 0, 5, 10, 2.5, 1.25, 3.75, 7, 9, 11;
  TetMeshingOptions opt;
  TetMeshingReport rep;
  const TetMesh m = tetrahedralizeSurface(V, F, seeds, opt, &rep);
  ASSERT_GT(m.tets.rows(), 0);
  EXPECT_NEAR(meshVolume(m.nodes, m.tets), 8000.0, 8000.0 * 1e-9);
  expectPositive(m);
  for (Eigen::Index s = 0; s < seeds.rows(); ++s) EXPECT_TRUE(hasNode(m, seeds.row(s).transpose())) << s;
  for (Eigen::Index v = 0; v < V.rows(); ++v) EXPECT_TRUE(hasNode(m, V.row(v).transpose())) << v;
  EXPECT_EQ(rep.nodes, m.nodes.rows());
  EXPECT_EQ(rep.tets, m.tets.rows());
  EXPECT_EQ(rep.seedPoints, 3);
  EXPECT_TRUE(m.fixedBone.empty());
  // Every node is used by a tet.
  std::vector<int> used(std::size_t(m.nodes.rows()), 0);
  for (Eigen::Index t = 0; t < m.tets.rows(); ++t)
    for (int c = 0; c < 4; ++c) used[m.tets(t, c)] = 1;
  for (int u : used) EXPECT_EQ(u, 1);
  // Inside-the-box nodes only.
  EXPECT_GE(m.nodes.col(0).minCoeff(), -10 - 1e-9);
  EXPECT_LE(m.nodes.col(2).maxCoeff(), 20 + 1e-9);
}

// The default keeps the surface: the mesh's boundary faces are the input triangles, unsplit, and
// quality refinement adds interior points only. Allowing splitting refines the boundary as well.
TEST(TetMesher, SurfaceKeptUnlessSplittingIsAllowed) {
  Points V(0, 3);
  Triangles F(0, 3);
  addBox(V, F, {0, 0, 0}, {40, 10, 10});  // long faces: bad tets next to them
  auto boundaryFaces = [](const TetMesh& m) {
    std::map<std::array<int, 3>, int> count;
    const int faces[4][3] = {{0, 1, 2}, {0, 1, 3}, {0, 2, 3}, {1, 2, 3}};
    for (Eigen::Index t = 0; t < m.tets.rows(); ++t)
      for (const auto& f : faces) {
        std::array<int, 3> key{m.tets(t, f[0]), m.tets(t, f[1]), m.tets(t, f[2])};
        std::sort(key.begin(), key.end());
        ++count[key];
      }
    int boundary = 0;
    for (const auto& [key, n] : count) boundary += n == 1;
    return boundary;
  };
  TetMeshingOptions opt;
  opt.radiusEdgeRatio = 1.2;
  TetMeshingReport kept;
  const TetMesh m = tetrahedralizeSurface(V, F, Points(0, 3), opt, &kept);
  EXPECT_TRUE(kept.surfacePreserved);
  EXPECT_TRUE(kept.preserveFailure.empty());
  EXPECT_EQ(boundaryFaces(m), F.rows());
  EXPECT_NEAR(meshVolume(m.nodes, m.tets), 4000.0, 4000.0 * 1e-9);
  expectPositive(m);

  opt.preserveSurface = false;
  TetMeshingReport split;
  const TetMesh s = tetrahedralizeSurface(V, F, Points(0, 3), opt, &split);
  EXPECT_FALSE(split.surfacePreserved);
  EXPECT_GT(boundaryFaces(s), F.rows());
  EXPECT_NEAR(meshVolume(s.nodes, s.tets), 4000.0, 4000.0 * 1e-9);
}

TEST(TetMesher, VolumeBoundAndOutsideSeedsIgnored) {
  Points V(0, 3);
  Triangles F(0, 3);
  addBox(V, F, {0, 0, 0}, {10, 10, 10});
  Points seeds(2, 3);
  seeds << 5, 5, 5, 50, 50, 50;  // the second is outside: ignored
  TetMeshingOptions opt;
  opt.maxTetVolume = 2.0;
  const TetMesh m = tetrahedralizeSurface(V, F, seeds, opt);
  EXPECT_NEAR(meshVolume(m.nodes, m.tets), 1000.0, 1e-6);
  EXPECT_GE(m.tets.rows(), 500);
  for (Eigen::Index t = 0; t < m.tets.rows(); ++t)
    EXPECT_LE(tetVolume(m.nodes.row(m.tets(t, 0)), m.nodes.row(m.tets(t, 1)), m.nodes.row(m.tets(t, 2)),
                        m.nodes.row(m.tets(t, 3))),
              2.0 + 1e-9);
  EXPECT_TRUE(hasNode(m, Eigen::Vector3d(5, 5, 5)));
  EXPECT_FALSE(hasNode(m, Eigen::Vector3d(50, 50, 50)));
  EXPECT_LE(m.nodes.maxCoeff(), 10 + 1e-9);
  expectPositive(m);
}

TEST(TetMesher, TwoDisjointCubes) {
  Points V(0, 3);
  Triangles F(0, 3);
  addBox(V, F, {0, 0, 0}, {4, 4, 4});
  addBox(V, F, {10, 0, 0}, {13, 3, 3});
  // Reversed orientation of the second shell must not matter.
  for (Eigen::Index f = 12; f < 24; ++f) std::swap(F(f, 1), F(f, 2));
  const TetMesh m = tetrahedralizeSurface(V, F, Points(0, 3), {});
  EXPECT_NEAR(meshVolume(m.nodes, m.tets), 64.0 + 27.0, 91.0 * 1e-9);
  expectPositive(m);
  // No tet spans the gap between the cubes.
  for (Eigen::Index t = 0; t < m.tets.rows(); ++t) {
    std::set<bool> side;
    for (int c = 0; c < 4; ++c) side.insert(m.nodes(m.tets(t, c), 0) > 7);
    EXPECT_EQ(side.size(), 1u);
  }
  // keepBoneComponents drops the cube without a bone node.
  TetMesh tagged = m;
  tagged.fixedBone.assign(std::size_t(m.nodes.rows()), -1);
  tagged.tetLabel.assign(std::size_t(m.tets.rows()), 0);
  for (Eigen::Index v = 0; v < m.nodes.rows(); ++v)
    if (m.nodes(v, 0) > 7) {
      tagged.fixedBone[v] = 2;
      break;
    }
  const auto rep = keepBoneComponents(tagged);
  EXPECT_EQ(rep.componentsKept, 1);
  EXPECT_EQ(rep.componentsDropped, 1);
  EXPECT_NEAR(meshVolume(tagged.nodes, tagged.tets), 27.0, 1e-9);
  EXPECT_EQ(rep.nodesDropped + tagged.nodes.rows(), m.nodes.rows());
  EXPECT_EQ(rep.tetsDropped + tagged.tets.rows(), m.tets.rows());
  EXPECT_EQ(tagged.tetLabel.size(), std::size_t(tagged.tets.rows()));
  EXPECT_EQ(std::count(tagged.fixedBone.begin(), tagged.fixedBone.end(), 2), 1);
  EXPECT_GT(tagged.nodes.col(0).minCoeff(), 7);
  // No bone node at all: nothing to keep.
  TetMesh none = m;
  none.fixedBone.assign(std::size_t(m.nodes.rows()), -1);
  EXPECT_THROW(keepBoneComponents(none), std::invalid_argument);
}

// The surface kept (-Y) while the constrained Delaunay stage splits segments: TetGen then needs the
// index of each split segment, which it records only when told to; without it this surface read
// uninitialised memory and crashed, typically after another run in the same process.
TEST(TetMesher, LatticeBoxMeshedRepeatedlyInOneProcess) {
  Points V;
  Triangles F;
  latticeBox({0, 0, 0}, {28, 10, 10}, 12, V, F);
  ASSERT_EQ(F.rows(), 6 * 12 * 12 * 2);
  Points seeds(8, 3);
  for (int s = 0; s < 8; ++s) seeds.row(s) << 3 + 3 * s, 5, 5;
  TetMesh first;
  for (int run = 0; run < 8; ++run) {
    TetMeshingReport rep;
    const TetMesh m = tetrahedralizeSurface(V, F, seeds, TetMeshingOptions{}, &rep);
    EXPECT_TRUE(rep.surfacePreserved) << rep.preserveFailure;
    ASSERT_GT(m.tets.rows(), 0);
    expectPositive(m);
    EXPECT_NEAR(meshVolume(m.nodes, m.tets), 28.0 * 10 * 10, 1e-9 * 2800);
    EXPECT_GE(m.nodes.minCoeff(), -1e-9);
    EXPECT_LE(m.nodes.col(0).maxCoeff(), 28 + 1e-9);
    EXPECT_LE(m.nodes.rightCols(2).maxCoeff(), 10 + 1e-9);
    if (run == 0) {
      for (Eigen::Index v = 0; v < V.rows(); ++v) EXPECT_TRUE(hasNode(m, V.row(v).transpose())) << v;
      first = m;
    } else {  // the same input gives the same mesh
      EXPECT_EQ(m.nodes, first.nodes);
      EXPECT_EQ(m.tets, first.tets);
    }
  }
}

TEST(TetMesher, BadSurfaceThrows) {
  Points V(0, 3);
  Triangles F(0, 3);
  addBox(V, F, {0, 0, 0}, {1, 1, 1});
  Triangles open = F.topRows(11);
  EXPECT_THROW(tetrahedralizeSurface(V, open, Points(0, 3), {}), std::invalid_argument);
  Triangles bad = F;
  bad(0, 0) = 99;
  EXPECT_THROW(tetrahedralizeSurface(V, bad, Points(0, 3), {}), std::invalid_argument);
  TetMeshingOptions q;
  q.radiusEdgeRatio = 0.9;
  EXPECT_THROW(tetrahedralizeSurface(V, F, Points(0, 3), q), std::invalid_argument);
  // Two boxes overlapping: the surface intersects itself; TetGen's error becomes a message.
  Points V2 = V;
  Triangles F2 = F;
  addBox(V2, F2, {0.5, 0.25, 0.25}, {1.5, 0.75, 0.75});
  try {
    tetrahedralizeSurface(V2, F2, Points(0, 3), {});
    ADD_FAILURE() << "self-intersecting surface accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("tet mesher"), std::string::npos);
  }
}

TEST(MeshTagging, TwoBoneVolume) {
  // Bone labels 20 (bone 0) and 21 (bone 1) inside soft tissue 3.
  auto g = makeGrid(20, 8, 8);
  auto labels = makeLabels(g);
  for (int k = 1; k < 7; ++k)
    for (int j = 1; j < 7; ++j)
      for (int i = 1; i < 19; ++i) labels.at(i, j, k) = 3;
  for (int k = 2; k < 6; ++k)
    for (int j = 2; j < 6; ++j) {
      for (int i = 2; i < 8; ++i) labels.at(i, j, k) = 20;
      for (int i = 12; i < 18; ++i) labels.at(i, j, k) = 21;
    }
  std::vector<int> boneOfLabel(22, -1);
  boneOfLabel[20] = 0;
  boneOfLabel[21] = 1;
  MaskVolume mask;
  mask.grid = g;
  mask.data.assign(g.voxelCount(), 1);

  const Points seeds = boneSeedPoints(labels, boneOfLabel, mask, 2, 2);
  ASSERT_GT(seeds.rows(), 0);
  int perBone[2] = {0, 0};
  for (Eigen::Index s = 0; s < seeds.rows(); ++s) {
    const Eigen::Vector3d f = g.physicalToIndex(seeds.row(s).transpose());
    const Eigen::Vector3d r = f.array().round();
    // Voxel centres, or face seeds 0.45 voxel from a bone voxel's centre towards a non-bone face.
    const double off = (f - r).norm();
    EXPECT_TRUE(off < 1e-9 || std::abs(off - 0.45) < 1e-9) << off;
    if (off > 1e-9) {
      const Eigen::Vector3d beyond = (r + (f - r) / 0.45).array().round();
      EXPECT_FALSE(g.contains(int(beyond[0]), int(beyond[1]), int(beyond[2])) &&
                   boneOfLabel[labels.at(int(beyond[0]), int(beyond[1]), int(beyond[2]))] ==
                       boneOfLabel[labels.at(int(r[0]), int(r[1]), int(r[2]))]);
    }
    const int l = labels.at(int(r[0]), int(r[1]), int(r[2]));
    ASSERT_TRUE(l == 20 || l == 21) << l;
    ++perBone[boneOfLabel[l]];
  }
  EXPECT_GT(perBone[0], 4);
  EXPECT_EQ(perBone[0], perBone[1]);  // the bones are copies translated by 5 lattice blocks
  // Masked-out voxels give no seeds.
  MaskVolume half = mask;
  for (int k = 0; k < 8; ++k)
    for (int j = 0; j < 8; ++j)
      for (int i = 10; i < 20; ++i) half.at(i, j, k) = 0;
  const Points seedsHalf = boneSeedPoints(labels, boneOfLabel, half, 2, 2);
  for (Eigen::Index s = 0; s < seedsHalf.rows(); ++s) EXPECT_LT(g.physicalToIndex(seedsHalf.row(s).transpose())[0], 9.5);
  EXPECT_THROW(boneSeedPoints(labels, boneOfLabel, mask, 0, 2), std::invalid_argument);

  // Tag a hand-made mesh: nodes at known voxels (slightly off-centre), tets with known centroids.
  TetMesh mesh;
  mesh.nodes.resize(6, 3);
  const double ijk[6][3] = {{3.2, 3, 3}, {14.4, 4, 4}, {10, 3, 3}, {0.3, 0, 0}, {25, 3, 3}, {7.4, 2, 5}};
  for (int v = 0; v < 6; ++v) mesh.nodes.row(v) = g.indexToPhysical(Eigen::Vector3d(ijk[v][0], ijk[v][1], ijk[v][2])).transpose();
  mesh.tets.resize(2, 4);
  mesh.tets << 0, 5, 2, 3, 1, 2, 4, 0;
  tagMesh(mesh, labels, boneOfLabel);
  ASSERT_EQ(mesh.fixedBone.size(), 6u);
  EXPECT_EQ(mesh.fixedBone[0], 0);
  EXPECT_EQ(mesh.fixedBone[1], 1);
  EXPECT_EQ(mesh.fixedBone[2], -1);
  EXPECT_EQ(mesh.fixedBone[3], -1);  // background
  EXPECT_EQ(mesh.fixedBone[4], -1);  // outside the grid: clamped to i=19, background
  ASSERT_EQ(mesh.tetLabel.size(), 2u);
  // Centroid of tet 0: i=(3.2+7.4+10+0.3)/4=5.225, j=2, k=2.75 -> voxel (5,2,3): bone label 20.
  EXPECT_EQ(mesh.tetLabel[0], 20);
  // Tet 1: i=(14.4+10+25+3.2)/4=13.15, j=k=3.25 -> voxel (13,3,3): label 21.
  EXPECT_EQ(mesh.tetLabel[1], 21);
}

TEST(MeshOrdering, MortonRenumberingKeepsTheMesh) {
  // A jittered grid of cubes split into 6 tets, numbered in a scrambled order.
  const int n = 6;
  TetMesh mesh;
  mesh.nodes.resize((n + 1) * (n + 1) * (n + 1), 3);
  auto id = [&](int i, int j, int k) { return (k * (n + 1) + j) * (n + 1) + i; };
  for (int k = 0; k <= n; ++k)
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) mesh.nodes.row(id(i, j, k)) << i + 0.1 * std::sin(i * j + k), j, k;
  std::vector<Eigen::Vector4i> tets;
  const int cube[6][4] = {{0, 1, 3, 7}, {0, 1, 7, 5}, {0, 5, 7, 4}, {0, 3, 2, 7}, {0, 2, 6, 7}, {0, 6, 4, 7}};
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        int c[8];
        for (int b = 0; b < 8; ++b) c[b] = id(i + (b & 1), j + ((b >> 1) & 1), k + ((b >> 2) & 1));
        for (const auto& t : cube) tets.emplace_back(c[t[0]], c[t[1]], c[t[2]], c[t[3]]);
      }
  // Scatter tets and nodes, as TetGen's creation order does.
  std::mt19937 rng(7);
  std::shuffle(tets.begin(), tets.end(), rng);
  std::vector<int> perm(std::size_t(mesh.nodes.rows()));
  std::iota(perm.begin(), perm.end(), 0);
  std::shuffle(perm.begin(), perm.end(), rng);
  const Points ordered = mesh.nodes;
  for (std::size_t v = 0; v < perm.size(); ++v) mesh.nodes.row(perm[v]) = ordered.row(Eigen::Index(v));
  for (auto& t : tets)
    for (int k = 0; k < 4; ++k) t[k] = perm[std::size_t(t[k])];
  mesh.tets.resize(Eigen::Index(tets.size()), 4);
  for (std::size_t t = 0; t < tets.size(); ++t) {
    mesh.tets.row(Eigen::Index(t)) = tets[t].transpose();
    if (tetVolume(mesh.nodes.row(tets[t][0]), mesh.nodes.row(tets[t][1]), mesh.nodes.row(tets[t][2]),
                  mesh.nodes.row(tets[t][3])) < 0)
      std::swap(mesh.tets(Eigen::Index(t), 2), mesh.tets(Eigen::Index(t), 3));
  }
  mesh.fixedBone.resize(std::size_t(mesh.nodes.rows()));
  for (std::size_t v = 0; v < mesh.fixedBone.size(); ++v) mesh.fixedBone[v] = int(v % 3) - 1;
  mesh.tetLabel.resize(std::size_t(mesh.tets.rows()));
  for (std::size_t t = 0; t < mesh.tetLabel.size(); ++t) mesh.tetLabel[t] = int(t % 5);

  const TetMesh before = mesh;
  const std::vector<int> newIndex = reorderMeshSpatially(mesh);
  ASSERT_EQ(mesh.nodes.rows(), before.nodes.rows());
  ASSERT_EQ(mesh.tets.rows(), before.tets.rows());
  EXPECT_NEAR(meshVolume(mesh.nodes, mesh.tets), meshVolume(before.nodes, before.tets), 1e-9);
  std::vector<int> seen(newIndex.size(), 0);
  for (std::size_t old = 0; old < newIndex.size(); ++old) {
    ++seen[std::size_t(newIndex[old])];
    EXPECT_EQ((mesh.nodes.row(newIndex[old]) - before.nodes.row(Eigen::Index(old))).norm(), 0.0);
    EXPECT_EQ(mesh.fixedBone[std::size_t(newIndex[old])], before.fixedBone[old]);
  }
  for (int s : seen) EXPECT_EQ(s, 1);
  // The same set of tets (as sorted node tuples, with their labels), all still positive.
  auto key = [](const Eigen::Vector4i& t, int label) {
    std::array<int, 5> k{t[0], t[1], t[2], t[3], label};
    std::sort(k.begin(), k.begin() + 4);
    return k;
  };
  std::vector<std::array<int, 5>> a, b;
  for (Eigen::Index t = 0; t < mesh.tets.rows(); ++t) {
    a.push_back(key(mesh.tets.row(t).transpose(), mesh.tetLabel[std::size_t(t)]));
    Eigen::Vector4i old = before.tets.row(t).transpose();
    for (int k = 0; k < 4; ++k) old[k] = newIndex[std::size_t(old[k])];
    b.push_back(key(old, before.tetLabel[std::size_t(t)]));
    EXPECT_GT(tetVolume(mesh.nodes.row(mesh.tets(t, 0)), mesh.nodes.row(mesh.tets(t, 1)),
                        mesh.nodes.row(mesh.tets(t, 2)), mesh.nodes.row(mesh.tets(t, 3))), 0);
  }
  std::sort(a.begin(), a.end());
  std::sort(b.begin(), b.end());
  EXPECT_EQ(a, b);
  // Neighbouring tets end up close in memory: the index spread of the tets around a node drops well
  // below that of the scattered order.
  auto spreadOf = [](const TetMesh& m) {
    std::vector<std::vector<int>> tetsOf(std::size_t(m.nodes.rows()));
    for (Eigen::Index t = 0; t < m.tets.rows(); ++t)
      for (int k = 0; k < 4; ++k) tetsOf[std::size_t(m.tets(t, k))].push_back(int(t));
    double sum = 0;
    for (const auto& ts : tetsOf)
      if (!ts.empty()) sum += *std::max_element(ts.begin(), ts.end()) - *std::min_element(ts.begin(), ts.end());
    return sum / double(tetsOf.size());
  };
  EXPECT_LT(spreadOf(mesh), 0.5 * spreadOf(before));
}

TEST(MeshTagging, NoEdgeJoinsTwoBonesAfterFreeingContacts) {
  // A bar of 12 x 2 x 2 cubes: bone 0 is the nodes with i <= 5, bone 1 those with i >= 6, so the
  // cubes between i = 5 and 6 join the two bones; a third bone is one node column that touches
  // bone 1 everywhere.
  Points V;
  Tets T;
  kuhnBoxMesh(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(12, 2, 2), {12, 2, 2}, V, T);
  TetMesh mesh;
  mesh.nodes = V;
  mesh.tets = T;
  mesh.fixedBone.resize(std::size_t(V.rows()));
  for (Eigen::Index v = 0; v < V.rows(); ++v) {
    const double x = V(v, 0);
    mesh.fixedBone[std::size_t(v)] = x <= 5.5 ? 0 : (x < 11.5 ? 1 : 2);
  }
  const auto before = mesh.fixedBone;
  const ContactReport rep = freeBoneContacts(mesh);
  EXPECT_GT(rep.edgesBetweenBones, 0);
  EXPECT_EQ(rep.bonesKept, 1);  // bone 2 would have lost every node: it stays fixed
  int freed = 0;
  for (Eigen::Index v = 0; v < V.rows(); ++v) {
    const double x = V(v, 0);
    const int b = mesh.fixedBone[std::size_t(v)];
    if (x == 5 || x == 6 || x == 11) {
      EXPECT_EQ(b, -1) << "node at x = " << x;
      ++freed;
    } else {
      EXPECT_EQ(b, before[std::size_t(v)]) << "node at x = " << x;  // only contact nodes change
    }
  }
  EXPECT_EQ(rep.nodesFreed, freed);
  // No edge joins bones 0 and 1 any more (bone 2's contact with bone 1 is gone too: its neighbours
  // at x = 11 are free now).
  for (Eigen::Index t = 0; t < T.rows(); ++t)
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) {
        const int ba = mesh.fixedBone[std::size_t(T(t, a))], bb = mesh.fixedBone[std::size_t(T(t, b))];
        EXPECT_FALSE(ba >= 0 && bb >= 0 && ba != bb) << "tet " << t;
      }
  // A second call has nothing left to do.
  const ContactReport again = freeBoneContacts(mesh);
  EXPECT_EQ(again.edgesBetweenBones, 0);
  EXPECT_EQ(again.nodesFreed, 0);
  TetMesh untagged;
  untagged.nodes = V;
  untagged.tets = T;
  EXPECT_THROW(freeBoneContacts(untagged), std::invalid_argument);
}

TEST(BodyMask, EveryPosablePieceIsKeptAndLabelledPiecesAreBridged) {
  // A body with a bone, an "eye" labelled 3 voxels away from it, a 2-voxel speck, and a piece of CT
  // with no label (a table's leg).
  const ImageGrid g = makeGrid(40, 20, 20);
  LabelVolume labels = makeLabels(g);
  MaskVolume mask;
  mask.grid = g;
  mask.data.assign(g.voxelCount(), 0);
  for (int k = 2; k < 18; ++k)
    for (int j = 2; j < 18; ++j)
      for (int i = 2; i < 15; ++i) {
        mask.at(i, j, k) = 1;
        labels.at(i, j, k) = (i > 6 && i < 10 && j > 6 && j < 12) ? 2 : 1;  // soft tissue around a bone
      }
  for (int k = 8; k < 12; ++k)
    for (int j = 8; j < 12; ++j)
      for (int i = 18; i < 22; ++i) mask.at(i, j, k) = 1, labels.at(i, j, k) = 5;  // the eye
  mask.at(30, 3, 3) = mask.at(31, 3, 3) = 1, labels.at(30, 3, 3) = labels.at(31, 3, 3) = 5;  // a speck
  for (int k = 2; k < 8; ++k)
    for (int j = 12; j < 18; ++j)
      for (int i = 30; i < 36; ++i) mask.at(i, j, k) = 1;  // unlabelled
  const PosableComponentsReport r = keepPosableComponents(mask, labels, {-1, -1, 0, -1, -1, -1});
  EXPECT_EQ(r.kept, 1);
  EXPECT_EQ(r.bridged, 1);
  EXPECT_EQ(r.dropped, 2);
  EXPECT_EQ(r.droppedVoxels, 2u + 216u);
  EXPECT_GT(r.bridgeVoxels, 0u);
  EXPECT_EQ(mask.at(20, 10, 10), 1);  // the eye stays, joined to the body across the gap:
  std::vector<std::uint8_t> seen(mask.data.size(), 0);
  std::vector<std::size_t> stack{g.linearIndex(20, 10, 10)};
  seen[stack[0]] = 1;
  while (!stack.empty()) {
    const std::size_t v = stack.back();
    stack.pop_back();
    const int i = int(v % 40), j = int((v / 40) % 20), k = int(v / 800);
    const int n[6][3] = {{i - 1, j, k}, {i + 1, j, k}, {i, j - 1, k}, {i, j + 1, k}, {i, j, k - 1}, {i, j, k + 1}};
    for (const auto& q : n)
      if (g.contains(q[0], q[1], q[2]) && mask.at(q[0], q[1], q[2]) && !seen[g.linearIndex(q[0], q[1], q[2])])
        seen[g.linearIndex(q[0], q[1], q[2])] = 1, stack.push_back(g.linearIndex(q[0], q[1], q[2]));
  }
  EXPECT_TRUE(seen[g.linearIndex(8, 8, 8)]);
  EXPECT_EQ(mask.at(30, 3, 3), 0);
  EXPECT_EQ(mask.at(32, 14, 4), 0);
  // The labels alone leave gaps when no label makes half of their outside.
  EXPECT_FALSE(labelsLeaveGaps(labels));  // soft tissue (1) makes most
  LabelVolume organs = makeLabels(g);
  for (int k = 0; k < 3; ++k) organs.at(k * 10, 5, 5) = organs.at(k * 10 + 1, 5, 5) = 3 + k;  // three organs
  EXPECT_TRUE(labelsLeaveGaps(organs));
  // A thin skin around many tissues, none of them half the body: the skin makes the outside.
  LabelVolume skinned = makeLabels(g);
  for (int k = 2; k < 18; ++k)
    for (int j = 2; j < 18; ++j)
      for (int i = 2; i < 38; ++i) {
        const bool shell = k == 2 || k == 17 || j == 2 || j == 17 || i == 2 || i == 37;
        skinned.at(i, j, k) = shell ? 1 : 2 + i / 6;  // 1 = skin, six tissues inside
      }
  EXPECT_FALSE(labelsLeaveGaps(skinned));
}
