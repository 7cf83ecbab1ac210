#pragma once
// Point location in a tet mesh: a uniform grid over the tets' bounding boxes answers "which tet
// contains p"; for a point outside the mesh, a bounding-volume hierarchy over the boundary faces finds
// the nearest point of the mesh (it lies on the boundary), so a point far outside the body costs a few
// dozen box tests rather than a scan of empty grid cells.
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "tet_mesh.h"

namespace repose {

/// Answers "which tet contains p" and "which tet is nearest to p". Holds references to nodes and
/// tets: both must outlive the locator and stay unchanged. Queries are const and thread-safe.
/// Construction is threaded (parallelFor) and deterministic.
class TetLocator {
 public:
  struct Hit {
    int tet = -1;                                       ///< -1 only for an empty mesh
    Eigen::Vector4d bary = Eigen::Vector4d::Zero();     ///< barycentric of p in `tet` (extrapolated outside)
    double distance = 0;                                ///< distance from p to the tet (0 inside)
  };

  /// nodes #V by 3, tets #T by 4 (node indices). Throws std::invalid_argument on bad indices.
  TetLocator(const Points& nodes, const Tets& tets);

  /// True and the containing tet if all barycentric coordinates of p are >= -eps in some tet
  /// (the lowest-numbered such tet of p's grid cell).
  bool findContaining(const Eigen::Vector3d& p, Hit& hit, double eps = 1e-10) const;
  /// The tet nearest to p (containing tets first), barycentric extrapolated. Outside the mesh, among
  /// the tets around the nearest boundary face (sharing one of its nodes) within 5 % of the minimal
  /// distance, the one with the smallest largest |barycentric| wins (stable extrapolation).
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
  void buildBoundary();
  int buildNode(int first, int count, std::vector<Eigen::Vector3f>& centroids);

  const Points& nodes_;
  const Tets& tets_;
  Eigen::Vector3d lo_ = Eigen::Vector3d::Zero();
  double h_ = 1;
  Eigen::Array3i dims_ = Eigen::Array3i::Ones();
  std::vector<std::size_t> cellStart_;  // CSR over cells
  std::vector<int> cellTets_;
  // Boundary faces (node triples) and, for their nodes, the incident tets (CSR by node).
  std::vector<std::array<int, 3>> faces_;
  std::vector<int> faceTet_;
  std::vector<std::size_t> nodeTetStart_;  // #V + 1 (empty ranges for interior nodes)
  std::vector<int> nodeTets_;
  // Hierarchy over the boundary faces: node n has a float box (lo xyz, hi xyz, rounded outward) and
  // either two children (left = n + 1, right = child_[n]) or a leaf range of faceOrder_.
  struct BvhNode {
    float box[6];
    int right;           // -1 for a leaf
    int first, count;    // leaf: faceOrder_[first, first + count)
  };
  std::vector<BvhNode> bvh_;
  std::vector<int> faceOrder_;
};

}  // namespace repose
