#pragma once
// BVH (Biovision hierarchy) motion capture: reader and forward kinematics.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

namespace repose {

enum class BvhChannel { Xposition, Yposition, Zposition, Xrotation, Yrotation, Zrotation };
/// "Xposition", ..., "Zrotation".
const char* bvhChannelName(BvhChannel channel);

struct BvhJoint {
  std::string name;
  int parent = -1;                                   ///< index into BvhMotion::joints, -1 for the root
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();  ///< from the parent joint, in the parent's frame (BVH units)
  std::vector<BvhChannel> channels;                  ///< in file order (0 to 6 channels)
  int firstChannel = 0;                              ///< column of channels[0] in BvhMotion::frames
  bool hasEndSite = false;
  Eigen::Vector3d endSite = Eigen::Vector3d::Zero();  ///< End Site offset when hasEndSite
};

using BvhFrames = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

struct BvhMotion {
  std::vector<BvhJoint> joints;  ///< file order: every parent before its children; joints[0] is the root
  int frameCount = 0;
  double frameTime = 0;          ///< seconds per frame
  BvhFrames frames;              ///< #frames by #channels, columns in file order (rotations in degrees)
  int channelCount() const { return int(frames.cols()); }
  int find(const std::string& name) const;  ///< joint index, -1 when absent
  double framesPerSecond() const { return frameTime > 0 ? 1.0 / frameTime : 0.0; }
};

/// Parses BVH text. Any channel order per joint, any joint count, End Sites, LF or CRLF lines.
/// Throws std::invalid_argument naming sourceName and the line number on: missing HIERARCHY/ROOT/
/// MOTION, unbalanced braces, an unknown or repeated channel name, a bad number, a frame row with
/// too few or too many values, or a frame count that does not match the rows.
BvhMotion parseBvh(const std::string& text, const std::string& sourceName = "BVH");
/// Reads and parses a file; errors name the file.
BvhMotion readBvhFile(const std::string& path);

/// Global transform of every joint for the given channel values (one frame row, #channels values):
/// G_j = G_parent · T(offset_j + position channels) · R_j, with R_j = R_ch1 · R_ch2 · R_ch3 the
/// rotation channels composed in file order (intrinsic Euler angles, the BVH convention).
/// translation() is the joint's position, linear() its global rotation (BVH frame, Y up).
std::vector<Eigen::Isometry3d> bvhGlobalPose(const BvhMotion& motion, const double* channelValues);
/// Same for frame `frame` (0 <= frame < frameCount); throws std::invalid_argument otherwise.
std::vector<Eigen::Isometry3d> bvhGlobalPose(const BvhMotion& motion, int frame);
/// All channels zero: the rest pose given by the offsets (a T-pose in most files).
std::vector<Eigen::Isometry3d> bvhRestPose(const BvhMotion& motion);

}  // namespace repose
