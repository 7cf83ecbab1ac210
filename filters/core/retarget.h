#pragma once
// Retargeting BVH motion onto a scan's skeleton: one repose::Pose per BVH frame.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "bvh.h"
#include "bvh_joint_map.h"
#include "pose.h"
#include "skeleton.h"

namespace repose {

enum class RetargetMode {
  /// Limb bones (joint centre -> centre of its main mapped child) point where the corresponding
  /// BVH bones point in the frame, with the BVH joint's twist about the bone; the trunk bends as the
  /// clip's trunk bends from its rest pose. Works whatever the two rest poses are (scan lying with
  /// arms down, BVH in a T-pose).
  Direction,
  /// Each mapped joint gets the BVH joint's global rotation relative to a reference frame of the
  /// clip (G_bvh(frame) · G_bvh(ref)^-1, mapped to LPS): the scan's rest pose is taken to be the
  /// clip's pose at the reference frame.
  Relative,
};
/// "direction" | "relative"; throws std::invalid_argument otherwise.
RetargetMode parseRetargetMode(const std::string& name);

struct RetargetOptions {
  RetargetMode mode = RetargetMode::Direction;
  int referenceFrame = 0;     ///< Relative mode's reference; in both modes the root translation is zero there
  bool translateRoot = true;  ///< move the root by the BVH root's displacement from the reference frame
  /// Millimetres per BVH unit; 0 = inferred from the clip's proportions (inferBvhUnits).
  double unitScaleMm = 0;
};

/// BVH axes (right-handed, X = character's left, Y up, Z forward) -> LPS (x left, y posterior,
/// z superior): (X, Y, Z) -> (X, -Z, Y). A proper rotation.
Eigen::Matrix3d bvhToLps();

/// Precomputes the mapping once, then produces a Pose per frame (microseconds each).
/// Joints the map does not drive follow their parents (identity local rotation). Pose rotations are
/// local, about rest centres, in the rest frame (pose.json): R_j = G_parent^-1 · G_j.
///
/// Every driven joint's posed orientation is the clip's orientation of its BVH joint applied to a
/// rest alignment A (scan rest -> clip rest, zero channels) that does not change over the clip:
///  - body: the skeleton root (when it has mapped children left and right of it, such as the hips)
///    aligns its rest pose on the left-right axis between those children and on the vertical;
///  - trunk: a joint with shares (the built-in map's spine, vertebrae, neck, head), or mapped to a
///    BVH joint on the clip's axial chain (root to the top of the head), takes the clip's rotation
///    between its BVH joint and the one below it in the body's alignment: the scan keeps its own
///    spinal curvature and head carriage and bends as the clip bends from its rest pose;
///  - limb bone: the scan bone's rest direction is aligned with the BVH bone's (minimal rotation),
///    and the frame's bone direction is matched exactly (unmapped BVH joints in between count);
///  - limb end (a mapped joint without mapped descendants: ankle, wrist): its parent bone's
///    alignment, so a foot or hand keeps its angle to the shank or forearm as the clip's does.
/// The main child of a limb joint with several mapped children is the one that best continues the
/// bone coming into the joint.
class BvhRetargeter {
 public:
  /// Throws std::invalid_argument if the map names a joint that the clip or the skeleton lacks, maps
  /// two BVH joints onto one skeleton joint, drives no joint but the root, the reference frame is
  /// out of range, or the unit scale is negative.
  BvhRetargeter(const BvhMotion& motion, const Skeleton& skeleton, const BvhJointMap& map,
                const RetargetOptions& options = {});

  /// Pose of frame `frame` (0 <= frame < frameCount()).
  Pose pose(int frame) const;
  int frameCount() const { return motion_.frameCount; }
  /// The clip's unit: given (name "given", no measure) or inferred.
  const BvhUnits& units() const { return units_; }
  /// Skeleton joint -> the BVH joint it follows (-1 for shares-driven and undriven joints).
  const std::vector<int>& bvhJointOfSkeletonJoint() const { return bvhOf_; }
  /// Skeleton joint -> the mapped descendant whose bone direction drives it (-1: none).
  const std::vector<int>& mainChild() const { return mainChild_; }

 private:
  enum class Drive { None, Body, Trunk, Limb, LimbEnd };
  struct Factor {  // (T_from^T · T_to)^weight; from = -1: identity
    int from, to;
    double weight;
  };
  void buildTrunkFactors(const BvhJointMap& map);
  void buildAlignments();
  std::vector<Eigen::Matrix3d> clipRotations(const std::vector<Eigen::Isometry3d>& bvh) const;

  BvhMotion motion_;
  Skeleton skeleton_;
  RetargetOptions options_;
  BvhUnits units_;
  std::vector<Drive> drive_;      // per skeleton joint
  std::vector<int> bvhOf_;        // per skeleton joint
  std::vector<std::vector<Factor>> factors_;  // per skeleton joint: Trunk
  std::vector<int> mainChild_;    // per skeleton joint
  std::vector<int> lateralLeft_, lateralRight_;  // Body: skeleton joints spanning the left-right axis
  std::vector<Eigen::Vector3d> restDirBvh_;     // BVH rest bone (or lateral) direction, LPS
  std::vector<Eigen::Matrix3d> restAlign_;      // A: scan rest -> BVH rest orientation of the bone
  Eigen::Matrix3d bodyAlign_ = Eigen::Matrix3d::Identity();  // the root's A (trunk joints use it)
  std::vector<Eigen::Matrix3d> refRotation_;    // Relative mode: G_bvh(ref) in LPS per BVH joint
  Eigen::Vector3d refRootPosition_ = Eigen::Vector3d::Zero();  // BVH units, BVH axes
  int translationJoint_ = 0;    // BVH joint whose displacement moves the root
};

/// Convenience: one frame.
Pose retargetBvhFrame(const BvhMotion& motion, const Skeleton& skeleton, const BvhJointMap& map, int frame,
                      const RetargetOptions& options = {});

}  // namespace repose
