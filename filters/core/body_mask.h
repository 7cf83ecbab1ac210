#pragma once
// The region to mesh: every non-background voxel, optionally united with CT above a threshold.
#include <optional>
#include <vector>

#include "image_grid.h"

namespace repose {

struct BodyMaskOptions {
  double bodyThreshold = -500.0;  ///< HU; CT voxels above it count as body
  /// mm: CT structures thinner than twice this (the table, its cushion, blankets, cables) are no
  /// body even where they touch it: the CT part is opened with a ball of this radius before its
  /// largest component is taken, then grown back within the CT by the same radius. 0 = off.
  double thinStructureMm = 5.0;
  bool fillHoles = true;          ///< fill cavities (slice by slice along k and in 3-D)
  bool keepLargestComponent = true;
};

/// mask = labels != 0 (∪ CT above the threshold, without the table), holes filled, largest
/// 6-connected component kept.
/// Throws std::invalid_argument when the image is on a different grid or the mask is empty.
MaskVolume bodyMask(const LabelVolume& labels, const IntensityVolume* image, const BodyMaskOptions& options);

/// Removes the outer voxel layer (6-neighbourhood erosion), so parts that touch skin-to-skin in the
/// scan (an arm against the torso, the thighs) are not welded together by the mesh.
MaskVolume peelOuterLayer(const MaskVolume& mask);

}  // namespace repose

namespace repose {

/// Puts bone voxels back into a peeled mask: peeling is for skin-to-skin contacts, and a bone
/// cut by the field of view or lying under a thin skin must stay in the mesh whole.
/// boneOfLabel maps label -> bone or -1 (labels beyond its size are not bone).
void keepBoneVoxels(MaskVolume& peeled, const LabelVolume& labels, const std::vector<int>& boneOfLabel);

}  // namespace repose
