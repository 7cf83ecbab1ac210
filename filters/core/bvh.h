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

/// Multiplies every length by `factor` (offsets, End Sites, position channels): the same clip in
/// another unit, e.g. 5.644 turns CMU units into centimetres. Throws unless factor is positive.
void scaleBvhLengths(BvhMotion& motion, double factor);

/// Length unit of a clip. BVH files do not say theirs: CMU conversions use 1/0.45 inch (56.44 mm),
/// others centimetres, metres, inches or millimetres.
struct BvhUnits {
  double mmPerUnit = 0;      ///< millimetres per BVH unit
  std::string name;          ///< "centimetres", "CMU units of 1/0.45 inch", ...
  std::string measure;       ///< what was compared with a human's: "leg length" or "rest pose height"
  double measuredUnits = 0;  ///< that length in BVH units
};
/// Infers the unit from the skeleton's proportions: the leg length (thigh + shank: the offset of each
/// knee joint, found by name (knee, shin, calf, tibia, lower leg, or ...Leg but not ...UpLeg), plus
/// its child's, averaged over the knees) against an adult's 800 mm hip to ankle; without a knee, the
/// rest pose's largest extent (joints and End Sites) against 1500 mm. Of millimetres, centimetres,
/// inches, CMU units, feet and metres, the unit whose length comes closest (by ratio) wins: units are
/// at least 2.2 times apart, so a body from 0.55 to 1.2 times an adult's reads right. Throws
/// std::invalid_argument when the skeleton has no length (every offset zero).
BvhUnits inferBvhUnits(const BvhMotion& motion);

}  // namespace repose
