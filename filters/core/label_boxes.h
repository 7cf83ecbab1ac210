#pragma once
// Where each label of a label volume lies: its index-space bounding box, and the 0/1 mask of one
// label cropped to it. The surface extractor contours each bone on its own crop; the posed volume's
// rigid-bone pass visits only the voxels near each bone.
#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "image_grid.h"

namespace repose {

/// Largest label value labelBoxes() keeps a box for (one box per value up to it).
constexpr std::int32_t kMaxBoxedLabel = 1 << 20;

/// Index-space bounding box of every positive label value (entry l for value l; empty boxes for
/// values not present). Empty (not usable) if a label exceeds kMaxBoxedLabel. Threaded over fixed
/// chunks of slices, so the result does not depend on the thread count.
std::vector<Eigen::AlignedBox3i> labelBoxes(const LabelVolume& labels);

/// 1 where `labels` holds `label`, 0 elsewhere, on the part of its grid inside `box` (index space,
/// inclusive; the crop keeps the grid's spacing and direction, its origin at the box's first voxel).
MaskVolume labelCrop(const LabelVolume& labels, std::int32_t label, const Eigen::AlignedBox3i& box);

}  // namespace repose
