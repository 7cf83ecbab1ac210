#include "label_boxes.h"

#include <algorithm>
#include <stdexcept>

#include "parallel_for.h"

namespace repose {

std::vector<Eigen::AlignedBox3i> labelBoxes(const LabelVolume& labels) {
  if (labels.data.size() != labels.grid.voxelCount())
    throw std::invalid_argument("label boxes: the volume's size does not match its grid");
  std::int32_t maxLabel = 0;
  for (const std::int32_t l : labels.data) maxLabel = std::max(maxLabel, l);
  if (maxLabel > kMaxBoxedLabel) return {};
  const auto& rd = labels.grid.dims;
  // Fixed chunks of slices in parallel, then merged.
  const std::size_t nLabels = std::size_t(maxLabel) + 1;
  const std::size_t nChunks = std::max<std::size_t>(1, std::min<std::size_t>(64, std::size_t(rd[2])));
  std::vector<std::vector<Eigen::AlignedBox3i>> chunkBox(nChunks);
  parallelFor(nChunks, [&](std::size_t cb, std::size_t ce) {
    for (std::size_t c = cb; c < ce; ++c) {
      auto& box = chunkBox[c];
      box.resize(nLabels);
      for (int k = int(c * std::size_t(rd[2]) / nChunks); k < int((c + 1) * std::size_t(rd[2]) / nChunks); ++k)
        for (int j = 0; j < rd[1]; ++j) {
          const std::int32_t* row = labels.data.data() + labels.grid.linearIndex(0, j, k);
          for (int i = 0; i < rd[0]; ++i)
            if (row[i] > 0) box[std::size_t(row[i])].extend(Eigen::Vector3i(i, j, k));
        }
    }
  }, 1);
  std::vector<Eigen::AlignedBox3i> boxes(nLabels);
  for (const auto& box : chunkBox)
    for (std::size_t l = 0; l < nLabels; ++l)
      if (!box[l].isEmpty()) boxes[l].extend(box[l]);
  return boxes;
}

MaskVolume labelCrop(const LabelVolume& labels, std::int32_t label, const Eigen::AlignedBox3i& box) {
  MaskVolume crop;
  crop.grid = labels.grid;
  if (box.isEmpty()) {
    crop.grid.dims = {0, 0, 0};
    return crop;
  }
  const Eigen::Vector3i lo = box.min().cwiseMax(0);
  const Eigen::Vector3i hi = box.max().cwiseMin(Eigen::Vector3i(labels.grid.dims[0], labels.grid.dims[1], labels.grid.dims[2]) -
                                                Eigen::Vector3i::Ones());
  crop.grid.dims = {hi[0] - lo[0] + 1, hi[1] - lo[1] + 1, hi[2] - lo[2] + 1};
  crop.grid.origin = labels.grid.indexToPhysical(lo.cast<double>());
  crop.data.resize(crop.grid.voxelCount());
  for (int k = lo[2]; k <= hi[2]; ++k)
    for (int j = lo[1]; j <= hi[1]; ++j)
      for (int i = lo[0]; i <= hi[0]; ++i)
        crop.at(i - lo[0], j - lo[1], k - lo[2]) = labels.at(i, j, k) == label ? 1 : 0;
  return crop;
}

}  // namespace repose
