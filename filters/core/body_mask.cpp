#include "body_mask.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <unordered_map>
#include <stdexcept>
#include <string>

#include "distance_transform.h"
#include "parallel_for.h"

namespace repose {

namespace {

void checkVolume(const char* what, const ImageGrid& grid, std::size_t size) {
  if (grid.dims[0] <= 0 || grid.dims[1] <= 0 || grid.dims[2] <= 0)
    throw std::invalid_argument(std::string(what) + ": the image has no voxels");
  if (size != grid.voxelCount())
    throw std::invalid_argument(std::string(what) + ": data holds " + std::to_string(size) +
                                " values but the grid has " + std::to_string(grid.voxelCount()) + " voxels");
}

// Visits, with 6-connectivity, every voxel whose value equals `from` reachable from the voxels of
// `starts`, and sets it to `to`. The queue holds the wavefront only (a surface, not the volume).
std::size_t flood3d(std::vector<std::uint8_t>& v, const std::array<int, 3>& d, std::deque<std::size_t>& queue,
                    std::uint8_t from, std::uint8_t to) {
  const std::size_t sx = 1, sy = std::size_t(d[0]), sz = std::size_t(d[0]) * d[1];
  std::size_t count = 0;
  while (!queue.empty()) {
    const std::size_t p = queue.front();
    queue.pop_front();
    ++count;
    const int i = int(p % sy), j = int((p / sy) % d[1]), k = int(p / sz);
    auto visit = [&](std::size_t q) {
      if (v[q] == from) {
        v[q] = to;
        queue.push_back(q);
      }
    };
    if (i > 0) visit(p - sx);
    if (i + 1 < d[0]) visit(p + sx);
    if (j > 0) visit(p - sy);
    if (j + 1 < d[1]) visit(p + sy);
    if (k > 0) visit(p - sz);
    if (k + 1 < d[2]) visit(p + sz);
  }
  return count;
}

// Keeps the largest 6-connected component of the non-zero voxels (values become 0/1).
void keepLargestComponent(std::vector<std::uint8_t>& v, const std::array<int, 3>& d) {
  constexpr std::uint8_t kFg = 1, kSeen = 2, kKeep = 3;
  std::size_t bestSeed = 0, bestSize = 0;
  std::deque<std::size_t> queue;
  for (std::size_t p = 0; p < v.size(); ++p) {
    if (v[p] != kFg) continue;
    v[p] = kSeen;
    queue.push_back(p);
    const std::size_t size = flood3d(v, d, queue, kFg, kSeen);
    if (size > bestSize) {
      bestSize = size;
      bestSeed = p;
    }
  }
  if (bestSize == 0) return;
  v[bestSeed] = kKeep;
  queue.push_back(bestSeed);
  flood3d(v, d, queue, kSeen, kKeep);
  for (auto& x : v) x = (x == kKeep) ? 1 : 0;
}

// Fills the background regions of each k-slice that are not 4-connected to the slice border.
void fillHolesPerSlice(std::vector<std::uint8_t>& v, const std::array<int, 3>& d) {
  const int nx = d[0], ny = d[1];
  parallelFor(std::size_t(d[2]), [&](std::size_t kb, std::size_t ke) {
    std::vector<std::uint8_t> outside;
    std::vector<int> stack;
    for (std::size_t k = kb; k < ke; ++k) {
      std::uint8_t* s = v.data() + k * std::size_t(nx) * ny;
      outside.assign(std::size_t(nx) * ny, 0);
      stack.clear();
      auto push = [&](int q) {
        if (!s[q] && !outside[q]) {
          outside[q] = 1;
          stack.push_back(q);
        }
      };
      for (int i = 0; i < nx; ++i) {
        push(i);
        push((ny - 1) * nx + i);
      }
      for (int j = 0; j < ny; ++j) {
        push(j * nx);
        push(j * nx + nx - 1);
      }
      while (!stack.empty()) {
        const int q = stack.back();
        stack.pop_back();
        const int i = q % nx, j = q / nx;
        if (i > 0) push(q - 1);
        if (i + 1 < nx) push(q + 1);
        if (j > 0) push(q - nx);
        if (j + 1 < ny) push(q + nx);
      }
      for (std::size_t q = 0; q < outside.size(); ++q)
        if (!outside[q]) s[q] = 1;
    }
  }, 1);
}

// Fills the background not 6-connected to the volume border.
void fillHoles3d(std::vector<std::uint8_t>& v, const std::array<int, 3>& d) {
  constexpr std::uint8_t kOutside = 2;
  std::deque<std::size_t> queue;
  auto seed = [&](int i, int j, int k) {
    const std::size_t p = (std::size_t(k) * d[1] + j) * d[0] + i;
    if (v[p] == 0) {
      v[p] = kOutside;
      queue.push_back(p);
    }
  };
  for (int k = 0; k < d[2]; ++k)
    for (int j = 0; j < d[1]; ++j) {
      seed(0, j, k);
      seed(d[0] - 1, j, k);
    }
  for (int k = 0; k < d[2]; ++k)
    for (int i = 0; i < d[0]; ++i) {
      seed(i, 0, k);
      seed(i, d[1] - 1, k);
    }
  for (int j = 0; j < d[1]; ++j)
    for (int i = 0; i < d[0]; ++i) {
      seed(i, j, 0);
      seed(i, j, d[2] - 1);
    }
  flood3d(v, d, queue, 0, kOutside);
  for (auto& x : v) x = (x == kOutside) ? 0 : 1;
}

// Opening of the CT part by a ball of radius r (mm) keeps the body and drops what is thinner than
// 2r (the table's shell, a cushion, cables); the largest piece of the opened mask and the labels is
// then grown back by r within the original mask, so the body's own surface is unchanged.
void removeThinStructures(MaskVolume& mask, const LabelVolume& labels, double r) {
  const std::size_t n = mask.data.size();
  MaskVolume outside = mask;
  for (auto& x : outside.data) x = x ? 0 : 1;
  const std::vector<float> toOutside = distanceToFeatures(outside);
  MaskVolume core = mask;  // eroded
  for (std::size_t p = 0; p < n; ++p) core.data[p] = toOutside[p] > r ? 1 : 0;
  const std::vector<float> toCore = distanceToFeatures(core);
  MaskVolume opened = mask;
  for (std::size_t p = 0; p < n; ++p) opened.data[p] = (toCore[p] <= r && mask.data[p]) || labels.data[p] != 0;
  keepLargestComponent(opened.data, opened.grid.dims);
  const std::vector<float> toOpened = distanceToFeatures(opened);
  const double grow = r + opened.grid.spacing.maxCoeff();
  for (std::size_t p = 0; p < n; ++p)
    mask.data[p] = (mask.data[p] && toOpened[p] <= grow) || labels.data[p] != 0 ? 1 : 0;
}

// Morphological closing by a ball of radius r (mm): dilation, then erosion, by distance transforms.
void close(MaskVolume& mask, double r) {
  const std::vector<float> toBody = distanceToFeatures(mask);
  MaskVolume outsideDilated = mask;
  for (std::size_t p = 0; p < mask.data.size(); ++p) outsideDilated.data[p] = toBody[p] > r ? 1 : 0;
  const std::vector<float> toOutside = distanceToFeatures(outsideDilated);
  for (std::size_t p = 0; p < mask.data.size(); ++p)
    mask.data[p] = mask.data[p] || toOutside[p] > r ? 1 : 0;
}

}  // namespace

bool labelsLeaveGaps(const LabelVolume& labels) {
  // The labels of the labelled voxels on the outside of the labelled region (a face on unlabelled).
  const ImageGrid& g = labels.grid;
  const auto& d = g.dims;
  std::unordered_map<std::int32_t, std::size_t> count;
  std::size_t outer = 0;
  for (int k = 0; k < d[2]; ++k)
    for (int j = 0; j < d[1]; ++j)
      for (int i = 0; i < d[0]; ++i) {
        const std::int32_t v = labels.at(i, j, k);
        if (v == 0) continue;
        const int n[6][3] = {{i - 1, j, k}, {i + 1, j, k}, {i, j - 1, k}, {i, j + 1, k}, {i, j, k - 1}, {i, j, k + 1}};
        for (const auto& q : n)
          if (g.contains(q[0], q[1], q[2]) && labels.at(q[0], q[1], q[2]) == 0) {
            ++count[v], ++outer;
            break;
          }
      }
  std::size_t largest = 0;
  for (const auto& [v, c] : count) largest = std::max(largest, c);
  return outer > 0 && 2 * largest < outer;
}

PosableComponentsReport keepPosableComponents(MaskVolume& mask, const LabelVolume& labels,
                                              const std::vector<int>& boneOfLabel, std::size_t minVoxels,
                                              double maxBridgeMm) {
  checkVolume("posable components: mask", mask.grid, mask.data.size());
  if (!mask.grid.sameGridAs(labels.grid) || labels.data.size() != mask.data.size())
    throw std::invalid_argument("posable components: the mask and the labels are on different grids");
  const ImageGrid& g = mask.grid;
  const std::size_t n = mask.data.size();
  const auto& d = g.dims;
  auto isBone = [&](std::size_t p) {
    const std::int32_t l = labels.data[p];
    return l >= 0 && std::size_t(l) < boneOfLabel.size() && boneOfLabel[l] >= 0;
  };
  // Components (6-connected), and whether each holds bone.
  std::vector<std::int32_t> comp(n, -1);
  std::vector<std::size_t> size;
  std::vector<char> hasBone, hasLabel;
  std::deque<std::size_t> queue;
  const std::size_t sy = std::size_t(d[0]), sz = sy * d[1];
  for (std::size_t s = 0; s < n; ++s) {
    if (!mask.data[s] || comp[s] >= 0) continue;
    const std::int32_t c = std::int32_t(size.size());
    size.push_back(0), hasBone.push_back(0), hasLabel.push_back(0);
    comp[s] = c;
    queue.push_back(s);
    while (!queue.empty()) {
      const std::size_t p = queue.front();
      queue.pop_front();
      ++size[c];
      hasBone[c] = hasBone[c] || isBone(p);
      hasLabel[c] = hasLabel[c] || labels.data[p] != 0;
      const int i = int(p % sy), j = int((p / sy) % d[1]), k = int(p / sz);
      const std::size_t nb[6] = {p - 1, p + 1, p - sy, p + sy, p - sz, p + sz};
      const bool ok[6] = {i > 0, i + 1 < d[0], j > 0, j + 1 < d[1], k > 0, k + 1 < d[2]};
      for (int q = 0; q < 6; ++q)
        if (ok[q] && mask.data[nb[q]] && comp[nb[q]] < 0) comp[nb[q]] = c, queue.push_back(nb[q]);
    }
  }
  PosableComponentsReport report;
  for (std::size_t c = 0; c < size.size(); ++c) report.kept += hasBone[c] ? 1 : 0;
  if (report.kept == 0) return report;  // nothing to bridge to: leave the mask for the caller's checks
  // Each component without bone, largest first: the shortest path through the background to a kept
  // voxel (a breadth-first search over 26-neighbours, bounded by maxBridgeMm), then three voxels thick.
  std::vector<std::size_t> order;
  for (std::size_t c = 0; c < size.size(); ++c)
    if (!hasBone[c]) order.push_back(c);
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return size[a] > size[b]; });
  const int maxSteps = int(std::ceil(maxBridgeMm / g.spacing.minCoeff()));
  std::unordered_map<std::int32_t, std::vector<std::size_t>> voxelsOf;  // components without bone
  for (std::size_t p = 0; p < n; ++p)
    if (comp[p] >= 0 && !hasBone[comp[p]]) voxelsOf[comp[p]].push_back(p);
  for (std::size_t c : order) {
    const std::vector<std::size_t>& own = voxelsOf[std::int32_t(c)];
    bool joined = false;
    if (size[c] >= minVoxels && hasLabel[c]) {
      std::unordered_map<std::size_t, std::size_t> from;  // background voxel -> the voxel it was reached from
      std::vector<std::size_t> frontier(own), next;
      std::size_t reached = n, reachedFrom = n;
      for (int step = 0; step < maxSteps && !frontier.empty() && reached == n; ++step) {
        next.clear();
        for (std::size_t p : frontier) {
          const int i = int(p % sy), j = int((p / sy) % d[1]), k = int(p / sz);
          for (int dk = -1; dk <= 1 && reached == n; ++dk)
            for (int dj = -1; dj <= 1 && reached == n; ++dj)
              for (int di = -1; di <= 1 && reached == n; ++di) {
                if (!g.contains(i + di, j + dj, k + dk)) continue;
                const std::size_t q = g.linearIndex(i + di, j + dj, k + dk);
                if (mask.data[q]) {
                  if (comp[q] >= 0 && hasBone[comp[q]]) reached = q, reachedFrom = p;
                } else if (from.emplace(q, p).second) {
                  next.push_back(q);
                }
              }
        }
        frontier.swap(next);
      }
      if (reached != n) {
        // Back from the kept voxel to the component, through background voxels, three voxels thick.
        for (std::size_t p = reachedFrom; !mask.data[p] || comp[p] != std::int32_t(c);) {
          const int i = int(p % sy), j = int((p / sy) % d[1]), k = int(p / sz);
          for (int dk = -1; dk <= 1; ++dk)
            for (int dj = -1; dj <= 1; ++dj)
              for (int di = -1; di <= 1; ++di)
                if (g.contains(i + di, j + dj, k + dk)) {
                  const std::size_t q = g.linearIndex(i + di, j + dj, k + dk);
                  if (!mask.data[q]) mask.data[q] = 1, ++report.bridgeVoxels;
                }
          const auto it = from.find(p);
          if (it == from.end()) break;
          p = it->second;
        }
        hasBone[c] = 1;  // now part of a posable piece: later components may bridge to it
        joined = true;
        ++report.bridged;
      }
    }
    if (!joined) {
      for (std::size_t p : own) mask.data[p] = 0;
      ++report.dropped;
      report.droppedVoxels += size[c];
    }
  }
  return report;
}

MaskVolume bodyMask(const LabelVolume& labels, const IntensityVolume* image, const BodyMaskOptions& options) {
  checkVolume("body mask: label volume", labels.grid, labels.data.size());
  if (image) {
    checkVolume("body mask: intensity image", image->grid, image->data.size());
    if (!labels.grid.sameGridAs(image->grid))
      throw std::invalid_argument(
          "body mask: the intensity image is not on the label volume's grid (dims, origin, spacing and "
          "direction must match); resample it onto the labels first");
  }
  MaskVolume mask;
  mask.grid = labels.grid;
  mask.data.assign(labels.data.size(), 0);
  const float threshold = float(options.bodyThreshold);
  parallelFor(mask.data.size(), [&](std::size_t b, std::size_t e) {
    for (std::size_t p = b; p < e; ++p)
      mask.data[p] = (labels.data[p] != 0 || (image && image->data[p] > threshold)) ? 1 : 0;
  }, 1 << 16);
  if (image && options.thinStructureMm > 0) removeThinStructures(mask, labels, options.thinStructureMm);
  if (options.closingMm > 0) close(mask, options.closingMm);

  const auto& d = mask.grid.dims;
  if (options.keepLargestComponent) keepLargestComponent(mask.data, d);
  if (options.fillHoles) {
    fillHolesPerSlice(mask.data, d);
    fillHoles3d(mask.data, d);
  }
  if (std::find(mask.data.begin(), mask.data.end(), std::uint8_t(1)) == mask.data.end())
    throw std::invalid_argument(
        "body mask is empty: no voxel has a non-zero label" +
        std::string(image ? " or an intensity above the body threshold (" + std::to_string(options.bodyThreshold) + ")"
                          : "") +
        "; check the label volume (and the threshold)");
  return mask;
}

MaskVolume peelOuterLayer(const MaskVolume& mask) {
  checkVolume("peel outer layer: mask", mask.grid, mask.data.size());
  MaskVolume out;
  out.grid = mask.grid;
  out.data.assign(mask.data.size(), 0);
  const auto& d = mask.grid.dims;
  const std::size_t sy = std::size_t(d[0]), sz = std::size_t(d[0]) * d[1];
  parallelFor(std::size_t(d[2]), [&](std::size_t kb, std::size_t ke) {
    for (int k = int(kb); k < int(ke); ++k)
      for (int j = 0; j < d[1]; ++j)
        for (int i = 0; i < d[0]; ++i) {
          const std::size_t p = k * sz + j * sy + i;
          if (!mask.data[p]) continue;
          // Voxels on the image border count as outer layer (outside the image is background).
          if (i == 0 || j == 0 || k == 0 || i == d[0] - 1 || j == d[1] - 1 || k == d[2] - 1) continue;
          if (mask.data[p - 1] && mask.data[p + 1] && mask.data[p - sy] && mask.data[p + sy] &&
              mask.data[p - sz] && mask.data[p + sz])
            out.data[p] = 1;
        }
  }, 1);
  return out;
}

}  // namespace repose

namespace repose {

void keepBoneVoxels(MaskVolume& peeled, const LabelVolume& labels, const std::vector<int>& boneOfLabel) {
  if (!peeled.grid.sameGridAs(labels.grid) || peeled.data.size() != labels.data.size())
    throw std::invalid_argument("keep bone voxels: mask and labels are on different grids");
  for (std::size_t v = 0; v < labels.data.size(); ++v) {
    const int label = labels.data[v];
    if (label >= 0 && std::size_t(label) < boneOfLabel.size() && boneOfLabel[label] >= 0) peeled.data[v] = 1;
  }
}

}  // namespace repose
