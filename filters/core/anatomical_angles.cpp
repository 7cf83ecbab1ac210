#include "anatomical_angles.h"

#include <algorithm>
#include <cctype>
#include <cmath>

namespace repose {
namespace {

constexpr double kDeg = M_PI / 180.0;

bool has(const std::string& lower, const char* word) { return lower.find(word) != std::string::npos; }

}  // namespace

JointClass classifyJoint(const std::string& name, bool isRoot) {
  std::string n = name;
  std::transform(n.begin(), n.end(), n.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  JointClass j;
  // "left"/"right" as a word part: left_hip, hip_left, LeftHip (not "upright").
  if (n.rfind("left", 0) == 0 || has(n, "_left")) j.side = BodySide::Left;
  else if (n.rfind("right", 0) == 0 || has(n, "_right")) j.side = BodySide::Right;
  if (isRoot || n == "pelvis" || n == "root") j.kind = JointKind::Root;
  else if (has(n, "neck") || has(n, "head") || has(n, "skull") || has(n, "cervical")) j.kind = JointKind::Neck;
  else if (has(n, "spine") || has(n, "vertebra") || has(n, "lumbar") || has(n, "thora") || has(n, "chest"))
    j.kind = JointKind::Spine;
  else if (has(n, "hip") || has(n, "upleg") || has(n, "thigh")) j.kind = JointKind::Hip;
  else if (has(n, "knee") || has(n, "tibia") || has(n, "shin")) j.kind = JointKind::Knee;
  else if (has(n, "ankle") || has(n, "foot")) j.kind = JointKind::Ankle;
  else if (has(n, "shoulder") || has(n, "humerus")) j.kind = JointKind::Shoulder;
  else if (has(n, "elbow") || has(n, "forearm")) j.kind = JointKind::Elbow;
  else if (has(n, "wrist") || has(n, "hand")) j.kind = JointKind::Wrist;
  // A limb joint needs a side for its signs; without one it keeps the plain angles.
  const bool limb = j.kind == JointKind::Hip || j.kind == JointKind::Knee || j.kind == JointKind::Ankle ||
                    j.kind == JointKind::Shoulder || j.kind == JointKind::Elbow || j.kind == JointKind::Wrist;
  if (limb && j.side == BodySide::Midline) j.kind = JointKind::Other;
  return j;
}

Eigen::Vector3d anatomicalSigns(const JointClass& joint) {
  // Rx(a) with a > 0 swings a bone that points down (a limb at rest) backwards and one that points
  // up (the trunk above a spinal joint) forwards. Ry(b) with b > 0 swings a downward bone towards
  // the patient's right (-x). Rz(c) with c > 0 turns the front (-y) towards the patient's left (+x).
  const double lateral = joint.side == BodySide::Left ? -1.0 : 1.0;  // abduction and internal rotation
  switch (joint.kind) {
    case JointKind::Root:
    case JointKind::Spine:
    case JointKind::Neck:
      return {1.0, -1.0, 1.0};
    case JointKind::Knee:  // the shin flexes backwards
      return {1.0, lateral, lateral};
    case JointKind::Hip:
    case JointKind::Shoulder:
    case JointKind::Elbow:  // the forearm flexes forwards
    case JointKind::Wrist:
    case JointKind::Ankle:  // dorsiflexion: the toes (in front) rise
      return {-1.0, lateral, lateral};
    case JointKind::Other:
      break;
  }
  return {1.0, 1.0, 1.0};
}

std::array<std::string, 3> anatomicalAngleNames(const JointClass& joint) {
  switch (joint.kind) {
    case JointKind::Root:
      return {"Tilt forward (+) / backward (−)", "Tilt to the patient's right (+) / left (−)",
              "Turn to the patient's left (+) / right (−)"};
    case JointKind::Spine:
    case JointKind::Neck:
      return {"Flexion (+) / extension (−)", "Lateral bending right (+) / left (−)",
              "Axial rotation left (+) / right (−)"};
    case JointKind::Ankle:
      return {"Dorsiflexion (+) / plantarflexion (−)", "Eversion (+) / inversion (−)",
              "Internal (+) / external rotation (−)"};
    case JointKind::Elbow:
      return {"Flexion (+) / extension (−)", "Valgus (+) / varus (−)", "Pronation (+) / supination (−)"};
    case JointKind::Knee:
      return {"Flexion (+) / extension (−)", "Valgus (+) / varus (−)", "Internal (+) / external rotation (−)"};
    case JointKind::Wrist:
      return {"Flexion (+) / extension (−)", "Radial (+) / ulnar deviation (−)",
              "Internal (+) / external rotation (−)"};
    case JointKind::Hip:
    case JointKind::Shoulder:
      return {"Flexion (+) / extension (−)", "Abduction (+) / adduction (−)", "Internal (+) / external rotation (−)"};
    case JointKind::Other:
      break;
  }
  return {"About the left-right axis", "About the front-back axis", "About the head-foot axis"};
}

Eigen::Quaterniond rotationFromEulerAngles(const Eigen::Vector3d& d) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(d.x() * kDeg, Eigen::Vector3d::UnitX()) *
                            Eigen::AngleAxisd(d.y() * kDeg, Eigen::Vector3d::UnitY()) *
                            Eigen::AngleAxisd(d.z() * kDeg, Eigen::Vector3d::UnitZ()));
}

Eigen::Vector3d eulerAnglesFromRotation(const Eigen::Quaterniond& q) {
  // Rx(a) Ry(b) Rz(c) = [[cb cc, -cb sc, sb], [., ., -sa cb], [., ., ca cb]].
  const Eigen::Matrix3d R = q.normalized().toRotationMatrix();
  const double b = std::asin(std::clamp(R(0, 2), -1.0, 1.0));
  double a, c;
  if (std::fabs(R(0, 2)) < 1 - 1e-12) {
    a = std::atan2(-R(1, 2), R(2, 2));
    c = std::atan2(-R(0, 1), R(0, 0));
  } else {  // gimbal lock: a and c turn about the same axis; put it all in a
    a = std::atan2(R(2, 1), R(1, 1));
    c = 0;
  }
  return Eigen::Vector3d(a, b, c) / kDeg;
}

Eigen::Vector3d anatomicalAngles(const Eigen::Quaterniond& q, const JointClass& joint) {
  return eulerAnglesFromRotation(q).cwiseProduct(anatomicalSigns(joint));
}

Eigen::Quaterniond rotationFromAnatomicalAngles(const Eigen::Vector3d& degrees, const JointClass& joint) {
  return rotationFromEulerAngles(degrees.cwiseProduct(anatomicalSigns(joint)));
}

}  // namespace repose
