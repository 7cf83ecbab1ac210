#include "meshing_grid.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

#include "parallel_for.h"

namespace repose {

namespace {

// Native spacing over coarse: 1 when the coarse spacing is (within rounding) the native one.
double binFactor(double nativeSpacing, double spacingMm) {
  return spacingMm > nativeSpacing * (1 + 1e-6) ? spacingMm / nativeSpacing : 1.0;
}

}  // namespace

ImageGrid meshingGrid(const ImageGrid& native, double spacingMm) {
  if (!(spacingMm >= 0) || !std::isfinite(spacingMm))
    throw std::invalid_argument("meshing grid: the spacing must be a finite number >= 0");
  ImageGrid g = native;
  Eigen::Vector3d firstCentre;
  for (int d = 0; d < 3; ++d) {
    const double f = binFactor(native.spacing[d], spacingMm);
    g.spacing[d] = native.spacing[d] * f;
    g.dims[d] = int(std::ceil(native.dims[d] / f - 1e-9));
    firstCentre[d] = 0.5 * f - 0.5;
  }
  g.origin = native.indexToPhysical(firstCentre);
  return g;
}

MeshingVolumes binToMeshingGrid(const MaskVolume& body, const LabelVolume& labels,
                                const std::vector<int>& boneOfLabel, const ImageGrid& coarse) {
  const ImageGrid& n = body.grid;
  if (!n.sameGridAs(labels.grid) || body.data.size() != n.voxelCount() || labels.data.size() != n.voxelCount())
    throw std::invalid_argument("meshing grid: the body mask and the labels are on different grids");
  // Native index range [begin, end) of every coarse index, per axis.
  std::array<std::vector<int>, 3> begin, end;
  for (int d = 0; d < 3; ++d) {
    const double f = coarse.spacing[d] / n.spacing[d];
    if (coarse.dims[d] <= 0 || f < 1 - 1e-6)
      throw std::invalid_argument("meshing grid: the coarse grid must not be finer than the scan");
    for (int I = 0; I < coarse.dims[d]; ++I) {
      begin[d].push_back(std::clamp(int(std::ceil(I * f - 0.5 - 1e-9)), 0, n.dims[d]));
      end[d].push_back(std::clamp(int(std::ceil((I + 1) * f - 0.5 - 1e-9)), 0, n.dims[d]));
    }
  }
  MeshingVolumes out;
  out.body.grid = out.bone.grid = coarse;
  out.body.data.assign(coarse.voxelCount(), 0);
  out.bone.data.assign(coarse.voxelCount(), -1);
  const auto boneOf = [&](std::int32_t label) {
    return label >= 0 && std::size_t(label) < boneOfLabel.size() ? boneOfLabel[label] : -1;
  };
  parallelFor(std::size_t(coarse.dims[2]), [&](std::size_t kb, std::size_t ke) {
    for (int K = int(kb); K < int(ke); ++K)
      for (int J = 0; J < coarse.dims[1]; ++J)
        for (int I = 0; I < coarse.dims[0]; ++I) {
          std::size_t total = 0, inside = 0;
          std::array<std::pair<int, int>, 4> bones{};  // (bone, voxels), the first four bones met
          int nBones = 0;
          for (int k = begin[2][K]; k < end[2][K]; ++k)
            for (int j = begin[1][J]; j < end[1][J]; ++j)
              for (int i = begin[0][I]; i < end[0][I]; ++i) {
                const std::size_t p = n.linearIndex(i, j, k);
                ++total;
                inside += body.data[p] != 0;
                const int b = boneOf(labels.data[p]);
                if (b < 0) continue;
                int slot = 0;
                while (slot < nBones && bones[slot].first != b) ++slot;
                if (slot == nBones) {
                  if (nBones == int(bones.size())) continue;
                  bones[nBones++] = {b, 0};
                }
                ++bones[slot].second;
              }
          const std::size_t q = coarse.linearIndex(I, J, K);
          int best = -1, bestCount = 0;
          for (int s = 0; s < nBones; ++s)
            if (bones[s].second > bestCount) best = bones[s].first, bestCount = bones[s].second;
          out.bone.data[q] = std::int16_t(best);
          out.body.data[q] = (total > 0 && 2 * inside >= total) || best >= 0 ? 1 : 0;
        }
  }, 1);
  return out;
}

}  // namespace repose
