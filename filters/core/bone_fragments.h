#pragma once
// Where the fragments of the bone labels go (a bone voxel ends in exactly one bone, or is left as
// soft tissue and reported): a fragment keeps no label of its own, because once a label is split
// its value names one side only (a right toe under the left foot's value tears off when the left
// foot moves).
#include "rig_bones.h"

namespace repose {

/// Gives every component that chooseBones left out (needs findBoneBoundaries) to a bone:
/// 1. the bone it touches (26-neighbours; through fragments already placed): of several, its own
///    kind on a compatible side first, then a compatible side, then the largest contact;
/// 2. else the nearest bone on its side of the mid-sagittal plane (fragments within
///    options.midlineBandMm of it, and midline bones, fit either side), its own kind first, within
///    the fragment distance (AutoRigOptions::maxFragmentDistanceMm / ...Voxels);
/// 3. else it is left as soft tissue: it gets the value of a new soft label
///    "unassigned_bone_fragments" (added to out.table; out.unassignedValue).
/// Steps 1 and 2 repeat until nothing moves, so a chain of fragments follows the bone it hangs on.
/// Fills out.fragments (each with its bone and why) and adds them to their bone (RigBone::voxels,
/// lo, hi; call findBoneBoundaries again to include them in its surface).
void assignFragments(const LabelVolume& labels, const AutoRigOptions& options, RigBones& out);

/// The labels with every bone voxel under its bone's value: split bones under their new values,
/// fragments under the bone they went to (or unassignedValue). Other voxels are unchanged.
LabelVolume relabelBones(const LabelVolume& labels, const RigBones& bones);

}  // namespace repose
