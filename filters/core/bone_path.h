#pragma once
// Rigid paths of the bone (Dirichlet) nodes from the rest shape to a pose: the load path of the
// fold-free continuation (fold_free_continuation.h).
#include <Eigen/Geometry>
#include <vector>

#include "dual_quaternion.h"
#include "tet_mesh.h"

namespace repose {

/// Fits, per bone, the rigid motion that carries its nodes from rest to posed (least squares,
/// Umeyama) and moves them along a rigid path from the rest shape (s = 0) to posed (s = 1).
/// - The rigid motion of the whole skeleton is factored out and applied in full at s = 0: moving
///   the rest shape rigidly strains nothing.
/// - With the skeleton's hierarchy, each bone follows its parent and turns relative to it by the
///   dual-quaternion blend of the identity and its motion relative to the parent. That blend is
///   rigid at every s and keeps the screw axis, so a bone turning about its joint keeps the joint
///   in place all along, and neighbouring bones neither part nor press into each other on the way.
///   (Without the hierarchy each bone blends on its own, and joints may drift mid-path.)
/// - Whatever of a node's motion is not rigid (nothing, for skinned bone nodes) is phased in
///   linearly, so s = 1 gives posed exactly.
class BonePath {
 public:
  /// rest, posed  #V by 3;  fixedBone  #V, >= 0: the node's bone, -1: not on the path;
  /// boneParents  per bone, its parent bone or -1 (a root); empty: no hierarchy
  /// Throws std::invalid_argument if boneParents does not cover every bone or has a cycle.
  BonePath(const Points& rest, const Points& posed, const std::vector<int>& fixedBone,
           const std::vector<int>& boneParents = {});

  /// The global rigid motion applied to a rest point: where the path starts.
  Eigen::Vector3d start(const Eigen::Vector3d& restPoint) const { return global_ * restPoint; }
  /// Writes the positions at s in [0, 1] of the given nodes (all with fixedBone >= 0) into x;
  /// at s = 1 exactly their posed positions.
  void place(double s, const std::vector<int>& nodes, Points& x) const;

 private:
  std::vector<Eigen::Isometry3d> bonesAt(double s) const;

  const Points& rest_;
  const Points& posed_;
  const std::vector<int>& fixedBone_;
  Eigen::Isometry3d global_ = Eigen::Isometry3d::Identity();
  std::vector<int> parent_;               ///< per bone: the parent the path follows, or -1
  std::vector<int> order_;                ///< bones, parents first
  std::vector<DualQuaternion> relative_;  ///< per bone: its motion relative to the parent (or to global_)
  Points remainder_;                      ///< per node: the non-rigid rest of its motion
};

}  // namespace repose
