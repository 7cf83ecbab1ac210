#pragma once
// Nearest points on a triangle and a tetrahedron (Euclidean, any frame with equal units per axis).
#include <Eigen/Core>

namespace repose {

/// The point of triangle abc nearest to p (Ericson, Real-Time Collision Detection, 5.1.5).
Eigen::Vector3d closestPointOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                       const Eigen::Vector3d& c);

/// Distance from p to the solid tetrahedron abcd (0 inside or on it); any orientation.
double pointTetDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                        const Eigen::Vector3d& c, const Eigen::Vector3d& d);

}  // namespace repose
