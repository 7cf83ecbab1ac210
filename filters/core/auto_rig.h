#pragma once
// Automatic skeleton from bone labels: bones split into connected components, adjacent bones found
// by their surface gap, joint centres placed at the articulations, a tree rooted at the pelvis.
#include <cstddef>
#include <string>
#include <vector>

#include "image_grid.h"
#include "label_table.h"
#include "skeleton.h"

namespace repose {

struct AutoRigOptions {
  /// Two bones are adjacent when their surfaces are at most this far apart (mm) ...
  double maxGapMm = 6.0;
  /// ... or at most this many voxels (of the largest spacing), whichever is larger: a coarse image
  /// cannot show a joint space narrower than a couple of voxels, and a hinge whose bones taper
  /// toward the joint (as the phantom's knees and elbows do) shows a wider one (30 mm at the tiny
  /// phantom's elbows, 3 of its 10 mm voxels).
  double maxGapVoxels = 3.5;
  /// Connected components smaller than noiseFraction x (the label's largest component), or than
  /// minComponentVoxels, are segmentation noise: ignored (left in the volume, in no bone).
  double noiseFraction = 0.01;
  int minComponentVoxels = 8;
  /// Plausible radii (mm) of a ball joint's head (femoral, humeral); fits outside are rejected.
  double minBallRadiusMm = 5.0;
  double maxBallRadiusMm = 40.0;
};

/// What autoRig found, for the user: every bone (kept or left out, and why) and every joint.
struct AutoRigReport {
  struct Bone {
    std::string name;        ///< label name, with a side or index suffix when its label was split
    int label = 0;           ///< label value in AutoRigResult::labels
    int sourceLabel = 0;     ///< label value in the input volume
    std::size_t voxels = 0;
    bool cutByFieldOfView = false;  ///< touches the image boundary
    std::string joint;       ///< joint it belongs to; empty when left out
    std::string note;        ///< why it was left out, merged or split ("" when nothing to say)
  };
  struct JointInfo {
    std::string name, parent, method;  ///< method: "root centroid", "sphere fit", "contact centroid"
    double gapMm = 0;        ///< surface gap to the parent bone (centre distance minus a voxel)
    double radiusMm = 0;     ///< fitted head radius (sphere fit only)
    double fitRmsMm = 0;     ///< sphere fit residual (sphere fit only)
  };
  std::vector<Bone> bones;
  std::vector<JointInfo> joints;
  std::vector<std::string> missingBones;  ///< bone names of the table with no (or only noise) voxels
  std::size_t noiseComponents = 0, noiseVoxels = 0;
  double seconds = 0;
  /// Human-readable summary, one item per line.
  std::string text() const;
};

struct AutoRigResult {
  /// Joints parents-first; the root is "pelvis" when hip/sacrum/pelvis labels are present.
  Skeleton skeleton;
  /// The input volume where every label holding several bones is split: its largest component
  /// keeps the value, the others get new values (above every value in use). skeleton.json can only
  /// name bones by label, so write and use this volume with the skeleton (it equals the input when
  /// nothing was split).
  LabelVolume labels;
  /// The input table extended with the split components' names (femur -> femur_left, femur_right).
  LabelTable table;
  AutoRigReport report;
};

/// Builds a skeleton from the bone labels of `labels` (kinds from `table`).
/// - Bones: each Bone label's 6-connected components; small ones are noise. A label with several
///   components becomes several bones, named by side of the mid-sagittal plane (mean x of all bone
///   voxels; LPS +x = patient left) when there are two on opposite sides, else name_1, name_2, ...
/// - Adjacency: surface gap (voxel-centre distance minus one voxel) within the options' limit.
/// - Fused groups: hip bones, sacrum, vertebra S1, coccyx that touch form the root "pelvis"; ribs,
///   ribcage, sternum join the vertebra (or spine) they are closest to.
/// - Tree: maximum spanning tree (smallest gap first) from the pelvis group, else from the largest
///   bone near the mid-sagittal plane. Bones not reached are reported and left out.
/// - Joint centre (between a bone and its parent): femur/humerus (and unknown bones whose contact
///   is a ball in a socket): centre of a sphere fitted to the child's articular surface; otherwise
///   the midpoint of the two bones' closest surface patches. Root: the centroid of its bones.
/// - Names: phantom and TotalSegmentator names map onto pose names (femur_left -> left_hip,
///   tibia_left -> left_knee, foot_left -> left_ankle, humerus_left -> left_shoulder,
///   forearm_left -> left_elbow, hand_left -> left_wrist, skull -> neck, the vertebra on the pelvis
///   -> spine, vertebrae_L4 -> vertebra_L4, scapula_left -> left_scapula, clavicula_left ->
///   left_clavicle); other bones keep their label name.
/// Bones cut by the field of view are kept (their other end still articulates) and reported.
/// Throws std::invalid_argument when the volume is empty or inconsistent, or has no bone voxels.
AutoRigResult autoRig(const LabelVolume& labels, const LabelTable& table, const AutoRigOptions& options = {});

/// Joint name autoRig gives a bone named `boneName` ("" when it keeps its own name); exposed for
/// motion mapping and tests.
std::string standardJointName(const std::string& boneName);

}  // namespace repose
