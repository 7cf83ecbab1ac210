#pragma once
// A joint rotation read as three anatomical angles with clinical signs: flexion, abduction (or
// lateral bending) and internal (or axial) rotation, keyed by the standard joint names
// (standardJointName: pelvis, spine, neck, vertebra_L5, left_hip, right_knee, left_shoulder, ...).
//
// A joint's rotation R (about its rest centre, axes of the rest physical frame, LPS: x towards the
// patient's left, y posterior, z superior) is decomposed as R = Rx(a) · Ry(b) · Rz(c): a about the
// left-right axis first (flexion/extension), then b about the front-back axis (abduction/adduction,
// lateral bending), then c about the bone's own long axis, head-foot at rest (rotation) - the order of
// a joint coordinate system, so a flexed knee's rotation turns the shin about itself. b is in
// [-90, 90]. The anatomical angles are (a, b, c) times the joint's signs, chosen so that:
//   hip, shoulder, elbow, wrist, knee: flexion positive (ankle: dorsiflexion positive);
//   limbs: abduction (the distal bone moving away from the midline) positive, internal rotation
//          (elbow: pronation) positive, on either side;
//   pelvis (root), spine, vertebrae, neck: flexion (bending forward) positive, lateral bending to the
//          patient's right positive, axial rotation to the patient's left positive;
//   other joints (clavicle, scapula, unknown names): the plain angles about x, y, z.
#include <array>
#include <string>

#include <Eigen/Geometry>

namespace repose {

enum class JointKind { Root, Spine, Neck, Hip, Knee, Ankle, Shoulder, Elbow, Wrist, Other };
enum class BodySide { Left, Right, Midline };

struct JointClass {
  JointKind kind = JointKind::Other;
  BodySide side = BodySide::Midline;
};

/// Kind and side from a joint's name ("left_hip", "vertebra_L5", "neck", ...; case-insensitive).
/// `isRoot` makes any name the root (the whole body's rotation).
JointClass classifyJoint(const std::string& name, bool isRoot = false);

/// Signs (+1/-1) turning the Euler angles (a, b, c) into the anatomical angles.
Eigen::Vector3d anatomicalSigns(const JointClass& joint);

/// The three angles' names with their signs, for a user interface, e.g.
/// {"Flexion (+) / extension (−)", "Abduction (+) / adduction (−)", "Internal (+) / external rotation (−)"}.
std::array<std::string, 3> anatomicalAngleNames(const JointClass& joint);

/// R = Rx(a) · Ry(b) · Rz(c), degrees.
Eigen::Quaterniond rotationFromEulerAngles(const Eigen::Vector3d& degrees);
/// Inverse of rotationFromEulerAngles with b in [-90, 90] (at b = ±90, c = 0).
Eigen::Vector3d eulerAnglesFromRotation(const Eigen::Quaterniond& q);

/// Anatomical angles (degrees) of a joint rotation, and back.
Eigen::Vector3d anatomicalAngles(const Eigen::Quaterniond& q, const JointClass& joint);
Eigen::Quaterniond rotationFromAnatomicalAngles(const Eigen::Vector3d& degrees, const JointClass& joint);

}  // namespace repose
