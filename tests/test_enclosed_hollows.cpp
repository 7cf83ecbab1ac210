// Hollows a surface walls in: lattice crossings along every axis, the exact distance transform
// against brute force, a shell thinner than a voxel filled, a wide cavity kept, a hole through a
// shell spanned, an open cup that holds no hollow, and the Visible Human's hip bone made solid.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

#include "distance_transform.h"
#include "enclosed_hollows.h"
#include "lattice_crossings.h"
#include "mesh_voxelizer.h"
#include "parallel_for.h"
#include "triangle_soups.h"

using namespace repose;

namespace {

/// Cubic lattice of n^3 voxels of h mm centred on `centre` (no voxel centre on the axes' planes
/// through it when n is even).
ImageGrid latticeAround(const Eigen::Vector3d& centre, int n, double h) {
  ImageGrid g;
  g.dims = {n, n, n};
  g.spacing = Eigen::Vector3d::Constant(h);
  g.origin = centre - Eigen::Vector3d::Constant(0.5 * (n - 1) * h);
  return g;
}

/// The closed surface swept by turning a profile of (radius, z) points about the z axis; the
/// profile starts and ends on the axis.
TriangleMesh lathe(const std::vector<Eigen::Vector2d>& profile, int segments) {
  const int rings = int(profile.size()) - 2;
  TriangleMesh m;
  m.V.resize(2 + rings * segments, 3);
  m.V.row(0) << 0, 0, profile.front().y();
  m.V.row(1) << 0, 0, profile.back().y();
  for (int r = 0; r < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      const double phi = 2 * M_PI * s / segments, rho = profile[std::size_t(r) + 1].x();
      m.V.row(2 + r * segments + s) << rho * std::cos(phi), rho * std::sin(phi), profile[std::size_t(r) + 1].y();
    }
  auto at = [&](int r, int s) { return 2 + r * segments + s % segments; };
  std::vector<Eigen::Vector3i> f;
  for (int s = 0; s < segments; ++s) {
    f.push_back({0, at(0, s + 1), at(0, s)});
    f.push_back({1, at(rings - 1, s), at(rings - 1, s + 1)});
    for (int r = 0; r + 1 < rings; ++r) {
      f.push_back({at(r, s), at(r, s + 1), at(r + 1, s + 1)});
      f.push_back({at(r, s), at(r + 1, s + 1), at(r + 1, s)});
    }
  }
  m.F.resize(Eigen::Index(f.size()), 3);
  for (std::size_t i = 0; i < f.size(); ++i) m.F.row(Eigen::Index(i)) = f[i].transpose();
  return m;
}

/// An outward sphere of radius `outer` around an inward one of radius `inner`: a hollow shell.
TriangleMesh hollowBall(double outer, double inner, int rings = 48, int segments = 96) {
  return concat(sphere({0, 0, 0}, outer, rings, segments), inverted(sphere({0, 0, 0}, inner, rings, segments)));
}

double ball(double r) { return 4.0 / 3.0 * M_PI * r * r * r; }

/// Voxels in the largest 6-connected piece of the inside, and the inside's count.
std::pair<std::size_t, std::size_t> largestPiece(const MeshVoxelization& m) {
  const std::array<int, 3>& d = m.boxDims;
  std::vector<char> seen(m.inside.size(), 0);
  std::size_t largest = 0, total = 0;
  for (std::size_t s = 0; s < m.inside.size(); ++s) {
    if (!m.inside[s] || seen[s]) continue;
    std::vector<std::size_t> stack{s};
    seen[s] = 1;
    std::size_t size = 0;
    while (!stack.empty()) {
      const std::size_t v = stack.back();
      stack.pop_back();
      ++size;
      const int i = int(v % std::size_t(d[0])), j = int(v / std::size_t(d[0]) % std::size_t(d[1])),
                k = int(v / (std::size_t(d[0]) * std::size_t(d[1])));
      const int c[3] = {i, j, k};
      const std::size_t stride[3] = {1, std::size_t(d[0]), std::size_t(d[0]) * std::size_t(d[1])};
      for (int a = 0; a < 3; ++a)
        for (int step : {-1, 1}) {
          if (c[a] + step < 0 || c[a] + step >= d[a]) continue;
          const std::size_t n = step > 0 ? v + stride[a] : v - stride[a];
          if (m.inside[n] && !seen[n]) seen[n] = 1, stack.push_back(n);
        }
    }
    largest = std::max(largest, size);
    total += size;
  }
  return {largest, total};
}

MeshVoxelizeOptions withHollows(double maxRadius = kMaxMarrowRadiusMm, bool fill = true) {
  MeshVoxelizeOptions o;
  o.findHollows = true;
  o.hollows.fill = fill;
  o.hollows.maxFillRadiusMm = maxRadius;
  return o;
}

}  // namespace

TEST(LatticeCrossings, BoxFacesAlongEveryAxis) {
  // A box with its faces halfway between lattice points, in grid indices: each row through it
  // enters (normal against the row, -1) after the voxel before its low face and leaves (+1) after
  // the last voxel inside.
  const Eigen::Vector3d lo(4.5, 6.5, 7.5), hi(14.5, 12.5, 11.5);
  const TriangleMesh b = box(lo, hi);
  IndexBox grid;
  grid.dims = {20, 18, 16};
  for (int axis = 0; axis < 3; ++axis) {
    std::vector<RowCrossing> crossings;
    for (Eigen::Index t = 0; t < b.F.rows(); ++t)
      crossRows(b.V.row(b.F(t, 0)).transpose(), b.V.row(b.F(t, 1)).transpose(), b.V.row(b.F(t, 2)).transpose(), axis,
                grid, crossings);
    const int u = (axis + 1) % 3, w = (axis + 2) % 3;
    const std::size_t rows = std::size_t(hi[u] - lo[u]) * std::size_t(hi[w] - lo[w]);
    ASSERT_EQ(crossings.size(), 2 * rows) << "axis " << axis;
    for (const RowCrossing& c : crossings) {
      const int along = int(c.row % std::uint32_t(grid.dims[u])), across = int(c.row / std::uint32_t(grid.dims[u]));
      EXPECT_TRUE(along > lo[u] && along < hi[u] && across > lo[w] && across < hi[w]) << "axis " << axis;
      EXPECT_EQ(c.last, c.sign < 0 ? int(lo[axis]) : int(hi[axis])) << "axis " << axis;
    }
  }
}

TEST(EnclosedHollows, ShellThinnerThanAVoxelIsFilled) {
  // 0.8 mm of shell around a hollow of radius 19.2 mm, on a 2 mm lattice: few voxel centres fall
  // in the shell, which falls apart into pieces, but its surfaces still wall the hollow in.
  const TriangleMesh shell = hollowBall(20, 19.2);
  const ImageGrid g = latticeAround({0.37, -0.21, 0.13}, 24, 2.0);
  const MeshVoxelization raw = voxelizeMesh(shell.V, shell.F, g);
  EXPECT_TRUE(raw.hollows.hollows.empty());  // not looked for
  EXPECT_LT(double(largestPiece(raw).first), 0.5 * double(raw.insideVoxels));
  const MeshVoxelization m = voxelizeMesh(shell.V, shell.F, g, withHollows());
  EXPECT_EQ(m.insideVoxels, raw.insideVoxels);
  ASSERT_EQ(m.hollows.hollows.size(), 1u);
  const EnclosedHollow& h = m.hollows.hollows[0];
  EXPECT_TRUE(h.thin);
  EXPECT_NEAR(h.radiusMm, 19.2, 2.0);
  EXPECT_TRUE(m.hollows.filled);
  EXPECT_EQ(m.hollows.thinVoxels, h.voxels);
  const auto [largest, total] = largestPiece(m);
  EXPECT_EQ(total, m.insideVoxels + m.hollows.thinVoxels);
  EXPECT_EQ(largest, total);  // one solid ball
  EXPECT_NEAR(double(total) * 8.0, ball(20), 0.03 * ball(20));
  EXPECT_TRUE(m.at(12, 12, 12));
  // Found but not filled: the inside stays the shell.
  const MeshVoxelization kept = voxelizeMesh(shell.V, shell.F, g, withHollows(kMaxMarrowRadiusMm, false));
  EXPECT_EQ(kept.inside, raw.inside);
  EXPECT_FALSE(kept.hollows.filled);
  EXPECT_EQ(kept.hollows.thinVoxels, h.voxels);
  // One thread: the same voxels.
  setParallelRunner([](std::size_t n, std::size_t, const RangeBody& body) { body(0, n); });
  const MeshVoxelization one = voxelizeMesh(shell.V, shell.F, g, withHollows());
  setParallelRunner(nullptr);
  EXPECT_EQ(one.inside, m.inside);
  EXPECT_EQ(one.hollows.hollows[0].radiusMm, h.radiusMm);
}

TEST(EnclosedHollows, ThickShellAroundAWideCavityKeepsIt) {
  // A skull-like shell: 16 mm of bone around a cavity of radius 50 mm, wider than marrow.
  const TriangleMesh skull = hollowBall(66, 50);
  const ImageGrid g = latticeAround({0.4, 0.3, -0.2}, 36, 4.0);
  const MeshVoxelization m = voxelizeMesh(skull.V, skull.F, g, withHollows());
  ASSERT_EQ(m.hollows.hollows.size(), 1u);
  EXPECT_FALSE(m.hollows.hollows[0].thin);
  EXPECT_NEAR(m.hollows.hollows[0].radiusMm, 50, 4.0);
  EXPECT_EQ(m.hollows.thinVoxels, 0u);
  EXPECT_NEAR(double(m.hollows.wideVoxels) * 64.0, ball(50), 0.05 * ball(50));
  EXPECT_NEAR(double(m.insideVoxels) * 64.0, ball(66) - ball(50), 0.05 * (ball(66) - ball(50)));
  EXPECT_FALSE(m.at(18, 18, 18));  // the cavity stays
  // Allowed wider marrow, it is filled.
  const MeshVoxelization wide = voxelizeMesh(skull.V, skull.F, g, withHollows(60.0));
  EXPECT_TRUE(wide.hollows.hollows[0].thin);
  EXPECT_TRUE(wide.at(18, 18, 18));
  EXPECT_NEAR(double(wide.insideVoxels + wide.hollows.thinVoxels) * 64.0, ball(66), 0.03 * ball(66));
  EXPECT_THROW(voxelizeMesh(skull.V, skull.F, g, withHollows(-1.0)), std::invalid_argument);
}

TEST(EnclosedHollows, HoleThroughTheShellIsSpanned) {
  // A shell 1 mm thick cut open above z = 12: a hole through both walls, two rims. The rims are
  // spanned as the winding number spans them, so the hollow is still walled in: the solid is the
  // ball below the cut.
  const TriangleMesh shell = concat(cutTop(sphere({0, 0, 0}, 20), 12.0), inverted(cutTop(sphere({0, 0, 0}, 19), 12.0)));
  EXPECT_EQ(analyzeMeshTopology(shell.V, shell.F).holes, 2u);
  const ImageGrid g = latticeAround({0.31, 0.17, 0.23}, 46, 1.0);
  const MeshVoxelization m = voxelizeMesh(shell.V, shell.F, g, withHollows());
  ASSERT_FALSE(m.hollows.hollows.empty());
  EXPECT_TRUE(m.hollows.hollows[0].thin);
  EXPECT_TRUE(m.at(23, 23, 23));
  double rim = -INFINITY;  // the outer rim's plane
  for (const auto& loop : boundaryLoops(shell.V, shell.F))
    for (int v : loop) rim = std::max(rim, shell.V(v, 2));
  const double below = M_PI * (20 + rim) * (20 + rim) * (40 - rim) / 3;  // the ball of radius 20 below z = rim
  EXPECT_NEAR(double(m.insideVoxels + m.hollows.thinVoxels), below, 0.04 * below) << "rim at z " << rim;
}

TEST(EnclosedHollows, OpenCupHoldsNoHollow) {
  // A cup 1 mm thick, closed at its rim: what it holds is open to the outside, not a hollow.
  std::vector<Eigen::Vector2d> profile;
  for (int a = 0; a <= 24; ++a) profile.emplace_back(19 * std::sin(M_PI / 2 * a / 24), -19 * std::cos(M_PI / 2 * a / 24));
  for (int a = 24; a >= 0; --a) profile.emplace_back(20 * std::sin(M_PI / 2 * a / 24), -20 * std::cos(M_PI / 2 * a / 24));
  const TriangleMesh cup = lathe(profile, 96);
  EXPECT_TRUE(analyzeMeshTopology(cup.V, cup.F).closed());
  const ImageGrid g = latticeAround({0.3, 0.2, -10.1}, 46, 1.0);
  const MeshVoxelization m = voxelizeMesh(cup.V, cup.F, g, withHollows());
  EXPECT_TRUE(m.hollows.hollows.empty());
  EXPECT_NEAR(double(m.insideVoxels), (ball(20) - ball(19)) / 2, 0.15 * (ball(20) - ball(19)) / 2);
  // The same cup with a lid 1 mm above its rim still holds no hollow: the gap is open all round.
  const TriangleMesh lid = box({-25, -25, 1}, {25, 25, 3});
  EXPECT_TRUE(voxelizeMesh(concat(cup, lid).V, concat(cup, lid).F, g, withHollows()).hollows.hollows.empty());
  // Resting on the rim (overlapping it by 0.3 mm), the lid closes the cup: what it holds is walled in.
  const TriangleMesh closedCup = concat(cup, box({-25, -25, -0.3}, {25, 25, 2}));
  const MeshVoxelization closed = voxelizeMesh(closedCup.V, closedCup.F, g, withHollows());
  ASSERT_EQ(closed.hollows.hollows.size(), 1u);
  EXPECT_NEAR(double(closed.hollows.thinVoxels), ball(19) / 2, 0.05 * ball(19) / 2);
}

TEST(EnclosedHollows, VisibleHumanHipBoneIsSolid) {
  // The female's left hip bone as the atlas ships it: ilium, ischium and pubis, each a cortical
  // shell about 1.2 mm thick (83.2 ml), walling in 391 ml of cancellous bone. Its envelope measured
  // independently (the three parts rasterized at 1 mm by VTK, closed by a 1 mm ball, holes filled
  // by SciPy): 474.2 ml.
  const TriangleMesh hip = readBinaryPly(std::string(REPOSE_SHARED_DATA) + "/visible_human/female/hip_left.ply");
  const Eigen::Vector3d lo = hip.V.colwise().minCoeff().transpose(), hi = hip.V.colwise().maxCoeff().transpose();
  const ImageGrid g = latticeAround(0.5 * (lo + hi), int((hi - lo).maxCoeff() / 3.0) + 4, 3.0);
  const MeshVoxelization m = voxelizeMesh(hip.V, hip.F, g, withHollows());
  const double shell = double(m.insideVoxels) * 27e-3, solid = double(m.insideVoxels + m.hollows.thinVoxels) * 27e-3;
  EXPECT_NEAR(shell, 83.2, 0.08 * 83.2);
  EXPECT_NEAR(solid, 474.2, 0.02 * 474.2);
  ASSERT_GE(m.hollows.hollows.size(), 1u);
  EXPECT_GT(double(m.hollows.hollows[0].voxels) * 27e-3, 380.0);
  EXPECT_NEAR(m.hollows.hollows[0].radiusMm, 16, 3.0);
  const auto [largest, total] = largestPiece(m);
  EXPECT_GT(double(largest), 0.99 * double(total));  // one bone, where the shell alone is hundreds of pieces
  const MeshVoxelization raw = voxelizeMesh(hip.V, hip.F, g);
  EXPECT_LT(double(largestPiece(raw).first), 0.2 * double(raw.insideVoxels));
}
