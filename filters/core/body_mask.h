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
  /// mm: a morphological closing of the labels by a ball of this radius, where the labels alone
  /// make the body (no CT, no skin label): organs, muscles and bones segmented apart leave gaps
  /// that are body too. 0 = off.
  double closingMm = 0;
  bool fillHoles = true;          ///< fill cavities (slice by slice along k and in 3-D)
  bool keepLargestComponent = true;
};

/// mask = labels != 0 (∪ CT above the threshold, without the table), holes filled, largest
/// 6-connected component kept.
/// Throws std::invalid_argument when the image is on a different grid or the mask is empty.
MaskVolume bodyMask(const LabelVolume& labels, const IntensityVolume* image, const BodyMaskOptions& options);

/// Whether the labels alone leave gaps in the body: no single label makes half of the outside of
/// the labelled region (a body labelled as a whole has one there, its skin or soft tissue; organs
/// and bones labelled alone show many). Such a body is closed (BodyMaskOptions::closingMm) before
/// meshing, which would fill the creases between touching parts of a body that has a skin.
bool labelsLeaveGaps(const LabelVolume& labels);

struct PosableComponentsReport {
  int kept = 0;       ///< components holding bone voxels
  int bridged = 0;    ///< components without bone joined to the nearest kept one by a bridge of voxels
  int dropped = 0;    ///< components without bone too small or too far to bridge
  std::size_t bridgeVoxels = 0, droppedVoxels = 0;
};

/// Keeps every 6-connected component of `mask` that holds a bone voxel (boneOfLabel: label -> bone
/// or -1) and joins each other labelled component of at least `minVoxels` to the nearest kept voxel within
/// `maxBridgeMm` by a bridge of voxels (the shortest 26-path through the background, three voxels
/// thick): the mesh then reaches it, and it moves with the anatomy it is bridged to (an eye
/// segmented apart from the head's tissue). Others are dropped (a piece of CT without any label, such
/// as a table's separate leg, is no anatomy). Nothing labelled is lost that can be posed.
PosableComponentsReport keepPosableComponents(MaskVolume& mask, const LabelVolume& labels,
                                              const std::vector<int>& boneOfLabel, std::size_t minVoxels = 27,
                                              double maxBridgeMm = 50.0);

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
