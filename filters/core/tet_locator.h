#pragma once
// Point location in a tet mesh with a uniform grid over the tets' bounding boxes.
#include <Eigen/Core>
#include <vector>

#include "tet_mesh.h"

namespace repose {

/// Answers "which tet contains p" and "which tet is nearest to p". Holds references to nodes and
/// tets: both must outlive the locator and stay unchanged. Queries are const and thread-safe.
class TetLocator {
 public:
  struct Hit {
    int tet = -1;                                       ///< -1 only for an empty mesh
    Eigen::Vector4d bary = Eigen::Vector4d::Zero();     ///< barycentric of p in `tet` (extrapolated outside)
    double distance = 0;                                ///< distance from p to the tet (0 inside)
  };

  /// nodes #V by 3, tets #T by 4 (node indices). Throws std::invalid_argument on bad indices.
  TetLocator(const Points& nodes, const Tets& tets);

  /// True and the containing tet if all barycentric coordinates of p are >= -eps in some tet.
  bool findContaining(const Eigen::Vector3d& p, Hit& hit, double eps = 1e-10) const;
  /// The tet nearest to p (containing tets first), barycentric extrapolated. Among tets within 5 %
  /// of the minimal distance, the one with the smallest largest |barycentric| wins (stable extrapolation).
  Hit findNearest(const Eigen::Vector3d& p) const;

  /// Barycentric coordinates of p with respect to tet t (affine, sums to 1).
  Eigen::Vector4d barycentric(int t, const Eigen::Vector3d& p) const;
  /// Euclidean distance from p to tet t (0 inside).
  double distanceToTet(int t, const Eigen::Vector3d& p) const;

 private:
  Eigen::Array3i cellOf(const Eigen::Vector3d& p) const;  // clamped to the grid
  std::size_t cellIndex(const Eigen::Array3i& c) const {
    return (std::size_t(c.z()) * dims_.y() + c.y()) * dims_.x() + c.x();
  }

  const Points& nodes_;
  const Tets& tets_;
  Eigen::Vector3d lo_ = Eigen::Vector3d::Zero();
  double h_ = 1;
  Eigen::Array3i dims_ = Eigen::Array3i::Ones();
  std::vector<std::size_t> cellStart_;  // CSR over cells
  std::vector<int> cellTets_;
};

}  // namespace repose
