#include "dual_quaternion.h"

#include <stdexcept>

namespace repose {

DualQuaternion DualQuaternion::fromIsometry(const Eigen::Isometry3d& T) {
  DualQuaternion dq;
  dq.real = Eigen::Quaterniond(T.rotation()).normalized();
  const Eigen::Vector3d t = T.translation();
  // dual = 0.5 * (0, t) * real
  const Eigen::Quaterniond tq(0, t.x(), t.y(), t.z());
  dq.dual.coeffs() = 0.5 * (tq * dq.real).coeffs();
  return dq;
}

Eigen::Isometry3d DualQuaternion::toIsometry() const {
  const double n = real.norm();
  if (!(n > 0)) throw std::invalid_argument("DualQuaternion: zero real part");
  const Eigen::Quaterniond r(real.coeffs() / n);
  const Eigen::Quaterniond d(dual.coeffs() / n);
  // t = 2 vec(d * conj(r)); the scalar part of that product is ignored (projection onto unit DQs).
  const Eigen::Vector3d t = 2.0 * (r.w() * d.vec() - d.w() * r.vec() + r.vec().cross(d.vec()));
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = r.toRotationMatrix();
  T.translation() = t;
  return T;
}

Eigen::Vector3d DualQuaternion::transformPoint(const Eigen::Vector3d& p) const {
  const double n = real.norm();
  if (!(n > 0)) throw std::invalid_argument("DualQuaternion: zero real part");
  const double inv = 1.0 / n;
  const Eigen::Vector3d v = real.vec() * inv, ve = dual.vec() * inv;
  const double w = real.w() * inv, we = dual.w() * inv;
  const Eigen::Vector3d t = 2.0 * (w * ve - we * v + v.cross(ve));
  return p + 2.0 * v.cross(v.cross(p) + w * p) + t;
}

}  // namespace repose
