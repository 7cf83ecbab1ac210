#pragma once
// Where the fragments of the bone labels go (a bone voxel ends in exactly one bone, or is left as
// soft tissue and reported): a fragment keeps no label of its own, because once a label is split
// its value names one side only (a right toe under the left foot's value tears off when the left
// foot moves).
#include "rig_bones.h"

namespace repose {

/// Gives every component that chooseBones left out (needs findBoneBoundaries) to a bone, its own
/// kind first because the label says what bone it is (a piece of a hip bone that touches the
/// femoral head stays with the hip bone):
/// 1. a bone of its own kind on a compatible side that it touches (26-neighbours, through pieces
///    already placed), else the nearest one within the fragment distance
///    (AutoRigOptions::maxFragmentDistanceMm / ...Voxels);
/// 2. else any bone it touches (a compatible side first, then the largest contact);
/// 3. else the nearest bone on its side within the fragment distance;
/// 4. else it is left as soft tissue: it gets the value of a new soft label
///    "unassigned_bone_fragments" (added to out.table; out.unassignedValue).
/// Sides: a fragment lies on the side of the mid-sagittal plane where its centroid is, or, within
/// options.midlineBandMm of it, on the side its label names (none: either side); midline bones fit
/// either side. The steps repeat until nothing moves, so a chain of pieces follows its bone.
/// Fills out.fragments (each with its bone and why) and adds them to their bone (RigBone::voxels,
/// lo, hi; call findBoneBoundaries again to include them in its surface).
void assignFragments(const LabelVolume& labels, const AutoRigOptions& options, RigBones& out);

/// The labels with every bone voxel under its bone's value: split bones under their new values,
/// fragments under the bone they went to (or unassignedValue). Other voxels are unchanged.
LabelVolume relabelBones(const LabelVolume& labels, const RigBones& bones);

}  // namespace repose
