#pragma once
// The skeleton's tree by anatomy: which bones move as one (fused groups), which joint hangs from
// which (parents anatomy allows, nearest first), and the joints' names (anatomy_names.h).
#include <string>
#include <vector>

#include "bone_contacts.h"
#include "rig_bones.h"

namespace repose {

/// One joint of the planned skeleton.
struct PlannedJoint {
  std::string name;
  int parent = -1;          ///< index into RigTree::joints (parents come first); -1 for the root
  std::vector<int> bones;   ///< its rigid group (indices into RigBones::bones)
  int childBone = -1;       ///< the bones whose articulation makes the joint (-1 for the root)
  int parentBone = -1;
  double gapMm = 0;         ///< closest voxel-centre distance between those two bones
  /// The parent lies beyond the adjacency gap (taken because anatomy expects it): the closest
  /// voxel centres of the two bones, as the contact patches are empty.
  bool beyondContact = false;
  Eigen::Vector3d closestOnChild = Eigen::Vector3d::Zero(), closestOnParent = Eigen::Vector3d::Zero();
};

struct RigTree {
  std::vector<PlannedJoint> joints;  ///< root first, parents before children
  std::vector<int> jointOfBone;      ///< per bone; -1 when left out
  std::vector<std::string> note;     ///< per bone: why it was left out, or whom it rides with
};

/// Plans the skeleton from the bones and their contacts (found within `contactMm`, voxel centres).
/// Groups (one joint each, never split):
/// - pelvis: hip bones, pelvis, sacrum, coccyx, S vertebrae that touch (or lie within
///   maxAnatomicGapMm of the largest of them);
/// - per side: radius + ulna (forearm), hand bones, tibia + fibula, foot bones, when they touch
///   or lie within maxAnatomicGapMm; a patella joins its femur (else its tibia);
/// - each rib, ribcage, sternum (and costal cartilage labelled bone) joins the vertebra or spine it
///   touches closest, else the nearest one (through ribs riding already); never a joint of its own.
/// Parents, by the bone types on both sides of a contact (the same on every body; a parent of the
/// other side is never taken; "trunk" = vertebrae, spine, ribs, sternum):
///   vertebra / spine region -> the pelvis or a vertebra below it;  skull -> a cervical vertebra
///   (else the spine);  mandible -> skull;  clavicle -> sternum (else the trunk);  scapula -> its
///   clavicle (else the trunk);  humerus -> its scapula (else the trunk);  radius, ulna -> humerus;
///   hand -> forearm;  femur -> pelvis;  tibia, fibula -> femur;  foot -> tibia or fibula;
///   unrecognised bones -> any bone; never the parent of a recognised one.
/// The preferred parent is taken when it exists at all, also beyond the contact gap up to
/// maxAnatomicGapMm; the fallback only when the preferred one is absent or out of reach. Among
/// allowed parents the smallest gap wins (Prim's algorithm from the root: the largest pelvis group,
/// else the largest spine group, else the largest group near the mid-sagittal plane).
RigTree planSkeleton(const ImageGrid& grid, const RigBones& bones, const std::vector<std::vector<BoneContact>>& contacts,
                     double contactMm, const AutoRigOptions& options);

}  // namespace repose
