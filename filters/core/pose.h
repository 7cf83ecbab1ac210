#pragma once
// pose.json and forward kinematics.
#include <Eigen/Geometry>
#include <map>
#include <string>
#include <vector>

#include "skeleton.h"

namespace repose {

/// Local joint rotations (about each joint's rest centre, axes in the rest physical frame)
/// plus a root translation.
struct Pose {
  std::map<std::string, Eigen::Quaterniond> rotations;
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
};

/// Parses pose.json: {"rotations": {JOINT: {"axis":[x,y,z],"degrees":a} | {"quaternion":[w,x,y,z]}},
/// "translation":[x,y,z]}. Throws std::invalid_argument on NaN/inf, a zero axis, a zero quaternion
/// or malformed JSON. Joint names are checked against a skeleton by validatePose.
Pose parsePoseJson(const std::string& text);
/// Exact (quaternions, 17 digits): for passing a pose between programs.
std::string poseToJson(const Pose& pose);
/// The pose as parsePoseJson(poseToJson(pose)) reads it back, without the text: each quaternion made
/// unit the way the parser does it, so a typed pose and its JSON pose the mesh to the same bits.
/// Throws std::invalid_argument on a zero or non-finite rotation or translation, like the parser.
Pose canonicalPose(const Pose& pose);
/// For a person to read and edit: every rotation as {"axis": [x,y,z] (unit), "degrees": a} with a in
/// [0, 180], 12 significant digits (parsePoseJson reads it back to 1e-10 degrees).
std::string poseToAxisAngleJson(const Pose& pose);
Pose readPoseFile(const std::string& path);
/// Throws std::invalid_argument if the pose names a joint the skeleton does not have.
void validatePose(const Pose& pose, const Skeleton& skeleton);
/// Largest |translation| component validatePose accepts (1 km).
constexpr double kMaxTranslationMm = 1e6;

/// Global rigid transform of every joint's bone (rest -> posed):
/// G_j = G_parent · T(c_j) · R_j · T(-c_j), the root's preceded by T(translation).
std::vector<Eigen::Isometry3d> forwardKinematics(const Skeleton& skeleton, const Pose& pose);

}  // namespace repose
