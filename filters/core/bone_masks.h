#pragma once
// The voxels of each bone of a skeleton, one bone at a time: the surface extractor contours each
// on its own crop rather than on the whole grid.
#include <functional>

#include "image_grid.h"
#include "skeleton.h"

namespace repose {

/// Calls visit(label, mask) for each label of the skeleton's joints (ascending, each once), mask the
/// label's 0/1 voxels cropped to its bounding box (see labelCrop; on the whole grid when a label
/// exceeds kMaxBoxedLabel), or null when the label has no voxel in `labels`.
void forEachBoneMask(const LabelVolume& labels, const Skeleton& skeleton,
                     const std::function<void(int label, const MaskVolume* mask)>& visit);

}  // namespace repose
