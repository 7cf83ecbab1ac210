#include "nearest_bones.h"

#include <cmath>
#include <limits>
#include <queue>
#include <stdexcept>
#include <tuple>

namespace repose {

NearestBones nearestBones(const MaskVolume& body, const Volume<std::int16_t>& bone) {
  const ImageGrid& g = body.grid;
  if (!g.sameGridAs(bone.grid) || body.data.size() != g.voxelCount() || bone.data.size() != g.voxelCount())
    throw std::invalid_argument("nearest bones: the body mask and the bone map are on different grids");
  const std::size_t n = g.voxelCount();
  constexpr float kInf = std::numeric_limits<float>::infinity();
  NearestBones r;
  r.first.assign(n, -1);
  r.second.assign(n, -1);
  r.firstMm.assign(n, kInf);
  r.secondMm.assign(n, kInf);

  // The 26 neighbour offsets and their lengths.
  struct Step {
    int di, dj, dk;
    float mm;
  };
  std::vector<Step> steps;
  for (int dk = -1; dk <= 1; ++dk)
    for (int dj = -1; dj <= 1; ++dj)
      for (int di = -1; di <= 1; ++di)
        if (di || dj || dk)
          steps.push_back({di, dj, dk,
                           float(std::sqrt(std::pow(di * g.spacing[0], 2) + std::pow(dj * g.spacing[1], 2) +
                                           std::pow(dk * g.spacing[2], 2)))});

  using Entry = std::tuple<float, std::size_t, std::int16_t>;  // distance, voxel, bone
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> queue;
  // Offers `bone` at distance d to voxel v: kept if it improves v's first or second bone.
  auto offer = [&](std::size_t v, std::int16_t b, float d) {
    if (b == r.first[v]) {
      if (d < r.firstMm[v]) r.firstMm[v] = d, queue.emplace(d, v, b);
    } else if (d < r.firstMm[v]) {
      r.second[v] = r.first[v], r.secondMm[v] = r.firstMm[v];
      r.first[v] = b, r.firstMm[v] = d;
      queue.emplace(d, v, b);
    } else if (d < r.secondMm[v]) {  // a better second (the same bone's or another's)
      r.second[v] = b, r.secondMm[v] = d;
      queue.emplace(d, v, b);
    }
  };
  for (std::size_t v = 0; v < n; ++v)
    if (bone.data[v] >= 0 && body.data[v]) offer(v, bone.data[v], 0.f);

  const int nx = g.dims[0], ny = g.dims[1], nz = g.dims[2];
  while (!queue.empty()) {
    const auto [d, v, b] = queue.top();
    queue.pop();
    // Stale entries: the voxel has since taken a shorter distance for this bone, or dropped it.
    const bool current = (b == r.first[v] && d == r.firstMm[v]) || (b == r.second[v] && d == r.secondMm[v]);
    if (!current) continue;
    const int i = int(v % nx), j = int((v / nx) % ny), k = int(v / (std::size_t(nx) * ny));
    for (const Step& s : steps) {
      const int a = i + s.di, bj = j + s.dj, c = k + s.dk;
      if (a < 0 || bj < 0 || c < 0 || a >= nx || bj >= ny || c >= nz) continue;
      const std::size_t w = g.linearIndex(a, bj, c);
      if (body.data[w]) offer(w, b, d + s.mm);
    }
  }
  return r;
}

}  // namespace repose
