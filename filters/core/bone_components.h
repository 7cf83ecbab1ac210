#pragma once
// Which voxels of a label volume form which bones: the 6-connected components of the bone labels,
// and which components are bones of their own (rule: AutoRigOptions::minBoneFraction ...). A
// label holding one bone per side (femur, for both femurs) is split by side of the mid-sagittal
// plane; every other component is left as a fragment for bone_fragments to place.
#include "rig_bones.h"

namespace repose {

/// Components of the labels the table calls bone; fills componentOf and components.
/// Throws std::invalid_argument when there is no bone voxel.
void findBoneComponents(const LabelVolume& labels, const LabelTable& table, RigBones& out);

/// Chooses the bones among the components (needs findBoneComponents) and names them:
/// - a label's largest component is a bone (at least options.minComponentVoxels voxels);
/// - a paired bone named without a side (femur, scapula, foot) may hold one more bone: the
///   largest component on the other side of the mid-sagittal plane; names get _left/_right;
/// - a label the rig does not recognise may hold any number (name_1, name_2, ...);
/// - a midline bone (skull, mandible, vertebra, sternum, sacrum) or a named side holds one;
/// - a second bone needs minBoneFraction of the largest component, minBoneVolumeMm3 and
///   minComponentVoxels.
/// The first bone of a label keeps its value, the others get new values above every value in use
/// (out.table gains their names). Sets out.midX: the voxel-weighted mean x of the midline bones,
/// or of all bones when there are none. Throws std::invalid_argument when no component is a bone.
void chooseBones(const ImageGrid& grid, const LabelTable& table, const AutoRigOptions& options, RigBones& out);

}  // namespace repose
