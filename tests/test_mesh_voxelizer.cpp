// Surface meshes to voxels: analytic volumes, holes, overlapping and nested pieces, mixed windings,
// reflected grids, label priorities.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <stdexcept>

#include "mesh_topology.h"
#include "mesh_voxelizer.h"
#include "parallel_for.h"
#include "triangle_soups.h"

using namespace repose;

namespace {

ImageGrid cube(double lo, double hi, double h) {
  ImageGrid g;
  const int n = int(std::round((hi - lo) / h)) + 1;
  g.dims = {n, n, n};
  g.origin = Eigen::Vector3d::Constant(lo);
  g.spacing = Eigen::Vector3d::Constant(h);
  return g;
}

}  // namespace

TEST(MeshTopology, SphereIsClosedAndOneComponent) {
  const TriangleMesh s = sphere({0, 0, 0}, 10);
  const MeshTopology t = analyzeMeshTopology(s.V, s.F);
  EXPECT_TRUE(t.closed());
  EXPECT_EQ(t.components, 1u);
  EXPECT_NEAR(t.enclosedVolume, 4.0 / 3.0 * M_PI * 1000, 0.01 * 4.0 / 3.0 * M_PI * 1000);
  const TriangleMesh open = cutTop(s, 9.0);
  const MeshTopology to = analyzeMeshTopology(open.V, open.F);
  EXPECT_GT(to.boundaryEdges, 0u);
  EXPECT_FALSE(to.closed());
}

TEST(MeshTopology, SplitsComponentsInFileOrderAndWeldsCoincidentVertices) {
  TriangleMesh two = concat(box({5, 0, 0}, {6, 1, 1}), sphere({0, 0, 0}, 2, 8, 16));
  const auto parts = splitConnectedComponents(two.V, two.F);
  ASSERT_EQ(parts.size(), 2u);
  EXPECT_EQ(parts[0].F.rows(), 12);  // the box came first
  EXPECT_EQ(parts[0].V.rows(), 8);
  EXPECT_DOUBLE_EQ(parts[0].V.col(0).minCoeff(), 5.0);
  EXPECT_EQ(parts[1].F.rows(), two.F.rows() - 12);
  // A soup with one vertex per triangle corner (as STL stores it) is still one closed piece.
  TriangleMesh soup;
  const TriangleMesh b = box({0, 0, 0}, {1, 1, 1});
  soup.V.resize(36, 3);
  soup.F.resize(12, 3);
  for (int t = 0; t < 12; ++t)
    for (int c = 0; c < 3; ++c) {
      soup.V.row(3 * t + c) = b.V.row(b.F(t, c));
      soup.F(t, c) = 3 * t + c;
    }
  EXPECT_EQ(splitConnectedComponents(soup.V, soup.F).size(), 1u);
  EXPECT_TRUE(analyzeMeshTopology(soup.V, soup.F).closed());
  MeshTriangles bad = b.F;
  bad(3, 1) = 8;
  EXPECT_THROW(splitConnectedComponents(b.V, bad), std::invalid_argument);
}

TEST(MeshTopology, HolesPiecesAndBoundaryChain) {
  const double r = 10;
  const TriangleMesh s = sphere({0, 0, 0}, r, 48, 96);
  // A cap cut off at z = 5: one hole, its rim the 96 edges of a ring, closed up by a flat fan.
  const TriangleMesh bowl = cutTop(s, 5.0);
  const MeshTopology t = analyzeMeshTopology(bowl.V, bowl.F);
  EXPECT_EQ(t.holes, 1u);
  EXPECT_EQ(t.boundaryEdges, 96u);
  EXPECT_EQ(boundaryLoops(bowl.V, bowl.F)[0].size(), 96u);
  EXPECT_NEAR(t.largestHole, 2 * std::sqrt(r * r - 25), 0.1);
  const double below = M_PI * (r + 5) * (r + 5) * (2 * r - 5) / 3;  // the ball below z = 5
  EXPECT_NEAR(t.enclosedVolume, below, 0.01 * below);
  const auto chain = boundaryChain(bowl.V, bowl.F);
  ASSERT_EQ(chain.size(), 1u);
  EXPECT_EQ(chain[0].size(), 96u);
  EXPECT_TRUE(boundaryChain(s.V, s.F).empty());
  // Half the sphere inside out: no hole, but its seam (the equator) is boundary twice over.
  TriangleMesh seam = s;
  for (Eigen::Index f = 0; f < seam.F.rows(); ++f)
    if (seam.V(seam.F(f, 0), 2) + seam.V(seam.F(f, 1), 2) + seam.V(seam.F(f, 2), 2) > 0)
      std::swap(seam.F(f, 1), seam.F(f, 2));
  EXPECT_EQ(analyzeMeshTopology(seam.V, seam.F).holes, 0u);
  const auto seams = boundaryChain(seam.V, seam.F);
  ASSERT_EQ(seams.size(), 1u);
  EXPECT_EQ(seams[0].size(), 2u * 96u);
  std::size_t turned = 0;
  const MeshTriangles fixed = consistentlyOriented(seam.V, seam.F, turned);
  EXPECT_EQ(turned, std::size_t(seam.F.rows() / 2));  // from the first triangle, which was reversed
  EXPECT_TRUE(boundaryChain(seam.V, fixed).empty());
  // Two closed boxes stored apart that meet along coincident vertices (as a hip bone's parts do):
  // one component once the vertices are merged, two pieces, non-manifold where they meet.
  const TriangleMesh boxes = concat(box({0, 0, 0}, {1, 1, 1}), box({1, 0, 0}, {2, 1, 1}));
  const MeshTopology b = analyzeMeshTopology(boxes.V, boxes.F);
  EXPECT_EQ(b.components, 1u);
  EXPECT_EQ(b.pieces, 2u);
  EXPECT_GT(b.nonManifoldEdges, 0u);
  EXPECT_EQ(b.holes, 0u);
  EXPECT_TRUE(boundaryChain(boxes.V, boxes.F).empty());
}

TEST(MeshVoxelizer, BoxGivesItsExactVoxels) {
  // Box faces halfway between voxel centres: exactly the 10 x 6 x 4 centres inside.
  const TriangleMesh b = box({-5, -3, -2}, {5, 3, 2});
  const ImageGrid g = cube(-9.5, 9.5, 1.0);
  const MeshVoxelization m = voxelizeMesh(b.V, b.F, g);
  EXPECT_EQ(m.insideVoxels, 10u * 6u * 4u);
  EXPECT_FALSE(m.cutByGrid);
  EXPECT_TRUE(m.at(10, 10, 10));  // centre voxel at (0.5, 0.5, 0.5)
  EXPECT_FALSE(m.at(16, 10, 10));
}

TEST(MeshVoxelizer, SphereVolumeMatchesAnalytic) {
  const double r = 12;
  const TriangleMesh s = sphere({0.3, -0.2, 0.1}, r);
  for (double h : {1.0, 0.5}) {
    const ImageGrid g = cube(-16, 16, h);
    const MeshVoxelization m = voxelizeMesh(s.V, s.F, g);
    const double volume = double(m.insideVoxels) * h * h * h;
    EXPECT_NEAR(volume, 4.0 / 3.0 * M_PI * r * r * r, 0.02 * 4.0 / 3.0 * M_PI * r * r * r) << "h " << h;
  }
}

TEST(MeshVoxelizer, AnisotropicRotatedGrid) {
  const double r = 10;
  const TriangleMesh s = sphere({1, 2, 3}, r);
  ImageGrid g;
  g.dims = {40, 30, 60};
  g.spacing = Eigen::Vector3d(0.7, 1.0, 0.5);
  g.direction = Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 1, 0).normalized()).toRotationMatrix();
  g.origin = Eigen::Vector3d(1, 2, 3) - g.direction * g.spacing.cwiseProduct(Eigen::Vector3d(20, 15, 30));
  const MeshVoxelization m = voxelizeMesh(s.V, s.F, g);
  EXPECT_NEAR(double(m.insideVoxels) * g.spacing.prod(), 4.0 / 3.0 * M_PI * r * r * r, 0.03 * 4.0 / 3.0 * M_PI * r * r * r);
  // Every inside voxel centre is inside the sphere (within a voxel).
  for (int k = 0; k < 60; ++k)
    for (int j = 0; j < 30; ++j)
      for (int i = 0; i < 40; ++i)
        if (m.at(i, j, k)) EXPECT_LT((g.indexToPhysical(Eigen::Vector3d(i, j, k)) - Eigen::Vector3d(1, 2, 3)).norm(), r + 0.1);
}

TEST(MeshVoxelizer, SelfIntersectingUnionOfTwoSpheres) {
  // Two overlapping closed spheres in one soup: the inside is their union, not their XOR.
  const double r = 8, d = 8;  // centres 8 apart
  const TriangleMesh u = concat(sphere({-d / 2, 0, 0}, r), sphere({d / 2, 0, 0}, r));
  const ImageGrid g = cube(-16, 16, 0.5);
  const MeshVoxelization m = voxelizeMesh(u.V, u.F, g);
  const double cap = M_PI * (r - d / 2) * (r - d / 2) * (3 * r - (r - d / 2)) / 3;  // spherical cap height r-d/2
  const double unionVolume = 2 * (4.0 / 3.0 * M_PI * r * r * r) - 2 * cap;
  EXPECT_NEAR(double(m.insideVoxels) * 0.125, unionVolume, 0.02 * unionVolume);
  EXPECT_TRUE(m.at(32, 32, 32));  // the origin lies in both spheres
}

TEST(MeshVoxelizer, NestedInwardPieceIsACavityInvertedMeshIsSolid) {
  // A hollow ball: outer sphere facing out, inner sphere facing in (as a skull's inner table).
  TriangleMesh inner = sphere({0, 0, 0}, 6, 32, 64);
  inner.F.col(1).swap(inner.F.col(2));
  const TriangleMesh shell = concat(sphere({0, 0, 0}, 10), inner);
  const ImageGrid g = cube(-12, 12, 0.5);
  const MeshVoxelization m = voxelizeMesh(shell.V, shell.F, g);
  const double expected = 4.0 / 3.0 * M_PI * (1000 - 216);
  EXPECT_NEAR(double(m.insideVoxels) * 0.125, expected, 0.03 * expected);
  EXPECT_EQ(m.repairs.cavities, 1u);
  EXPECT_FALSE(m.at(24, 24, 24));  // the centre is in the cavity
  // The whole ball inside out is still a solid ball: orientation only matters between pieces.
  TriangleMesh flipped = sphere({0, 0, 0}, 10);
  flipped.F.col(1).swap(flipped.F.col(2));
  const MeshVoxelization f = voxelizeMesh(flipped.V, flipped.F, g);
  EXPECT_NEAR(double(f.insideVoxels) * 0.125, 4.0 / 3.0 * M_PI * 1000, 0.02 * 4.0 / 3.0 * M_PI * 1000);
  // An inward-facing piece beside (not inside) the ball is kept as a solid, and reported.
  TriangleMesh side = sphere({0, 0, 0}, 1.5, 12, 24);
  side.V.col(0).array() += 12.0;  // centre (12, 0, 0), outside the ball of radius 9 at (-2, 0, 0)
  side.F.col(1).swap(side.F.col(2));
  const TriangleMesh two = concat(sphere({-2, 0, 0}, 9), side);
  const MeshVoxelization t = voxelizeMesh(two.V, two.F, cube(-12, 14, 0.5));
  EXPECT_EQ(t.repairs.invertedPieces, 1u);
  EXPECT_EQ(t.repairs.cavities, 0u);
  EXPECT_TRUE(t.at(48, 26, 26));  // (12, 1, 1) inside the small sphere
}

/// The error voxelizeLabels throws for a lone skin, or "" when it accepts it.
std::string voxelizeError(const TriangleMesh& m, const std::string& file, const ImageGrid& g) {
  try {
    voxelizeLabels({VoxelizePart{"body", file, VoxelizeRole::Skin, m.V, m.F}}, g);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(MeshVoxelizer, HolesAreSpannedOpenSheetsAreErrors) {
  const double r = 10;
  const TriangleMesh s = sphere({0, 0, 0}, r, 48, 96);
  ImageGrid g = cube(-14, 14, 0.5);
  g.origin += Eigen::Vector3d::Constant(0.13);  // no voxel centre on the rims' planes
  // A hole of a few tenths of a voxel (the polar fan): the whole ball.
  const TriangleMesh pin = cutTop(s, 9.95);
  const MeshVoxelization p = voxelizeMesh(pin.V, pin.F, g);
  EXPECT_EQ(p.topology.holes, 1u);
  EXPECT_NEAR(double(p.insideVoxels) * 0.125, 4.0 / 3.0 * M_PI * 1000, 0.02 * 4.0 / 3.0 * M_PI * 1000);
  EXPECT_GT(p.meanInsideWinding, 0.9);
  // A cap 5 mm high removed (a hole 17 mm across): w = 1/2 on the flat disc spanning the planar rim,
  // so the inside is the ball below the rim's plane.
  const TriangleMesh bowl = cutTop(s, 5.0);
  const MeshVoxelization m = voxelizeMesh(bowl.V, bowl.F, g);
  double rim = -INFINITY;
  for (const auto& loop : boundaryLoops(bowl.V, bowl.F))
    for (int v : loop) rim = std::max(rim, bowl.V(v, 2));
  const double below = M_PI * (r + rim) * (r + rim) * (2 * r - rim) / 3;
  EXPECT_NEAR(double(m.insideVoxels) * 0.125, below, 0.02 * below) << "rim at z " << rim;
  EXPECT_NEAR(m.topology.largestHole, 2 * std::sqrt(r * r - rim * rim), 0.2);
  EXPECT_GT(m.evaluatedVoxels, 0u);
  EXPECT_GT(m.meanInsideWinding, kMinInsideWinding);
  EXPECT_EQ(voxelizeError(bowl, "bowl.stl", g), "");
  // The top half removed, and a shallow dish: too open; the message names the file and the holes.
  for (double cut : {0.0, -8.0}) {
    const std::string e = voxelizeError(cutTop(s, cut), "dish.stl", g);
    EXPECT_EQ(e.find("dish.stl: the surface is not closed enough to have an inside (1 hole(s)"), 0u) << e;
    EXPECT_NE(e.find("winding number inside averages 0."), std::string::npos) << e;
  }
  // A flat sheet has no inside at all.
  TriangleMesh sheet = cutTop(s, -9.0);
  sheet.V.col(2).setZero();
  const std::string e = voxelizeError(sheet, "sheet.obj", g);
  EXPECT_EQ(e.find("sheet.obj: the surface is not closed enough to have an inside"), 0u) << e;
  EXPECT_NE(e.find("nothing"), std::string::npos) << e;
}

TEST(MeshVoxelizer, OverlappingPiecesMakeTheirExactUnion) {
  // Box faces halfway between voxel centres: the union's and the overlap's voxels are known exactly.
  const TriangleMesh two = concat(box({-5, -3, -2}, {3, 3, 2}), box({-1, -1, -4}, {6, 2, 1}));
  const MeshVoxelization m = voxelizeMesh(two.V, two.F, cube(-9.5, 9.5, 1.0));
  const std::size_t a = 8 * 6 * 4, b = 7 * 3 * 5, both = 4 * 3 * 3;
  EXPECT_EQ(m.insideVoxels, a + b - both);
  EXPECT_EQ(m.overlapVoxels, both);
  EXPECT_EQ(m.topology.pieces, 2u);
  EXPECT_EQ(m.repairs.cavities + m.repairs.invertedPieces, 0u);
}

TEST(MeshVoxelizer, MixedWindingsAreTurnedToAgree) {
  // Every 7th triangle reversed, as careless exports leave them: the same ball.
  const TriangleMesh s = sphere({0.3, -0.2, 0.1}, 10, 24, 48);
  TriangleMesh mixed = s;
  std::size_t reversed = 0;
  for (Eigen::Index t = 3; t < mixed.F.rows(); t += 7, ++reversed) std::swap(mixed.F(t, 1), mixed.F(t, 2));
  const ImageGrid g = cube(-12, 12, 0.5);
  const MeshVoxelization m = voxelizeMesh(mixed.V, mixed.F, g), ref = voxelizeMesh(s.V, s.F, g);
  EXPECT_EQ(m.repairs.trianglesTurned, reversed);
  EXPECT_EQ(m.inside, ref.inside);
  std::size_t turned = 0;
  EXPECT_EQ(consistentlyOriented(s.V, s.F, turned), s.F);
  EXPECT_EQ(turned, 0u);
}

TEST(MeshVoxelizer, ReflectedGridAndOneThreadGiveTheSameVoxels) {
  const TriangleMesh two = concat(sphere({-3, 0, 1}, 7, 24, 48), cutTop(sphere({4, 1, 0}, 6, 24, 48), 4.0));
  ImageGrid g;
  g.dims = {40, 36, 32};
  g.spacing = Eigen::Vector3d(0.6, 0.5, 0.7);
  g.direction = Eigen::AngleAxisd(0.3, Eigen::Vector3d(0, 1, 1).normalized()).toRotationMatrix();
  g.origin = -g.direction * g.spacing.cwiseProduct(Eigen::Vector3d(20, 18, 16));
  const MeshVoxelization m = voxelizeMesh(two.V, two.F, g);
  // The same lattice with its k axis reversed (a direction matrix of determinant -1).
  ImageGrid f = g;
  f.direction.col(2) = -g.direction.col(2);
  f.origin = g.indexToPhysical(Eigen::Vector3d(0, 0, g.dims[2] - 1));
  const MeshVoxelization r = voxelizeMesh(two.V, two.F, f);
  ASSERT_EQ(r.insideVoxels, m.insideVoxels);
  for (int k = 0; k < g.dims[2]; ++k)
    for (int j = 0; j < g.dims[1]; ++j)
      for (int i = 0; i < g.dims[0]; ++i) ASSERT_EQ(m.at(i, j, k), r.at(i, j, g.dims[2] - 1 - k));
  // One thread: the same voxels.
  setParallelRunner([](std::size_t n, std::size_t, const RangeBody& body) { body(0, n); });
  const MeshVoxelization one = voxelizeMesh(two.V, two.F, g);
  setParallelRunner(nullptr);
  EXPECT_EQ(one.inside, m.inside);
  EXPECT_DOUBLE_EQ(one.meanInsideWinding, m.meanInsideWinding);
}

TEST(MeshVoxelizer, LabelsPrioritiesWarningsAndGrid) {
  const TriangleMesh body = box({-20.25, -10.25, -30.25}, {20.25, 10.25, 30.25});
  const TriangleMesh boneA = sphere({0, 0, 10}, 6, 24, 48);
  const TriangleMesh boneB = sphere({0, 0, -10}, 6, 24, 48);
  const TriangleMesh muscle = box({-8, -8, -20}, {8, 8, 20});       // under both bones
  const TriangleMesh sticking = box({15, -3, -3}, {25, 3, 3});       // half outside the body
  std::vector<VoxelizePart> parts{{"soft_tissue", "skin.vtp", VoxelizeRole::Skin, body.V, body.F},
                                   {"muscle", "muscle.obj", VoxelizeRole::Tissue, muscle.V, muscle.F},
                                   {"upper", "a.stl", VoxelizeRole::Bone, boneA.V, boneA.F},
                                   {"lower", "b.stl", VoxelizeRole::Bone, boneB.V, boneB.F},
                                   {"stick", "c.stl", VoxelizeRole::Bone, sticking.V, sticking.F}};
  LabelVoxelizeOptions o;
  o.voxelMm = 1.0;
  o.padVoxels = 2;
  const LabelVoxelization r = voxelizeLabels(parts, ImageGrid{}, o);
  const ImageGrid& g = r.labels.grid;
  // Centred on the skin's bounds, 2 voxels of padding: centres at half-integers.
  EXPECT_EQ(g.dims[0], 46);
  EXPECT_EQ(g.dims[2], 66);
  EXPECT_NEAR(g.origin.x(), -22.5, 1e-12);
  EXPECT_TRUE(g.direction.isIdentity());
  // Label order: skin, bones in order, tissues.
  ASSERT_EQ(r.table.labels.size(), 6u);
  EXPECT_EQ(r.table.labels[1].name, "soft_tissue");
  EXPECT_EQ(r.table.labels[2].name, "upper");
  EXPECT_EQ(r.table.labels[2].kind, LabelKind::Bone);
  EXPECT_EQ(r.table.labels[4].name, "stick");
  EXPECT_EQ(r.table.labels[5].name, "muscle");
  EXPECT_EQ(r.table.labels[5].kind, LabelKind::Soft);
  auto labelAt = [&](double x, double y, double z) {
    const Eigen::Vector3d ijk = g.physicalToIndex({x, y, z});
    return r.labels.at(int(std::lround(ijk.x())), int(std::lround(ijk.y())), int(std::lround(ijk.z())));
  };
  EXPECT_EQ(labelAt(0, 0, 10), 2);    // bone over tissue
  EXPECT_EQ(labelAt(0, 0, -10), 3);
  EXPECT_EQ(labelAt(0, 0, 0), 5);     // tissue over skin
  EXPECT_EQ(labelAt(0, 9, 0), 1);     // skin interior
  EXPECT_EQ(labelAt(22, 0, 0), 4);    // the bone outside the skin is kept
  EXPECT_EQ(labelAt(0, 0, 32), 0);
  ASSERT_EQ(r.parts.size(), 5u);
  EXPECT_DOUBLE_EQ(r.parts[3].outsideSkinFraction, 3.0 / 8.0);  // x 20.5 .. 22.5 of 15.5 .. 22.5
  EXPECT_EQ(r.parts[1].outsideSkinFraction, 0.0);
  bool warned = false;
  for (const auto& w : r.warnings) warned |= w.find("c.stl:") == 0 && w.find("outside the skin") != std::string::npos;
  EXPECT_TRUE(warned) << r.text();
  EXPECT_EQ(r.parts[0].labelledVoxels + r.parts[1].labelledVoxels + r.parts[2].labelledVoxels +
                r.parts[3].labelledVoxels + r.parts[4].labelledVoxels,
            std::size_t(40 * 20 * 60 + 3 * 6 * 6));

  // Too many voxels, no skin, two skins, duplicate names.
  o.maxVoxels = 1000;
  EXPECT_THROW(voxelizeLabels(parts, ImageGrid{}, o), std::invalid_argument);
  o.maxVoxels = std::size_t(1) << 30;
  EXPECT_THROW(voxelizeLabels({parts[2]}, ImageGrid{}, o), std::invalid_argument);
  auto twice = parts;
  twice[1].role = VoxelizeRole::Skin;
  EXPECT_THROW(voxelizeLabels(twice, ImageGrid{}, o), std::invalid_argument);
  twice = parts;
  twice[3].name = "upper";
  EXPECT_THROW(voxelizeLabels(twice, ImageGrid{}, o), std::invalid_argument);
}

TEST(MeshVoxelizer, BonesAreSolidWideCavitiesStayAndTheReportSaysSo) {
  // Two bones: a cortical shell 1 mm thick around marrow of radius 14 mm, and a skull-like shell
  // 12 mm thick around a cavity of radius 40 mm; and a tissue shaped as the first (not a bone).
  auto shell = [](const Eigen::Vector3d& c, double outer, double inner) {
    TriangleMesh in = sphere(c, inner);
    in.F.col(1).swap(in.F.col(2));
    return concat(sphere(c, outer), in);
  };
  auto ball = [](double r) { return 4.0 / 3.0 * M_PI * r * r * r; };
  const TriangleMesh body = box({-60.3, -60.3, -130.3}, {60.3, 60.3, 90.3});
  const TriangleMesh marrow = shell({0, 0, -70}, 15, 14), skull = shell({0, 0, 30}, 52, 40),
                     sac = shell({0, 0, -110}, 15, 14);
  const std::vector<VoxelizePart> parts{{"soft_tissue", "skin.vtp", VoxelizeRole::Skin, body.V, body.F},
                                        {"femur_left", "femur.stl", VoxelizeRole::Bone, marrow.V, marrow.F},
                                        {"skull", "skull.stl", VoxelizeRole::Bone, skull.V, skull.F},
                                        {"bladder", "bladder.stl", VoxelizeRole::Tissue, sac.V, sac.F}};
  LabelVoxelizeOptions o;
  o.voxelMm = 2.0;
  const LabelVoxelization r = voxelizeLabels(parts, ImageGrid{}, o);
  const VoxelizedPart &femur = r.parts[1], &head = r.parts[2], &bladder = r.parts[3];
  EXPECT_NEAR(femur.solidVolume, ball(15), 0.04 * ball(15));
  EXPECT_NEAR(femur.voxelVolume, ball(15) - ball(14), 0.25 * (ball(15) - ball(14)));
  EXPECT_EQ(femur.labelledVoxels, femur.solidVoxels);
  EXPECT_EQ(head.solidVoxels, head.voxels);
  EXPECT_EQ(head.labelledVoxels, head.voxels);
  EXPECT_NEAR(double(head.hollows.wideVoxels) * 8.0, ball(40), 0.04 * ball(40));
  EXPECT_TRUE(bladder.hollows.hollows.empty());  // only bones are looked into
  auto labelAt = [&](const LabelVoxelization& v, double z) {
    const Eigen::Vector3d ijk = v.labels.grid.physicalToIndex({0.5, 0.5, z});
    return v.labels.at(int(std::lround(ijk.x())), int(std::lround(ijk.y())), int(std::lround(ijk.z())));
  };
  EXPECT_EQ(labelAt(r, -70), 2);   // marrow is bone
  EXPECT_EQ(labelAt(r, 30), 1);    // the cranial cavity is soft tissue
  EXPECT_EQ(labelAt(r, -110), 1);  // so is the tissue's hollow
  const std::string text = r.text();
  EXPECT_NE(text.find("femur.stl): " + std::to_string(femur.topology.triangles) +
                      " triangles, 2 pieces, 1 cavities carved; filled "),
            std::string::npos)
      << text;
  EXPECT_NE(text.find(" of hollow interior (1 hollow, radius up to 1"), std::string::npos) << text;
  EXPECT_NE(text.find(": shell " + std::to_string(femur.voxels) + " voxels, "), std::string::npos) << text;
  EXPECT_NE(text.find(", solid " + std::to_string(femur.solidVoxels) + " voxels, "), std::string::npos) << text;
  EXPECT_NE(text.find("kept 1 cavity of 2"), std::string::npos) << text;
  EXPECT_NE(text.find("room for an organ"), std::string::npos) << text;
  // Hollow bones: the shell is labelled, the solid still reported.
  o.hollowBones = true;
  const LabelVoxelization h = voxelizeLabels(parts, ImageGrid{}, o);
  EXPECT_EQ(h.parts[1].labelledVoxels, femur.voxels);
  EXPECT_EQ(h.parts[1].solidVoxels, femur.solidVoxels);
  EXPECT_EQ(labelAt(h, -70), 1);
  EXPECT_NE(h.text().find("left open "), std::string::npos) << h.text();
  // A narrower marrow limit keeps the marrow as a cavity.
  o.hollowBones = false;
  o.maxMarrowRadiusMm = 5;
  EXPECT_EQ(voxelizeLabels(parts, ImageGrid{}, o).parts[1].labelledVoxels, femur.voxels);
}

TEST(MeshVoxelizer, BadInput) {
  const TriangleMesh b = box({0, 0, 0}, {1, 1, 1});
  const ImageGrid g = cube(-2, 2, 1);
  EXPECT_THROW(voxelizeMesh(MeshVertices(), MeshTriangles(), g), std::invalid_argument);
  MeshVertices nan = b.V;
  nan(2, 1) = NAN;
  EXPECT_THROW(voxelizeMesh(nan, b.F, g), std::invalid_argument);
  EXPECT_THROW(voxelizeMesh(b.V, b.F, ImageGrid{}), std::invalid_argument);
  EXPECT_THROW(gridFittingPoints(b.V, 0.0, 2, 1000), std::invalid_argument);
}
