#pragma once
// Retargeting BVH motion onto a scan's skeleton: one repose::Pose per BVH frame.
#include <Eigen/Core>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "bvh.h"
#include "pose.h"
#include "skeleton.h"

namespace repose {

/// BVH joint name -> skeleton joint name. A skeleton joint takes at most one BVH joint.
using BvhJointMap = std::map<std::string, std::string>;

enum class RetargetMode {
  /// Each mapped scan bone (joint centre -> centre of its main mapped child) points where the
  /// corresponding BVH bone points in the frame, with the BVH joint's twist about the bone.
  /// Works whatever the two rest poses are (scan lying with arms down, BVH in a T-pose).
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
  double unitScaleMm = 56.44; ///< millimetres per BVH unit (CMU: about 5.6 cm)
};

/// BVH axes (right-handed, X = character's left, Y up, Z forward) -> LPS (x left, y posterior,
/// z superior): (X, Y, Z) -> (X, -Z, Y). A proper rotation.
Eigen::Matrix3d bvhToLps();

/// Built-in defaults for the CMU clips (both the "3dsMax" and the "MotionBuilder" conversions):
/// skeleton joint name -> candidate BVH joint names, best first. The upper-arm joint is LeftArm in
/// MotionBuilder files (whose LeftShoulder is the collar) and LeftShoulder in 3dsMax files.
const std::vector<std::pair<std::string, std::vector<std::string>>>& cmuJointCandidates();
/// Resolves cmuJointCandidates() for a clip and a skeleton: for every skeleton joint that has
/// candidates, the first candidate the clip contains. Throws std::invalid_argument if nothing maps.
BvhJointMap defaultCmuJointMap(const BvhMotion& motion, const Skeleton& skeleton);
/// Joint map JSON: {"BVH joint": "skeleton joint", ...}, optionally wrapped as {"map": {...}}.
BvhJointMap parseJointMapJson(const std::string& text);
BvhJointMap readJointMapFile(const std::string& path);

/// Precomputes the mapping once, then produces a Pose per frame (microseconds each).
/// Joints not in the map follow their parents (identity local rotation). Pose rotations are local,
/// about rest centres, in the rest frame (pose.json): R_j = G_parent^-1 · G_j.
/// Direction mode details: the root (when it has mapped children left and right of it, such as
/// the hips) takes the BVH root's rotation with its rest pose aligned on the left-right axis
/// between those children and on the vertical; a mapped joint without mapped descendants (a leaf,
/// e.g. the ankle) keeps its mapped parent's rotation composed with the BVH rotation between the two
/// BVH joints. The main child of a joint with several mapped children is the one that best
/// continues the bone coming into the joint (the neck for the spine).
class BvhRetargeter {
 public:
  /// Throws std::invalid_argument if the map names a joint that the clip or the skeleton lacks, maps
  /// two BVH joints onto one skeleton joint, the reference frame is out of range, or the unit scale
  /// is not positive.
  BvhRetargeter(const BvhMotion& motion, const Skeleton& skeleton, const BvhJointMap& map,
                const RetargetOptions& options = {});

  /// Pose of frame `frame` (0 <= frame < frameCount()).
  Pose pose(int frame) const;
  int frameCount() const { return motion_.frameCount; }
  /// Skeleton joint -> BVH joint index (-1 when unmapped), in skeleton order.
  const std::vector<int>& bvhJointOfSkeletonJoint() const { return bvhOf_; }
  /// Skeleton joint -> the mapped descendant whose bone direction drives it (-1: leaf or unmapped).
  const std::vector<int>& mainChild() const { return mainChild_; }

 private:
  Pose poseFromGlobal(const std::vector<Eigen::Matrix3d>& global, const std::vector<Eigen::Isometry3d>& bvh) const;

  BvhMotion motion_;
  Skeleton skeleton_;
  RetargetOptions options_;
  std::vector<int> bvhOf_;       // per skeleton joint
  std::vector<int> mainChild_;   // per skeleton joint
  std::vector<int> mappedAncestor_;  // nearest mapped proper ancestor, -1 if none
  std::vector<int> lateralLeft_, lateralRight_;  // root only: skeleton joints spanning the left-right axis
  std::vector<Eigen::Vector3d> restDirBvh_;     // a0: BVH rest bone (or lateral) direction, LPS
  std::vector<Eigen::Matrix3d> restAlign_;      // C^-1: scan rest -> BVH rest orientation of the bone
  std::vector<Eigen::Matrix3d> refRotation_;    // Relative mode: G_bvh(ref) in LPS per skeleton joint
  Eigen::Vector3d refRootPosition_ = Eigen::Vector3d::Zero();  // BVH units, BVH axes
  int translationJoint_ = 0;    // BVH joint whose displacement moves the root
};

/// Convenience: one frame.
Pose retargetBvhFrame(const BvhMotion& motion, const Skeleton& skeleton, const BvhJointMap& map, int frame,
                      const RetargetOptions& options = {});

}  // namespace repose
