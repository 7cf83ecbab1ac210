#pragma once
// Where each planned joint rotates: the centre of a sphere fitted to a ball joint's head (femoral,
// humeral), else the middle of the two bones' closest surface patches; the root at its centroid.
#include <string>
#include <vector>

#include "bone_contacts.h"
#include "rig_bones.h"
#include "rig_tree.h"

namespace repose {

struct JointCenter {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  std::string method;     ///< "root centroid", "sphere fit", "inscribed ball", "contact centroid", "closest points"
  double radiusMm = 0;    ///< fitted head radius (sphere fit, inscribed ball)
  double fitRmsMm = 0;    ///< sphere fit residual
};

/// One centre per planned joint (same order). Femur and humerus (and unrecognised bones whose
/// contact is a ball in a socket) get a sphere fitted to the child's articular surface near the
/// contact, kept when its radius lies within [minBallRadiusMm, maxBallRadiusMm].
std::vector<JointCenter> findJointCenters(const ImageGrid& grid, const RigBones& bones,
                                          const std::vector<std::vector<BoneContact>>& contacts, const RigTree& tree,
                                          const AutoRigOptions& options);

}  // namespace repose
