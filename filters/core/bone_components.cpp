#include "bone_components.h"

#include <algorithm>
#include <climits>
#include <map>
#include <stdexcept>

namespace repose {

namespace {

using V3 = Eigen::Vector3d;

// Breadth-first flood of one component from voxel s.
BoneComponent flood(const LabelVolume& labels, std::size_t s, int id, std::vector<std::int32_t>& comp,
                    std::vector<std::size_t>& queue) {
  const ImageGrid& grid = labels.grid;
  const int nx = grid.dims[0], ny = grid.dims[1];
  const std::ptrdiff_t stride[3] = {1, nx, std::ptrdiff_t(nx) * ny};
  const int v = labels.data[s];
  BoneComponent c;
  c.label = v;
  c.lo = {INT_MAX, INT_MAX, INT_MAX};
  V3 indexSum = V3::Zero();
  queue.assign(1, s);
  comp[s] = id;
  for (std::size_t q = 0; q < queue.size(); ++q) {
    const std::size_t p = queue[q];
    const int ijk[3] = {int(p % nx), int((p / nx) % ny), int(p / (std::size_t(nx) * ny))};
    ++c.count;
    indexSum += V3(ijk[0], ijk[1], ijk[2]);
    for (int d = 0; d < 3; ++d) {
      c.lo[d] = std::min(c.lo[d], ijk[d]);
      c.hi[d] = std::max(c.hi[d], ijk[d]);
      if (ijk[d] == 0 || ijk[d] == grid.dims[d] - 1) c.cut = true;
      for (int sgn : {-1, 1}) {
        const int nd = ijk[d] + sgn;
        if (nd < 0 || nd >= grid.dims[d]) continue;
        const std::size_t np = std::size_t(std::ptrdiff_t(p) + sgn * stride[d]);
        if (comp[np] < 0 && labels.data[np] == v) {
          comp[np] = id;
          queue.push_back(np);
        }
      }
    }
  }
  c.centroid = grid.indexToPhysical(indexSum / double(c.count));
  return c;
}

enum class Capacity { One, OnePerSide, Any };

Capacity capacityOf(const BoneName& b) {
  if (!b.known()) return Capacity::Any;
  if (isMidlineBone(b.type) || b.side != BoneSide::None) return Capacity::One;
  return Capacity::OnePerSide;
}

BoneSide sideOfX(double x, double midX) { return x > midX ? BoneSide::Left : BoneSide::Right; }

}  // namespace

void findBoneComponents(const LabelVolume& labels, const LabelTable& table, RigBones& out) {
  int maxLabel = 0;
  for (std::int32_t v : labels.data) maxLabel = std::max<int>(maxLabel, v);
  std::vector<char> isBone(std::size_t(maxLabel) + 1, 0);
  for (const LabelInfo& l : table.labels)
    if (l.kind == LabelKind::Bone && l.value >= 0 && l.value <= maxLabel) isBone[l.value] = 1;
  out.componentOf.assign(labels.data.size(), -1);
  out.components.clear();
  std::vector<std::size_t> queue;
  for (std::size_t s = 0; s < labels.data.size(); ++s) {
    const int v = labels.data[s];
    if (v <= 0 || !isBone[v] || out.componentOf[s] >= 0) continue;
    out.components.push_back(flood(labels, s, int(out.components.size()), out.componentOf, queue));
  }
  if (out.components.empty())
    throw std::invalid_argument("no bone voxels: no label of the volume is a bone in " +
                                (table.source.empty() ? std::string("the label table") : table.source) +
                                " (give a table with kind 'bone', or name the bones in the skeleton by hand)");
}

namespace {

// x (mm) of the mid-sagittal plane: the voxel-weighted mean x of each label's largest component,
// of the midline bones' labels when there are any.
double midSagittalX(const LabelTable& table, const std::vector<BoneComponent>& comps,
                    const std::map<int, std::vector<int>>& compsOfLabel) {
  double sumMid = 0, nMid = 0, sumAll = 0, nAll = 0;
  for (const auto& [label, list] : compsOfLabel) {
    const BoneComponent& c = comps[list[0]];
    const double n = double(c.count);
    sumAll += n * c.centroid.x();
    nAll += n;
    if (isMidlineBone(recogniseBone(table.nameOf(label)).type)) {
      sumMid += n * c.centroid.x();
      nMid += n;
    }
  }
  return nMid > 0 ? sumMid / nMid : sumAll / nAll;
}

// Component statistics from its voxels (after a split).
void restat(const ImageGrid& grid, const std::vector<std::size_t>& voxels, BoneComponent& c) {
  const int nx = grid.dims[0], ny = grid.dims[1];
  c.count = voxels.size();
  c.lo = {INT_MAX, INT_MAX, INT_MAX};
  c.hi = {-1, -1, -1};
  c.cut = false;
  V3 sum = V3::Zero();
  for (std::size_t p : voxels) {
    const int ijk[3] = {int(p % nx), int((p / nx) % ny), int(p / (std::size_t(nx) * ny))};
    sum += V3(ijk[0], ijk[1], ijk[2]);
    for (int d = 0; d < 3; ++d) {
      c.lo[d] = std::min(c.lo[d], ijk[d]);
      c.hi[d] = std::max(c.hi[d], ijk[d]);
      c.cut = c.cut || ijk[d] == 0 || ijk[d] == grid.dims[d] - 1;
    }
  }
  c.centroid = grid.indexToPhysical(sum / double(c.count));
}

// A paired bone labelled without a side whose two sides touch (knees together, feet together)
// forms one component across the midline: halve it at the mid-sagittal plane when each side holds
// a bone's worth (hip bones excepted: they join the pelvis anyway).
void splitAcrossMidline(const ImageGrid& grid, const LabelTable& table, const AutoRigOptions& options,
                        double secondMinVolume, RigBones& out) {
  std::vector<char> candidate(out.components.size(), 0);
  for (std::size_t c = 0; c < out.components.size(); ++c) {
    const BoneName b = recogniseBone(table.nameOf(out.components[c].label));
    const BoneComponent& comp = out.components[c];
    double xlo = 1e300, xhi = -1e300;  // physical x range of its box's corners
    for (int corner = 0; corner < 8; ++corner) {
      const V3 ijk((corner & 1 ? comp.hi : comp.lo)[0], (corner & 2 ? comp.hi : comp.lo)[1],
                   (corner & 4 ? comp.hi : comp.lo)[2]);
      const double x = grid.indexToPhysical(ijk).x();
      xlo = std::min(xlo, x);
      xhi = std::max(xhi, x);
    }
    candidate[c] = isPairedBone(b.type) && b.side == BoneSide::None && b.type != BoneType::HipBone &&
                   xlo < out.midX && xhi > out.midX;
  }
  std::vector<std::vector<std::size_t>> left(out.components.size()), right(out.components.size());
  const int nx = grid.dims[0], ny = grid.dims[1];
  for (std::size_t p = 0; p < out.componentOf.size(); ++p) {
    const int c = out.componentOf[p];
    if (c < 0 || !candidate[c]) continue;
    const V3 x = grid.indexToPhysical(V3(double(p % nx), double((p / nx) % ny), double(p / (std::size_t(nx) * ny))));
    (x.x() > out.midX ? left : right)[c].push_back(p);
  }
  for (std::size_t c = 0; c < candidate.size(); ++c) {
    if (!candidate[c]) continue;
    const double least = std::max({double(options.minComponentVoxels),
                                   options.minBoneFraction * double(out.components[c].count), secondMinVolume});
    if (double(left[c].size()) < least || double(right[c].size()) < least) continue;
    BoneComponent half = out.components[c];
    half.halved = true;
    restat(grid, left[c], out.components[c]);
    out.components[c].halved = true;
    restat(grid, right[c], half);
    const int id = int(out.components.size());
    for (std::size_t p : right[c]) out.componentOf[p] = id;
    out.components.push_back(half);
  }
}

std::map<int, std::vector<int>> componentsOfLabels(const std::vector<BoneComponent>& comps) {
  std::map<int, std::vector<int>> m;  // largest first
  for (int c = 0; c < int(comps.size()); ++c) m[comps[c].label].push_back(c);
  for (auto& [label, list] : m)
    std::stable_sort(list.begin(), list.end(), [&](int a, int b) { return comps[a].count > comps[b].count; });
  return m;
}

}  // namespace

void chooseBones(const ImageGrid& grid, const LabelTable& table, const AutoRigOptions& options, RigBones& out) {
  const double voxelVolume = grid.spacing.prod();
  out.midX = midSagittalX(table, out.components, componentsOfLabels(out.components));
  splitAcrossMidline(grid, table, options, options.minBoneVolumeMm3 / voxelVolume, out);
  const auto& comps = out.components;
  const std::map<int, std::vector<int>> compsOfLabel = componentsOfLabels(comps);

  out.table = table;
  int nextValue = 0;
  for (const BoneComponent& c : comps) nextValue = std::max(nextValue, c.label);
  for (const LabelInfo& l : table.labels) nextValue = std::max(nextValue, l.value);
  ++nextValue;
  out.bones.clear();
  out.boneOfComponent.assign(comps.size(), -1);
  for (const auto& [label, list] : compsOfLabel) {
    const std::string base = table.nameOf(label);
    const BoneName anatomy = recogniseBone(base);
    const BoneComponent& main = comps[list[0]];
    if (int(main.count) < options.minComponentVoxels) continue;  // all fragments
    const double secondMin = std::max({double(options.minComponentVoxels), options.minBoneFraction * double(main.count),
                                       options.minBoneVolumeMm3 / voxelVolume});
    std::vector<int> chosen{list[0]};
    const Capacity capacity = capacityOf(anatomy);
    const BoneSide mainSide = sideOfX(main.centroid.x(), out.midX);
    for (std::size_t r = 1; r < list.size() && capacity != Capacity::One; ++r) {
      const BoneComponent& c = comps[list[r]];
      if (double(c.count) < secondMin) break;  // the rest are smaller still
      if (capacity == Capacity::Any) chosen.push_back(list[r]);
      else if (sideOfX(c.centroid.x(), out.midX) != mainSide) {
        chosen.push_back(list[r]);
        break;
      }
    }
    const bool sided = capacity == Capacity::OnePerSide && chosen.size() == 2;
    for (std::size_t r = 0; r < chosen.size(); ++r) {
      const BoneComponent& c = comps[chosen[r]];
      RigBone b;
      b.comp = chosen[r];
      b.sourceLabel = label;
      b.value = r == 0 ? label : nextValue++;
      b.anatomy = anatomy;
      if (b.anatomy.side == BoneSide::None && !isMidlineBone(anatomy.type) &&
          std::abs(c.centroid.x() - out.midX) > options.midlineBandMm)
        b.anatomy.side = sideOfX(c.centroid.x(), out.midX);  // a bone across the midline has none
      b.name = chosen.size() == 1 ? base
               : sided            ? base + (b.anatomy.side == BoneSide::Left ? "_left" : "_right")
                                  : base + "_" + std::to_string(r + 1);
      b.voxels = c.count;
      b.centroid = c.centroid;
      b.lo = c.lo;
      b.hi = c.hi;
      b.cut = c.cut;
      out.boneOfComponent[chosen[r]] = int(out.bones.size());
      if (chosen.size() > 1) {  // the split bones' names, in the source label's colour
        const LabelInfo* source = table.find(label);
        LabelInfo info = source ? *source : LabelInfo{};
        info.value = b.value;
        info.name = b.name;
        info.kind = LabelKind::Bone;
        auto it = std::find_if(out.table.labels.begin(), out.table.labels.end(),
                               [&](const LabelInfo& l) { return l.value == b.value; });
        if (it != out.table.labels.end()) *it = info;
        else out.table.labels.push_back(info);
      }
      out.bones.push_back(std::move(b));
    }
  }
  if (out.bones.empty())
    throw std::invalid_argument("every bone label has fewer than " + std::to_string(options.minComponentVoxels) +
                                " connected voxels");
}

}  // namespace repose
