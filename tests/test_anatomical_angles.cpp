// Anatomical angles and joint ranges: every sign checked on where the bone goes, not on formulas.
#include <gtest/gtest.h>

#include "anatomical_angles.h"
#include "joint_limits.h"
#include "pose.h"

using repose::classifyJoint;
using repose::JointKind;
using Eigen::Vector3d;

namespace {
// LPS: x patient left, y posterior, z superior.
const Vector3d kDown(0, 0, -1), kUp(0, 0, 1), kFront(0, -1, 0), kLeft(1, 0, 0);

Vector3d moved(const std::string& joint, const Vector3d& anatomical, const Vector3d& v) {
  return repose::rotationFromAnatomicalAngles(anatomical, classifyJoint(joint)) * v;
}
}  // namespace

TEST(AnatomicalAngles, ClassifiesStandardNames) {
  EXPECT_EQ(classifyJoint("left_hip").kind, JointKind::Hip);
  EXPECT_EQ(classifyJoint("left_hip").side, repose::BodySide::Left);
  EXPECT_EQ(classifyJoint("right_knee").side, repose::BodySide::Right);
  EXPECT_EQ(classifyJoint("vertebra_L5").kind, JointKind::Spine);
  EXPECT_EQ(classifyJoint("spine").kind, JointKind::Spine);
  EXPECT_EQ(classifyJoint("neck").kind, JointKind::Neck);
  EXPECT_EQ(classifyJoint("pelvis").kind, JointKind::Root);
  EXPECT_EQ(classifyJoint("sacrum", true).kind, JointKind::Root);
  EXPECT_EQ(classifyJoint("right_elbow").kind, JointKind::Elbow);
  EXPECT_EQ(classifyJoint("left_clavicle").kind, JointKind::Other);
  EXPECT_EQ(classifyJoint("hip").kind, JointKind::Other);  // a limb without a side keeps plain angles
}

TEST(AnatomicalAngles, EulerRoundTripAndOrder) {
  for (const Vector3d& a : {Vector3d(30, -20, 45), Vector3d(-120, 80, -170), Vector3d(0, 0, 0), Vector3d(10, -89, 5)}) {
    const Vector3d back = repose::eulerAnglesFromRotation(repose::rotationFromEulerAngles(a));
    EXPECT_LT((back - a).norm(), 1e-9) << a.transpose();
  }
  // Gimbal lock: the rotation survives even though the angles are not unique.
  const Eigen::Quaterniond q = repose::rotationFromEulerAngles({20, 90, 30});
  EXPECT_NEAR(q.angularDistance(repose::rotationFromEulerAngles(repose::eulerAnglesFromRotation(q))), 0, 1e-9);
  // The last angle turns a bone about its own long axis: a knee flexed 90 degrees, then rotated,
  // leaves the shin pointing where the flexion put it.
  const Eigen::Quaterniond flexed = repose::rotationFromEulerAngles({90, 0, 0});
  const Eigen::Quaterniond rotated = repose::rotationFromEulerAngles({90, 0, 40});
  EXPECT_LT((flexed * kDown - rotated * kDown).norm(), 1e-12);
}

TEST(AnatomicalAngles, LimbFlexionIsPositive) {
  // Hip and shoulder flexion swing the limb forwards, knee flexion the shin backwards, elbow flexion
  // the forearm forwards, ankle dorsiflexion raises the toes.
  for (const char* j : {"left_hip", "right_hip", "left_shoulder", "right_shoulder", "left_elbow", "right_wrist"})
    EXPECT_LT(moved(j, {60, 0, 0}, kDown).y(), -0.8) << j;
  for (const char* j : {"left_knee", "right_knee"}) EXPECT_GT(moved(j, {45, 0, 0}, kDown).y(), 0.7) << j;
  EXPECT_GT(moved("left_ankle", {20, 0, 0}, kFront).z(), 0.3);
}

TEST(AnatomicalAngles, AbductionAndInternalRotationOnBothSides) {
  // Abduction moves the limb away from the midline: towards +x on the left, -x on the right.
  EXPECT_GT(moved("left_hip", {0, 30, 0}, kDown).x(), 0.4);
  EXPECT_LT(moved("right_hip", {0, 30, 0}, kDown).x(), -0.4);
  EXPECT_GT(moved("left_shoulder", {0, 80, 0}, kDown).x(), 0.9);
  EXPECT_LT(moved("right_shoulder", {0, 80, 0}, kDown).x(), -0.9);
  // Internal rotation turns the front of the limb towards the midline.
  EXPECT_LT(moved("left_hip", {0, 0, 30}, kFront).x(), -0.4);
  EXPECT_GT(moved("right_hip", {0, 0, 30}, kFront).x(), 0.4);
}

TEST(AnatomicalAngles, TrunkSigns) {
  EXPECT_LT(moved("spine", {30, 0, 0}, kUp).y(), -0.4);        // flexion: the trunk bends forwards
  EXPECT_LT(moved("vertebra_L3", {0, 20, 0}, kUp).x(), -0.3);  // lateral bending right: towards -x
  EXPECT_GT(moved("neck", {0, 0, 40}, kFront).x(), 0.6);       // axial rotation left: the face turns to +x
  EXPECT_LT(moved("pelvis", {20, 0, 0}, kUp).y(), -0.3);
}

TEST(AnatomicalAngles, AnglesRoundTripThroughTheSigns) {
  const repose::JointClass hip = classifyJoint("left_hip");
  const Vector3d a(60, 20, -15);
  EXPECT_LT((repose::anatomicalAngles(repose::rotationFromAnatomicalAngles(a, hip), hip) - a).norm(), 1e-9);
  EXPECT_EQ(repose::anatomicalAngleNames(hip)[0], "Flexion (+) / extension (−)");
}

TEST(JointLimits, RangesFollowTheJoint) {
  const repose::JointLimits knee = repose::jointLimits("left_knee");
  EXPECT_GE(knee.upper.x(), 140);  // a hinge: wide flexion
  EXPECT_LE(knee.lower.x(), 0);
  EXPECT_GE(knee.lower.x(), -15);  // little hyperextension
  EXPECT_LE(knee.upper.y(), 20);   // little valgus
  const repose::JointLimits hip = repose::jointLimits("right_hip");
  EXPECT_GE(hip.upper.x(), 120);
  EXPECT_LT(hip.lower.x(), 0);
  EXPECT_GT(hip.upper.y(), hip.lower.y());
  EXPECT_EQ(repose::jointLimits("pelvis").upper.z(), 180);
  EXPECT_EQ(knee.clamp({400, -400, 10}), Vector3d(knee.upper.x(), knee.lower.y(), 10));
  // The middle angle never leaves the decomposition's range.
  for (const char* j : {"pelvis", "spine", "neck", "left_hip", "left_knee", "left_ankle", "left_shoulder",
                        "left_elbow", "left_wrist", "clavicle"}) {
    const repose::JointLimits l = repose::jointLimits(j);
    EXPECT_GE(l.lower.y(), -90) << j;
    EXPECT_LE(l.upper.y(), 90) << j;
  }
}

TEST(Pose, AxisAngleWriterIsReadableAndReadsBack) {
  repose::Pose p;
  p.rotations["left_hip"] = Eigen::Quaterniond(Eigen::AngleAxisd(-M_PI / 3, Vector3d::UnitX()));
  p.rotations["left_knee"] = Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Vector3d(1, 2, 3).normalized()));
  p.translation = Vector3d(0, 0, 12.5);
  const std::string text = repose::poseToAxisAngleJson(p);
  // -60 degrees about x is written as 60 degrees about -x, with no rounding noise.
  EXPECT_NE(text.find("\"degrees\" : 60"), std::string::npos) << text;
  EXPECT_NE(text.find("-1"), std::string::npos) << text;
  EXPECT_EQ(text.find("quaternion"), std::string::npos);
  EXPECT_EQ(text.find("e-1"), std::string::npos) << text;  // no 1e-17 leftovers
  const repose::Pose q = repose::parsePoseJson(text);
  ASSERT_EQ(q.rotations.size(), 2u);
  for (const auto& [name, r] : p.rotations) EXPECT_LT(q.rotations.at(name).angularDistance(r), 1e-10) << name;
  EXPECT_EQ(q.translation, p.translation);
}
