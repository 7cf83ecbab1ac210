#pragma once
// Automatic skeleton from bone labels: bones found as connected components (a label holding both
// sides split by side, fragments given to the bone they belong to), fused by anatomy (pelvis,
// forearm, shank, ribs with the spine), a tree whose parents anatomy allows, joint centres at the
// articulations, and joint names from a fixed vocabulary (anatomy_names.h).
#include <cstddef>
#include <string>
#include <vector>

#include "anatomy_names.h"
#include "image_grid.h"
#include "label_table.h"
#include "rig_bones.h"
#include "skeleton.h"

namespace repose {

/// What autoRig found, for the user: every bone (kept or left out, and why), every fragment and
/// where it went, and every joint.
struct AutoRigReport {
  struct Bone {
    std::string name;        ///< label name, with a side or index suffix when its label was split
    int label = 0;           ///< label value in AutoRigResult::labels
    int sourceLabel = 0;     ///< label value in the input volume
    std::size_t voxels = 0;  ///< its main component plus the fragments it received
    bool cutByFieldOfView = false;  ///< touches the image boundary
    std::string joint;       ///< joint it belongs to; empty when left out
    std::string note;        ///< why it was left out, split or rides along ("" when nothing to say)
  };
  struct Fragment {
    std::string label;       ///< name of its label in the input table
    int sourceLabel = 0;
    std::size_t voxels = 0;
    std::string bone;        ///< the bone it went to; empty when left as soft tissue
    int value = 0;           ///< its label value in AutoRigResult::labels
    std::string why;
  };
  struct JointInfo {
    std::string name, parent, method;  ///< method: "root centroid", "sphere fit", "contact centroid", ...
    double gapMm = 0;        ///< surface gap to the parent bone (centre distance minus a voxel)
    double radiusMm = 0;     ///< fitted head radius (sphere fit only)
    double fitRmsMm = 0;     ///< sphere fit residual (sphere fit only)
  };
  std::string tableSource;  ///< the label table's source (a file, or the built-in names)
  std::vector<Bone> bones;
  std::vector<Fragment> fragments;  ///< largest first
  std::vector<JointInfo> joints;
  std::vector<std::string> missingBones;  ///< bone names of the table with no (or only fragment) voxels
  std::size_t fragmentsReassigned = 0, fragmentVoxelsReassigned = 0;
  std::size_t noiseComponents = 0, noiseVoxels = 0;  ///< fragments left as soft tissue
  double seconds = 0;
  /// Human-readable summary, one item per line (beyond the 30 largest fragments, the smaller ones
  /// are summed per label, destination and kind of reason).
  std::string text() const;
};

struct AutoRigResult {
  /// Joints parents-first; the root is "pelvis" when hip/sacrum/pelvis labels are present.
  Skeleton skeleton;
  /// The input volume with every bone voxel under its bone's value: a label holding several bones
  /// is split (its largest bone keeps the value, the others get new values above every value in
  /// use), fragments take the value of the bone they went to, and fragments far from every bone
  /// a new soft label (unassigned_bone_fragments). skeleton.json names bones by label, so write and
  /// use this volume with the skeleton (it equals the input when nothing moved).
  LabelVolume labels;
  /// The input table extended with the split bones' names (femur -> femur_left, femur_right).
  LabelTable table;
  AutoRigReport report;
};

/// Builds a skeleton from the bone labels of `labels` (kinds from `table`), in stages:
/// 1. bones: findBoneComponents and chooseBones (bone_components.h): which components are bones,
///    labels split by side;
/// 2. fragments: assignFragments (bone_fragments.h): every other component to a bone or, far from
///    all, to soft tissue;
/// 3. contacts within the adjacency gap (bone_contacts.h): surface gap = voxel-centre distance
///    minus one voxel, at most max(maxGapMm, maxGapVoxels x the largest spacing);
/// 4. tree and names: planSkeleton (rig_tree.h): fused groups, parents by anatomy, names from the
///    vocabulary of anatomy_names.h;
/// 5. centres: findJointCenters (joint_centers.h).
/// Bones cut by the field of view are kept (their other end still articulates) and reported.
/// Throws std::invalid_argument when the volume is empty or inconsistent, has no bone voxels, or
/// (options.checkTable) when the table's names contradict where its bones lie
/// (checkLabelTableFit, label_table_fit.h).
AutoRigResult autoRig(const LabelVolume& labels, const LabelTable& table, const AutoRigOptions& options = {});

}  // namespace repose
