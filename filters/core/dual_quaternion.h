#pragma once
// Unit dual quaternions for rigid transforms (Kavan et al. 2008).
#include <Eigen/Geometry>

namespace repose {

struct DualQuaternion {
  Eigen::Quaterniond real{1, 0, 0, 0};   ///< rotation
  Eigen::Quaterniond dual{0, 0, 0, 0};   ///< 0.5 * t * real

  static DualQuaternion fromIsometry(const Eigen::Isometry3d& T);
  Eigen::Isometry3d toIsometry() const;   ///< of the normalised dual quaternion
  /// Transforms a point by the normalised dual quaternion.
  Eigen::Vector3d transformPoint(const Eigen::Vector3d& p) const;
};

}  // namespace repose
