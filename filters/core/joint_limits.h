#pragma once
// Ranges of motion of the anatomical angles (anatomical_angles.h), in degrees from the scan's rest
// pose, keyed by the standard joint names. They bound what an interactive edit may set (a slider,
// a drag); poses read from files or motion capture are not clamped. Generous on purpose: a scan's
// rest pose is rarely the anatomical position, and a virtual patient may be placed at the edge of
// its range.
#include <string>

#include <Eigen/Core>

#include "anatomical_angles.h"

namespace repose {

struct JointLimits {
  Eigen::Vector3d lower, upper;  ///< anatomical degrees: flexion, abduction, rotation
  /// `degrees` clamped into the range, per angle.
  Eigen::Vector3d clamp(const Eigen::Vector3d& degrees) const { return degrees.cwiseMax(lower).cwiseMin(upper); }
};

/// The range of a joint class. The middle angle stays within [-90, 90] (the decomposition's range).
JointLimits jointLimits(const JointClass& joint);
/// Shorthand: jointLimits(classifyJoint(name, isRoot)).
JointLimits jointLimits(const std::string& jointName, bool isRoot = false);

}  // namespace repose
