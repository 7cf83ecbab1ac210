#pragma once
// Which skeleton joint a BVH clip drives, and with which of the clip's joints: the built-in map of
// the CMU clips onto the standard joint names, joint map files, and the report of what is driven.
//
// The skeleton's joints by the standard names of anatomy_names.h (what the automatic rig and the
// phantom call them): pelvis, spine, chest, vertebra_<level>, neck (C7 or a cervical spine label; the
// skull's joint when no cervical bone is below it), head (the skull above a neck), jaw, and the
// girdles and limbs left_/right_ clavicle, scapula, shoulder, elbow, wrist, hip, knee, ankle.
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "bvh.h"
#include "skeleton.h"

namespace repose {

/// A share of a BVH joint's rotation relative to its BVH parent: the same axis, `fraction` of the
/// angle (1 = all of it).
struct BvhShare {
  std::string bvhJoint;
  double fraction = 1.0;
};

/// How a clip drives a skeleton.
struct BvhJointMap {
  /// BVH joint -> the skeleton joint that follows it. At most one BVH joint per skeleton joint.
  std::map<std::string, std::string> joints;
  /// Skeleton joint -> the shares of BVH joints' rotations it takes, composed in order up the
  /// chain: a spine of many vertebrae divides the clip's few spine joints among them. A skeleton
  /// joint is in `joints` or here, not in both.
  std::map<std::string, std::vector<BvhShare>> shares;
  bool empty() const { return joints.empty() && shares.empty(); }
};

/// The built-in map of the CMU clips, both conversions: "3dsMax" (LeftHip, LeftKnee, LeftAnkle,
/// LeftCollar, LeftShoulder = the upper arm, lowerback, Chest, Chest2, lowerneck, Neck, Head) and
/// "MotionBuilder" (LeftUpLeg, LeftLeg, LeftFoot, LeftShoulder = the collar, LeftArm, LowerBack,
/// Spine, Spine1, Neck, Neck1, Head), onto the standard names that the skeleton has:
///  - pelvis and every limb joint follow their CMU joint (the collar drives the clavicle, or the
///    scapula when there is no clavicle);
///  - the trunk (spine, chest, vertebra_*, neck, head) divides the six CMU trunk joints by spinal
///    level: lowerback over L5-L1, upper back T12-T7, thorax T6-T1, lower neck C7-C4, upper neck
///    C3-C1, head the skull. A skeleton trunk joint takes the part of each CMU joint's rotation that
///    falls between its level and the next trunk joint's (the lowest one also everything below it),
///    so a vertebra chain bends smoothly and a whole-spine bone takes the whole bend.
/// Throws std::invalid_argument when the clip has none of the CMU names or nothing maps.
BvhJointMap defaultCmuJointMap(const BvhMotion& motion, const Skeleton& skeleton);

/// Joint map JSON: {"BVH joint": "skeleton joint", ...}, optionally wrapped as {"map": {...}}.
BvhJointMap parseJointMapJson(const std::string& text);
BvhJointMap readJointMapFile(const std::string& path);

/// What a map drives, for the user.
struct JointMapCoverage {
  /// Skeleton joints the map drives (skeleton order) and their BVH sources ("LeftLeg",
  /// "lowerback 40% + Chest").
  std::vector<std::pair<std::string, std::string>> driven;
  /// Standard limb and girdle joints the map does not drive (they only follow their parents). A
  /// clavicle or scapula next to a driven one of the same side is not listed: clips have one shoulder
  /// girdle joint.
  std::vector<std::string> undrivenLimbs;
  /// Other standard joints the map does not drive: they follow their parents (jaw, a scapula beside a
  /// driven clavicle, ...).
  std::vector<std::string> following;
  /// Joints whose names are not standard: no built-in map can drive them (they follow their parents).
  std::vector<std::string> unknownNames;
};
/// Throws std::invalid_argument if the map names a skeleton joint the skeleton lacks.
JointMapCoverage jointMapCoverage(const Skeleton& skeleton, const BvhJointMap& map);

}  // namespace repose
