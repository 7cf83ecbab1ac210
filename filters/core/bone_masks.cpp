#include "bone_masks.h"

#include <algorithm>
#include <set>
#include <vector>

#include "label_boxes.h"

namespace repose {

void forEachBoneMask(const LabelVolume& labels, const Skeleton& skeleton,
                     const std::function<void(int label, const MaskVolume* mask)>& visit) {
  const std::vector<Eigen::AlignedBox3i> boxes = labelBoxes(labels);
  const Eigen::AlignedBox3i wholeGrid(
      Eigen::Vector3i::Zero(), Eigen::Vector3i(labels.grid.dims[0] - 1, labels.grid.dims[1] - 1, labels.grid.dims[2] - 1));
  std::set<int> boneLabels;
  for (const Joint& joint : skeleton.joints) boneLabels.insert(joint.labels.begin(), joint.labels.end());
  for (const int label : boneLabels) {
    const bool boxed = label > 0 && static_cast<std::size_t>(label) < boxes.size();
    const Eigen::AlignedBox3i box =
        boxes.empty() ? wholeGrid : boxed ? boxes[static_cast<std::size_t>(label)] : Eigen::AlignedBox3i();
    const MaskVolume crop = labelCrop(labels, label, box);
    const bool present = std::find(crop.data.begin(), crop.data.end(), 1) != crop.data.end();
    visit(label, present ? &crop : nullptr);
  }
}

}  // namespace repose
