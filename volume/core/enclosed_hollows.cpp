#include "enclosed_hollows.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>

#include "distance_transform.h"
#include "lattice_crossings.h"

namespace repose {
namespace {

// One byte a voxel of the box: what it is, and which of its segments towards +i, +j, +k is crossed.
enum : std::uint8_t { Inside = 1, Outside = 2, Seen = 4, CutI = 8 };
constexpr std::uint8_t cutBit(int axis) { return std::uint8_t(CutI << axis); }

/// The surface's index box with one voxel more each side (clipped to the grid), so that its border
/// lies beyond the surface, and its voxels' flags.
struct Lattice {
  IndexBox box;
  std::array<std::ptrdiff_t, 3> stride{0, 0, 0};
  std::vector<std::uint8_t> flags;

  std::array<int, 3> coords(std::size_t v) const {
    const std::size_t plane = std::size_t(box.dims[0]) * std::size_t(box.dims[1]);
    return {int(v % std::size_t(box.dims[0])), int((v % plane) / std::size_t(box.dims[0])), int(v / plane)};
  }
  /// Calls f(n) for each neighbour n of v that no triangle separates from it.
  template <class Fn>
  void forJoined(std::size_t v, Fn f) const {
    const std::array<int, 3> c = coords(v);
    for (int a = 0; a < 3; ++a) {
      if (c[a] + 1 < box.dims[a] && !(flags[v] & cutBit(a))) f(v + std::size_t(stride[a]));
      if (c[a] > 0 && !(flags[v - std::size_t(stride[a])] & cutBit(a))) f(v - std::size_t(stride[a]));
    }
  }
};

IndexBox boxOf(const WindingInside& in) {
  IndexBox b;
  b.min = in.boxMin;
  b.dims = in.boxDims;
  return b;
}

Lattice latticeOf(const MeshVertices& V, const MeshTriangles& F, const ImageGrid& grid, const WindingInside& in) {
  Lattice L;
  for (int a = 0; a < 3; ++a) {
    L.box.min[a] = std::max(0, in.boxMin[a] - 1);
    L.box.dims[a] = std::min(grid.dims[a], in.boxMin[a] + in.boxDims[a] + 1) - L.box.min[a];
  }
  L.stride = {1, L.box.dims[0], std::ptrdiff_t(L.box.dims[0]) * L.box.dims[1]};
  L.flags.assign(L.box.count(), 0);
  const IndexBox inBox = boxOf(in);
  const std::array<int, 3> shift{in.boxMin[0] - L.box.min[0], in.boxMin[1] - L.box.min[1], in.boxMin[2] - L.box.min[2]};
  for (int k = 0; k < in.boxDims[2]; ++k)
    for (int j = 0; j < in.boxDims[1]; ++j)
      for (int i = 0; i < in.boxDims[0]; ++i)
        if (in.inside[inBox.index(i, j, k)]) L.flags[L.box.index(i + shift[0], j + shift[1], k + shift[2])] |= Inside;
  // The surface and the cones over its holes, in grid indices.
  const ClosingCones cones = closingCones(V, F);
  std::vector<Eigen::Vector3d> p(std::size_t(cones.V.rows()));
  for (Eigen::Index v = 0; v < cones.V.rows(); ++v) p[std::size_t(v)] = grid.physicalToIndex(cones.V.row(v).transpose());
  std::vector<RowCrossing> crossings;
  for (int axis = 0; axis < 3; ++axis) {
    crossings.clear();
    for (const MeshTriangles* T : {&F, &cones.F})
      for (Eigen::Index t = 0; t < T->rows(); ++t)
        crossRows(p[std::size_t((*T)(t, 0))], p[std::size_t((*T)(t, 1))], p[std::size_t((*T)(t, 2))], axis, L.box,
                  crossings);
    const int u = (axis + 1) % 3, w = (axis + 2) % 3;
    for (const RowCrossing& c : crossings) {
      if (c.last + 1 >= L.box.dims[axis]) continue;  // beyond the box's last voxel
      std::array<int, 3> at{0, 0, 0};
      at[axis] = c.last;
      at[u] = int(c.row % std::uint32_t(L.box.dims[u]));
      at[w] = int(c.row / std::uint32_t(L.box.dims[u]));
      L.flags[L.box.index(at[0], at[1], at[2])] |= cutBit(axis);
    }
  }
  return L;
}

/// Marks Outside the voxels the box's border reaches without crossing the surface.
void floodOutside(Lattice& L) {
  std::vector<std::size_t> stack;  // depth first: it holds a front, not all the outside
  const std::array<int, 3>& d = L.box.dims;
  for (int k = 0; k < d[2]; ++k)
    for (int j = 0; j < d[1]; ++j)
      for (int i = 0; i < d[0]; i += (j == 0 || k == 0 || j == d[1] - 1 || k == d[2] - 1) ? 1 : std::max(1, d[0] - 1)) {
        const std::size_t v = L.box.index(i, j, k);
        if (!(L.flags[v] & Inside)) L.flags[v] |= Outside, stack.push_back(v);
      }
  while (!stack.empty()) {
    const std::size_t v = stack.back();
    stack.pop_back();
    L.forJoined(v, [&](std::size_t n) {
      if (L.flags[n] & (Inside | Outside)) return;
      L.flags[n] |= Outside;
      stack.push_back(n);
    });
  }
}

/// The voxels of the hollow holding `seed`, marked Seen.
void collectHollow(Lattice& L, std::size_t seed, std::vector<std::size_t>& voxels) {
  voxels.assign(1, seed);
  L.flags[seed] |= Seen;
  for (std::size_t q = 0; q < voxels.size(); ++q)
    L.forJoined(voxels[q], [&](std::size_t n) {
      if (L.flags[n] & (Inside | Outside | Seen)) return;
      L.flags[n] |= Seen;
      voxels.push_back(n);
    });
}

/// The radius of one hollow (see the header) from its voxels.
double radiusOf(const Lattice& L, const std::vector<std::size_t>& voxels, const Eigen::Vector3d& spacing) {
  std::array<int, 3> lo{L.box.dims}, hi{-1, -1, -1};
  for (std::size_t v : voxels) {
    const std::array<int, 3> c = L.coords(v);
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], c[a]), hi[a] = std::max(hi[a], c[a]);
  }
  // The hollow's box with one layer around it: the distance to the nearest voxel not of the hollow.
  MaskVolume notHollow;
  notHollow.grid.dims = {hi[0] - lo[0] + 3, hi[1] - lo[1] + 3, hi[2] - lo[2] + 3};
  notHollow.grid.spacing = spacing;
  notHollow.data.assign(notHollow.grid.voxelCount(), 1);
  for (std::size_t v : voxels) {
    const std::array<int, 3> c = L.coords(v);
    notHollow.at(c[0] - lo[0] + 1, c[1] - lo[1] + 1, c[2] - lo[2] + 1) = 0;
  }
  const std::vector<float> d = distanceToFeatures(notHollow);
  return double(*std::max_element(d.begin(), d.end()));
}

}  // namespace

EnclosedHollows fillEnclosedHollows(const MeshVertices& V, const MeshTriangles& F, const ImageGrid& grid,
                                    WindingInside& inside, const HollowOptions& options) {
  if (!(options.maxFillRadiusMm >= 0)) throw std::invalid_argument("the largest radius to fill must not be negative");
  EnclosedHollows out;
  out.filled = options.fill;
  if (inside.boxDims[0] == 0 || inside.boxDims[1] == 0 || inside.boxDims[2] == 0) return out;
  Lattice L = latticeOf(V, F, grid, inside);
  floodOutside(L);
  const IndexBox inBox = boxOf(inside);
  std::vector<std::size_t> voxels;
  for (std::size_t seed = 0; seed < L.flags.size(); ++seed) {
    if (L.flags[seed] & (Inside | Outside | Seen)) continue;
    collectHollow(L, seed, voxels);
    EnclosedHollow h;
    h.voxels = voxels.size();
    h.radiusMm = radiusOf(L, voxels, grid.spacing);
    h.thin = h.radiusMm <= options.maxFillRadiusMm;
    (h.thin ? out.thinVoxels : out.wideVoxels) += h.voxels;
    double& extreme = h.thin ? out.largestThinRadiusMm : out.smallestWideRadiusMm;
    extreme = extreme == 0 ? h.radiusMm : h.thin ? std::max(extreme, h.radiusMm) : std::min(extreme, h.radiusMm);
    out.hollows.push_back(h);
    if (!h.thin || !options.fill) continue;
    for (std::size_t v : voxels) {  // inside the surface's box: its border, one voxel out, is all outside
      const std::array<int, 3> c = L.coords(v);
      inside.inside[inBox.index(L.box.min[0] + c[0] - inside.boxMin[0], L.box.min[1] + c[1] - inside.boxMin[1],
                                L.box.min[2] + c[2] - inside.boxMin[2])] = 1;
    }
  }
  std::stable_sort(out.hollows.begin(), out.hollows.end(),
                   [](const EnclosedHollow& a, const EnclosedHollow& b) { return a.voxels > b.voxels; });
  return out;
}

}  // namespace repose
