#include "joint_limits.h"

namespace repose {

JointLimits jointLimits(const JointClass& joint) {
  using V = Eigen::Vector3d;
  switch (joint.kind) {
    case JointKind::Root:  // the whole body: any orientation
      return {V(-180, -90, -180), V(180, 90, 180)};
    case JointKind::Spine:
      return {V(-45, -45, -60), V(90, 45, 60)};
    case JointKind::Neck:
      return {V(-70, -50, -80), V(80, 50, 80)};
    case JointKind::Hip:
      return {V(-30, -40, -60), V(140, 60, 60)};
    case JointKind::Knee:  // a hinge: little hyperextension, varus/valgus or rotation
      return {V(-10, -15, -45), V(150, 15, 45)};
    case JointKind::Ankle:
      return {V(-60, -45, -45), V(45, 45, 45)};
    case JointKind::Shoulder:
      return {V(-70, -45, -90), V(180, 90, 90)};
    case JointKind::Elbow:
      return {V(-10, -15, -90), V(150, 15, 90)};
    case JointKind::Wrist:
      return {V(-80, -45, -45), V(80, 45, 45)};
    case JointKind::Other:
      break;
  }
  return {V(-150, -90, -90), V(150, 90, 90)};
}

JointLimits jointLimits(const std::string& jointName, bool isRoot) { return jointLimits(classifyJoint(jointName, isRoot)); }

}  // namespace repose
