#include "bone_contacts.h"

#include <algorithm>
#include <cmath>

#include "parallel_for.h"

namespace repose {

void findBoneBoundaries(const ImageGrid& grid, RigBones& rb) {
  const int nx = grid.dims[0];
  const std::ptrdiff_t stride[3] = {1, nx, std::ptrdiff_t(nx) * grid.dims[1]};
  parallelFor(rb.bones.size(), [&](std::size_t b0, std::size_t b1) {
    for (std::size_t bi = b0; bi < b1; ++bi) {
      RigBone& b = rb.bones[bi];
      auto inBone = [&](std::size_t p) {
        const int c = rb.componentOf[p];
        return c >= 0 && rb.boneOfComponent[c] == int(bi);
      };
      b.boundary.clear();
      for (int k = b.lo[2]; k <= b.hi[2]; ++k)
        for (int j = b.lo[1]; j <= b.hi[1]; ++j)
          for (int i = b.lo[0]; i <= b.hi[0]; ++i) {
            const std::size_t p = grid.linearIndex(i, j, k);
            if (!inBone(p)) continue;
            const int ijk[3] = {i, j, k};
            bool edge = false;
            for (int d = 0; d < 3 && !edge; ++d)
              for (int sgn : {-1, 1}) {
                const int nd = ijk[d] + sgn;
                if (nd >= 0 && nd < grid.dims[d] && !inBone(std::size_t(std::ptrdiff_t(p) + sgn * stride[d]))) {
                  edge = true;
                  break;
                }
              }
            if (edge) b.boundary.push_back(p);
          }
      std::vector<Eigen::Vector3d> points;
      points.reserve(b.boundary.size());
      for (std::size_t p : b.boundary) {
        const int i = int(p % nx), j = int((p / nx) % grid.dims[1]), k = int(p / (std::size_t(nx) * grid.dims[1]));
        points.push_back(grid.indexToPhysical(Eigen::Vector3d(i, j, k)));
      }
      b.surface = std::make_shared<PointGrid>(std::move(points), 2 * grid.spacing.maxCoeff());
    }
  }, 1);
}

std::vector<std::vector<BoneContact>> findBoneContacts(const ImageGrid& grid, const RigBones& rb, double thr) {
  const auto& bones = rb.bones;
  const int B = int(bones.size());
  const Eigen::Vector3d h = grid.spacing;
  const int nx = grid.dims[0], ny = grid.dims[1];
  auto coords = [&](std::size_t p, int& i, int& j, int& k) {
    i = int(p % nx);
    j = int((p / nx) % ny);
    k = int(p / (std::size_t(nx) * ny));
  };
  int rad[3];
  for (int d = 0; d < 3; ++d) rad[d] = int(std::floor(thr / h[d]));
  struct Offset { int di, dj, dk; float d; };
  std::vector<Offset> offsets;
  for (int dk = -rad[2]; dk <= rad[2]; ++dk)
    for (int dj = -rad[1]; dj <= rad[1]; ++dj)
      for (int di = -rad[0]; di <= rad[0]; ++di) {
        const double d = Eigen::Vector3d(di * h[0], dj * h[1], dk * h[2]).norm();
        if (d <= thr) offsets.push_back({di, dj, dk, float(d)});
      }
  std::vector<std::vector<BoneContact>> contacts(B);
  parallelFor(std::size_t(B), [&](std::size_t b0, std::size_t b1) {
    std::vector<float> dist;
    for (std::size_t ai = b0; ai < b1; ++ai) {
      const RigBone& a = bones[ai];
      int lo[3], hi[3], dim[3];
      for (int d = 0; d < 3; ++d) {
        lo[d] = std::max(0, a.lo[d] - rad[d]);
        hi[d] = std::min(grid.dims[d] - 1, a.hi[d] + rad[d]);
        dim[d] = hi[d] - lo[d] + 1;
      }
      std::vector<int> others;
      for (int o = 0; o < B; ++o) {
        if (o == int(ai)) continue;
        bool overlap = true;
        for (int d = 0; d < 3; ++d) overlap = overlap && bones[o].lo[d] <= hi[d] && bones[o].hi[d] >= lo[d];
        if (overlap) others.push_back(o);
      }
      if (others.empty()) continue;
      dist.assign(std::size_t(dim[0]) * dim[1] * dim[2], std::numeric_limits<float>::max());
      for (std::size_t p : a.boundary) {
        int i, j, k;
        coords(p, i, j, k);
        for (const Offset& o : offsets) {
          const int x = i + o.di - lo[0], y = j + o.dj - lo[1], z = k + o.dk - lo[2];
          if (x < 0 || y < 0 || z < 0 || x >= dim[0] || y >= dim[1] || z >= dim[2]) continue;
          float& t = dist[(std::size_t(z) * dim[1] + y) * dim[0] + x];
          t = std::min(t, o.d);
        }
      }
      for (int o : others) {
        BoneContact c;
        c.other = o;
        for (std::size_t p : bones[o].boundary) {
          int i, j, k;
          coords(p, i, j, k);
          if (i < lo[0] || j < lo[1] || k < lo[2] || i > hi[0] || j > hi[1] || k > hi[2]) continue;
          const float d = dist[(std::size_t(k - lo[2]) * dim[1] + (j - lo[1])) * dim[0] + (i - lo[0])];
          if (d <= thr) {
            c.near.emplace_back(p, d);
            c.dmin = std::min(c.dmin, d);
          }
        }
        if (!c.near.empty()) contacts[ai].push_back(std::move(c));
      }
    }
  }, 1);
  return contacts;
}

const BoneContact* findContact(const std::vector<std::vector<BoneContact>>& contacts, int self, int other) {
  for (const BoneContact& c : contacts[self])
    if (c.other == other) return &c;
  return nullptr;
}

}  // namespace repose
