// Retargeting BVH motion onto a skeleton with a different rest pose.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>

#include "bvh.h"
#include "bvh_joint_map.h"
#include "pose.h"
#include "retarget.h"
#include "skeleton.h"

namespace {

const std::string kMocap = std::string(REPOSE_SHARED_DATA) + "/mocap/";
constexpr double kDeg = M_PI / 180;

// A T-pose BVH in CMU MotionBuilder names: legs straight down, arms horizontal. The trunk is
// LowerBack, Spine and Head (no Spine1, Neck, Neck1). Columns (rotations in the
// order listed): Hips 0-5 (pos XYZ, rot Y X Z), LeftUpLeg 6-8 (Z X Y), LeftLeg 9-11 (X Y Z),
// LeftFoot 12-14 (Z Y X), RightUpLeg 15-17, RightLeg 18-20, RightFoot 21-23 (Z X Y),
// LowerBack 24-26, Spine 27-29, Head 30-32, LeftArm 33-35, LeftForeArm 36-38, LeftHand 39-41,
// RightArm 42-44, RightForeArm 45-47, RightHand 48-50 (all Z Y X).
const char* kHierarchy = R"(HIERARCHY
ROOT Hips
{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Yrotation Xrotation Zrotation
  JOINT LeftUpLeg
  {
    OFFSET 1.5 -0.5 0.2
    CHANNELS 3 Zrotation Xrotation Yrotation
    JOINT LeftLeg
    {
      OFFSET 0 -7 0
      CHANNELS 3 Xrotation Yrotation Zrotation
      JOINT LeftFoot
      {
        OFFSET 0 -7 0
        CHANNELS 3 Zrotation Yrotation Xrotation
        End Site
        {
          OFFSET 0 -0.5 2
        }
      }
    }
  }
  JOINT RightUpLeg
  {
    OFFSET -1.5 -0.5 0.2
    CHANNELS 3 Zrotation Xrotation Yrotation
    JOINT RightLeg
    {
      OFFSET 0 -7 0
      CHANNELS 3 Zrotation Xrotation Yrotation
      JOINT RightFoot
      {
        OFFSET 0 -7 0
        CHANNELS 3 Zrotation Xrotation Yrotation
        End Site
        {
          OFFSET 0 -0.5 2
        }
      }
    }
  }
  JOINT LowerBack
  {
    OFFSET 0 0 0
    CHANNELS 3 Zrotation Yrotation Xrotation
    JOINT Spine
    {
      OFFSET 0 3 -0.2
      CHANNELS 3 Zrotation Yrotation Xrotation
      JOINT Head
      {
        OFFSET 0 4 0.5
        CHANNELS 3 Zrotation Yrotation Xrotation
        End Site
        {
          OFFSET 0 2 0
        }
      }
      JOINT LeftArm
      {
        OFFSET 2 2.5 0
        CHANNELS 3 Zrotation Yrotation Xrotation
        JOINT LeftForeArm
        {
          OFFSET 4 0 0
          CHANNELS 3 Zrotation Yrotation Xrotation
          JOINT LeftHand
          {
            OFFSET 3 0 0
            CHANNELS 3 Zrotation Yrotation Xrotation
            End Site
            {
              OFFSET 1 0 0
            }
          }
        }
      }
      JOINT RightArm
      {
        OFFSET -2 2.5 0
        CHANNELS 3 Zrotation Yrotation Xrotation
        JOINT RightForeArm
        {
          OFFSET -4 0 0
          CHANNELS 3 Zrotation Yrotation Xrotation
          JOINT RightHand
          {
            OFFSET -3 0 0
            CHANNELS 3 Zrotation Yrotation Xrotation
            End Site
            {
              OFFSET -1 0 0
            }
          }
        }
      }
    }
  }
}
)";
constexpr int kColumns = 51;

std::string bvhText(const std::vector<std::vector<double>>& rows) {
  std::ostringstream out;
  out.precision(17);
  out << kHierarchy << "MOTION\nFrames: " << rows.size() << "\nFrame Time: 0.0333333\n";
  for (const auto& row : rows) {
    for (std::size_t k = 0; k < row.size(); ++k) out << (k ? " " : "") << row[k];
    out << "\n";
  }
  return out.str();
}

repose::Joint makeJoint(const std::string& name, int parent, double x, double y, double z) {
  repose::Joint j;
  j.name = name;
  j.parent = parent;
  j.center = Eigen::Vector3d(x, y, z);
  return j;
}

// Scan-like skeleton (LPS mm): lying straight, legs down and slightly converging, arms down at the
// sides: a different rest pose from the BVH's T-pose. Parents first.
repose::Skeleton scanSkeleton(double hipX = 90, double kneeX = 70, double shoulderX = 180) {
  repose::Skeleton s;
  s.joints.push_back(makeJoint("pelvis", -1, 0, 25, 960));
  s.joints.push_back(makeJoint("spine", 0, 0, 50, 1020));
  s.joints.push_back(makeJoint("neck", 1, 0, 8, 1555));
  for (double side : {1.0, -1.0}) {
    const std::string pre = side > 0 ? "left_" : "right_";
    const int base = int(s.joints.size());
    s.joints.push_back(makeJoint(pre + "hip", 0, side * hipX, 5, 920));
    s.joints.push_back(makeJoint(pre + "knee", base, side * kneeX, 5, 490));
    s.joints.push_back(makeJoint(pre + "ankle", base + 1, side * kneeX, 8, 80));
  }
  for (double side : {1.0, -1.0}) {
    const std::string pre = side > 0 ? "left_" : "right_";
    const int base = int(s.joints.size());
    s.joints.push_back(makeJoint(pre + "shoulder", 1, side * shoulderX, 5, 1385));
    s.joints.push_back(makeJoint(pre + "elbow", base, side * (shoulderX + 10), 5, 1100));
    s.joints.push_back(makeJoint(pre + "wrist", base + 1, side * (shoulderX + 10), 5, 840));
  }
  return s;
}

Eigen::Vector3d lps(const Eigen::Vector3d& bvh) { return repose::bvhToLps() * bvh; }

// Posed direction of the scan bone from joint a's centre to joint b's centre (b a descendant of a
// that does not move b's centre relative to a's bone).
Eigen::Vector3d scanBone(const repose::Skeleton& s, const std::vector<Eigen::Isometry3d>& g, const std::string& a,
                         const std::string& b) {
  const int ia = s.find(a), ib = s.find(b);
  return (g[ia] * s.joints[ib].center - g[ia] * s.joints[ia].center).normalized();
}
Eigen::Vector3d bvhBone(const repose::BvhMotion& m, const std::vector<Eigen::Isometry3d>& g, const std::string& a,
                        const std::string& b) {
  return lps(g[m.find(b)].translation() - g[m.find(a)].translation()).normalized();
}

struct Bone {
  const char *scanA, *scanB, *bvhA, *bvhB;
};
const Bone kLimbBones[] = {
    {"left_hip", "left_knee", "LeftUpLeg", "LeftLeg"},       {"left_knee", "left_ankle", "LeftLeg", "LeftFoot"},
    {"right_hip", "right_knee", "RightUpLeg", "RightLeg"},   {"right_knee", "right_ankle", "RightLeg", "RightFoot"},
    {"left_shoulder", "left_elbow", "LeftArm", "LeftForeArm"},
    {"left_elbow", "left_wrist", "LeftForeArm", "LeftHand"}, {"right_shoulder", "right_elbow", "RightArm", "RightForeArm"},
    {"right_elbow", "right_wrist", "RightForeArm", "RightHand"},
};

// A map of BVH joints that skeleton joints follow.
repose::BvhJointMap follow(std::initializer_list<std::pair<const std::string, std::string>> joints) {
  repose::BvhJointMap map;
  map.joints = joints;
  return map;
}

// Global rotation of a BVH joint in LPS.
Eigen::Matrix3d bvhRotation(const repose::BvhMotion& m, const std::vector<Eigen::Isometry3d>& g, const std::string& joint) {
  return repose::bvhToLps() * g[m.find(joint)].linear() * repose::bvhToLps().transpose();
}

double angleOf(const Eigen::Matrix3d& r) { return Eigen::AngleAxisd(r).angle() / kDeg; }

std::vector<double> zeroRow() { return std::vector<double>(kColumns, 0.0); }

repose::BvhMotion knownMotion() {
  std::vector<std::vector<double>> rows;
  rows.push_back(zeroRow());  // 0: rest (T-pose)
  {
    std::vector<double> r = zeroRow();  // 1: hip flexion 30, knee flexion 50, ankle 20, arm down, elbow 60
    r[0] = 1, r[1] = 2, r[2] = 3;
    r[7] = -30;   // LeftUpLeg Xrotation (Z X Y)
    r[9] = 50;    // LeftLeg Xrotation (X Y Z)
    r[14] = 20;   // LeftFoot Xrotation (Z Y X)
    r[33] = -90;  // LeftArm Zrotation
    r[37] = -60;  // LeftForeArm Yrotation
    rows.push_back(r);
  }
  {
    std::vector<double> r = zeroRow();  // 2: pure twists about the bone axes
    r[8] = 40;    // LeftUpLeg Yrotation: femur straight down, twisted
    r[35] = 30;   // LeftArm Xrotation: T-pose arm twisted
    rows.push_back(r);
  }
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> angle(-70, 70), position(-5, 5);
  for (int f = 0; f < 12; ++f) {  // 3..14: random everything
    std::vector<double> r(kColumns);
    for (int k = 0; k < kColumns; ++k) r[k] = k < 3 ? position(rng) : angle(rng);
    rows.push_back(r);
  }
  return repose::parseBvh(bvhText(rows), "known.bvh");
}

TEST(Retarget, DefaultMapResolvesBothCmuConversions) {
  const repose::Skeleton s = scanSkeleton();
  const repose::BvhJointMap walk = repose::defaultCmuJointMap(repose::readBvhFile(kMocap + "cmu_131_01_walk.bvh"), s);
  EXPECT_EQ(walk.joints.size(), 13u);  // pelvis and 12 limb joints
  EXPECT_EQ(walk.joints.at("LeftShoulder"), "left_shoulder");  // 3dsMax: LeftShoulder rotates the upper arm
  EXPECT_EQ(walk.joints.at("LeftHip"), "left_hip");
  EXPECT_EQ(walk.joints.at("RightWrist"), "right_wrist");
  // A whole-spine bone below the skull's joint takes the five CMU spine and neck joints, the skull the head.
  ASSERT_EQ(walk.shares.at("spine").size(), 5u);
  EXPECT_EQ(walk.shares.at("spine")[0].bvhJoint, "lowerback");
  EXPECT_EQ(walk.shares.at("spine")[4].bvhJoint, "Neck");  // 3dsMax: Neck is the upper neck
  ASSERT_EQ(walk.shares.at("neck").size(), 1u);
  EXPECT_EQ(walk.shares.at("neck")[0].bvhJoint, "Head");
  const repose::BvhJointMap mb = repose::defaultCmuJointMap(repose::readBvhFile(kMocap + "cmu_short_75frames.bvh"), s);
  EXPECT_EQ(mb.joints.size(), 13u);
  EXPECT_EQ(mb.joints.at("LeftArm"), "left_shoulder");  // MotionBuilder: LeftShoulder is the collar
  EXPECT_EQ(mb.joints.count("LeftShoulder"), 0u);
  EXPECT_EQ(mb.joints.at("LeftUpLeg"), "left_hip");
  EXPECT_EQ(mb.shares.at("spine")[0].bvhJoint, "LowerBack");
  EXPECT_EQ(mb.shares.at("spine")[3].bvhJoint, "Neck");  // MotionBuilder: Neck is the lower neck
  EXPECT_EQ(mb.shares.at("neck")[0].bvhJoint, "Head");
}

TEST(Retarget, DirectionModeReproducesBvhBoneDirections) {
  const repose::BvhMotion m = knownMotion();
  const repose::Skeleton s = scanSkeleton();
  const repose::BvhRetargeter retarget(m, s, repose::defaultCmuJointMap(m, s));
  EXPECT_EQ(retarget.mainChild()[s.find("left_hip")], s.find("left_knee"));
  for (int f = 0; f < m.frameCount; ++f) {
    const repose::Pose pose = retarget.pose(f);
    const auto g = repose::forwardKinematics(s, pose);
    const auto b = repose::bvhGlobalPose(m, f);
    for (const Bone& bone : kLimbBones)
      EXPECT_LT((scanBone(s, g, bone.scanA, bone.scanB) - bvhBone(m, b, bone.bvhA, bone.bvhB)).norm(), 1e-6)
          << "frame " << f << " bone " << bone.scanA << "->" << bone.scanB;
    // The pelvis's left-right axis (between the hip centres) follows the BVH's.
    const int pelvis = s.find("pelvis");
    const Eigen::Vector3d lateral =
        (g[pelvis].linear() * (s.joints[s.find("left_hip")].center - s.joints[s.find("right_hip")].center)).normalized();
    EXPECT_LT((lateral - bvhBone(m, b, "RightUpLeg", "LeftUpLeg")).norm(), 1e-6) << "frame " << f;
    // The trunk turns as the clip's does from its rest pose (both rest poses have the hips on the x
    // axis, so the body's alignment is the identity): the whole-spine bone as Spine, the skull as Head.
    EXPECT_LT((g[s.find("spine")].linear() - bvhRotation(m, b, "Spine")).norm(), 1e-9) << "frame " << f;
    EXPECT_LT((g[s.find("neck")].linear() - bvhRotation(m, b, "Head")).norm(), 1e-9) << "frame " << f;
    // Rigid transforms only.
    for (const auto& t : g) EXPECT_LT((t.linear().transpose() * t.linear() - Eigen::Matrix3d::Identity()).norm(), 1e-9);
  }

  // Hand-computed directions for frame 1 (root not rotated).
  const auto g = repose::forwardKinematics(s, retarget.pose(1));
  const double s30 = std::sin(30 * kDeg), c30 = std::cos(30 * kDeg), s20 = std::sin(20 * kDeg), c20 = std::cos(20 * kDeg);
  EXPECT_LT((scanBone(s, g, "left_hip", "left_knee") - Eigen::Vector3d(0, -s30, -c30)).norm(), 1e-9);  // thigh forward
  EXPECT_LT((scanBone(s, g, "left_knee", "left_ankle") - Eigen::Vector3d(0, s20, -c20)).norm(), 1e-9);  // shin back
  EXPECT_LT((scanBone(s, g, "left_shoulder", "left_elbow") - Eigen::Vector3d(0, 0, -1)).norm(), 1e-9);  // arm down
  EXPECT_LT((scanBone(s, g, "left_elbow", "left_wrist") - Eigen::Vector3d(0, -c30, -s30)).norm(), 1e-9);  // forearm fwd
  EXPECT_LT((scanBone(s, g, "right_hip", "right_knee") - Eigen::Vector3d(0, 0, -1)).norm(), 1e-9);
  EXPECT_LT((scanBone(s, g, "right_shoulder", "right_elbow") - Eigen::Vector3d(-1, 0, 0)).norm(), 1e-9);  // T-pose
  // Limb end (ankle): keeps the knee's rotation composed with the BVH ankle's 20 degrees.
  const repose::Pose p1 = retarget.pose(1);
  EXPECT_NEAR(Eigen::AngleAxisd(p1.rotations.at("left_ankle")).angle(), 20 * kDeg, 1e-9);
  EXPECT_NEAR(Eigen::AngleAxisd(p1.rotations.at("right_ankle")).angle(), 0, 1e-9);
  // Root translation: inferred CMU units (legs of 14 units) to mm, BVH (1,2,3) -> LPS (1,-3,2),
  // relative to frame 0.
  EXPECT_EQ(retarget.units().name, "CMU units of 1/0.45 inch");
  EXPECT_LT((p1.translation - 25.4 / 0.45 * Eigen::Vector3d(1, -3, 2)).norm(), 1e-9);
}

TEST(Retarget, DirectionModeTransfersTwist) {
  const repose::BvhMotion m = knownMotion();
  const repose::Skeleton s = scanSkeleton();
  const auto g = repose::forwardKinematics(s, repose::BvhRetargeter(m, s, repose::defaultCmuJointMap(m, s)).pose(2));
  const Eigen::Vector3d anterior(0, -1, 0);  // perpendicular to the femur and arm swings between the rest poses
  // Femur twisted 40 degrees about its (vertical) axis: BVH forward (0,0,1) -> Ry(40) (0,0,1).
  const Eigen::Vector3d femurForward = g[s.find("left_hip")].linear() * anterior;
  EXPECT_LT((femurForward - lps(Eigen::Vector3d(std::sin(40 * kDeg), 0, std::cos(40 * kDeg)))).norm(), 1e-9);
  EXPECT_LT((scanBone(s, g, "left_hip", "left_knee") - Eigen::Vector3d(0, 0, -1)).norm(), 1e-9);
  // Arm lifted to the T-pose and twisted 30 degrees about it: forward -> Rx(30) (0,0,1).
  const Eigen::Vector3d armForward = g[s.find("left_shoulder")].linear() * anterior;
  EXPECT_LT((armForward - lps(Eigen::Vector3d(0, -std::sin(30 * kDeg), std::cos(30 * kDeg)))).norm(), 1e-9);
  EXPECT_LT((scanBone(s, g, "left_shoulder", "left_elbow") - Eigen::Vector3d(1, 0, 0)).norm(), 1e-9);
  // The untwisted right side keeps its forward axis.
  EXPECT_LT((g[s.find("right_hip")].linear() * anterior - anterior).norm(), 1e-9);
}

TEST(Retarget, RelativeMode) {
  const repose::BvhMotion m = knownMotion();
  const repose::Skeleton s = scanSkeleton();
  const repose::BvhJointMap map = repose::defaultCmuJointMap(m, s);
  for (int f : {1, 5, 9}) {
    repose::RetargetOptions options;
    options.mode = repose::RetargetMode::Relative;
    options.referenceFrame = f;
    const repose::Pose pose = repose::BvhRetargeter(m, s, map, options).pose(f);
    EXPECT_EQ(pose.rotations.size(), 15u);
    for (const auto& r : pose.rotations) EXPECT_LT(Eigen::AngleAxisd(r.second).angle(), 1e-9) << r.first;
    EXPECT_LT(pose.translation.norm(), 1e-9);
  }
  // Reference = rest frame 0: every driven scan bone turns by its BVH joint's global rotation (the
  // whole-spine bone by Spine's, whose rotation includes LowerBack's; the skull by Head's).
  repose::RetargetOptions options;
  options.mode = repose::RetargetMode::Relative;
  const repose::BvhRetargeter retarget(m, s, map, options);
  for (int f = 1; f < m.frameCount; ++f) {
    const auto g = repose::forwardKinematics(s, retarget.pose(f));
    const auto b = repose::bvhGlobalPose(m, f);
    for (const Bone& bone : kLimbBones)
      EXPECT_LT((g[s.find(bone.scanA)].linear() - bvhRotation(m, b, bone.bvhA)).norm(), 1e-9)
          << "frame " << f << " " << bone.scanA;
    EXPECT_LT((g[s.find("spine")].linear() - bvhRotation(m, b, "Spine")).norm(), 1e-9) << "frame " << f;
    EXPECT_LT((g[s.find("neck")].linear() - bvhRotation(m, b, "Head")).norm(), 1e-9) << "frame " << f;
  }
}

TEST(Retarget, RejectsBadMapsAndOptions) {
  const repose::BvhMotion m = knownMotion();
  const repose::Skeleton s = scanSkeleton();
  EXPECT_THROW(repose::BvhRetargeter(m, s, follow({{"NoSuchJoint", "left_hip"}})), std::invalid_argument);
  EXPECT_THROW(repose::BvhRetargeter(m, s, follow({{"LeftUpLeg", "no_such_joint"}})), std::invalid_argument);
  EXPECT_THROW(repose::BvhRetargeter(m, s, follow({{"LeftUpLeg", "left_hip"}, {"LeftLeg", "left_hip"}})),
               std::invalid_argument);
  EXPECT_THROW(repose::BvhRetargeter(m, s, repose::BvhJointMap()), std::invalid_argument);
  // A map that drives the root alone would give rest-pose frames.
  EXPECT_THROW(repose::BvhRetargeter(m, s, follow({{"Hips", "pelvis"}})), std::invalid_argument);
  repose::BvhJointMap shares;
  shares.shares["spine"] = {{"NoSuchJoint", 0.5}};
  EXPECT_THROW(repose::BvhRetargeter(m, s, shares), std::invalid_argument);
  shares.shares["spine"] = {{"Spine", -1}};
  EXPECT_THROW(repose::BvhRetargeter(m, s, shares), std::invalid_argument);
  repose::RetargetOptions bad;
  bad.referenceFrame = m.frameCount;
  EXPECT_THROW(repose::BvhRetargeter(m, s, follow({{"LeftUpLeg", "left_hip"}}), bad), std::invalid_argument);
  EXPECT_THROW(repose::BvhRetargeter(m, s, follow({{"LeftUpLeg", "left_hip"}})).pose(-1), std::invalid_argument);
  repose::RetargetOptions negative;
  negative.unitScaleMm = -10;
  EXPECT_THROW(repose::BvhRetargeter(m, s, follow({{"LeftUpLeg", "left_hip"}}), negative), std::invalid_argument);
  EXPECT_THROW(repose::parseRetargetMode("sideways"), std::invalid_argument);
  const repose::BvhJointMap map = repose::parseJointMapJson(R"({"map": {"LeftUpLeg": "left_hip", "Hips": "pelvis"}})");
  EXPECT_EQ(map.joints.size(), 2u);
  EXPECT_EQ(map.joints.at("Hips"), "pelvis");
  EXPECT_THROW(repose::parseJointMapJson(R"({"LeftUpLeg": 3})"), std::invalid_argument);
  EXPECT_THROW(repose::parseJointMapJson("[1,2"), std::invalid_argument);
  // Joints not in the map follow their parents.
  const repose::Pose pose = repose::BvhRetargeter(m, s, map).pose(5);
  EXPECT_EQ(pose.rotations.size(), 2u);
  const auto g = repose::forwardKinematics(s, pose);
  EXPECT_TRUE(g[s.find("left_knee")].isApprox(g[s.find("left_hip")], 1e-12));
}

// Per sampled frame: femur and upper-arm anterior components (in the pelvis's frame, so the
// walking direction does not matter), knee angles and knee flexion sense, from the posed scan.
struct GaitSample {
  int frame;
  double antL, antR, armL, armR, kneeL, kneeR;
  bool kneesFlexBackward;
};

std::vector<GaitSample> gait(const repose::Skeleton& s, const repose::BvhRetargeter& retarget, int first, int last,
                             int step) {
  std::vector<GaitSample> out;
  for (int f = first; f <= last; f += step) {
    const auto g = repose::forwardKinematics(s, retarget.pose(f));
    const Eigen::Matrix3d pelvis = g[s.find("pelvis")].linear();
    auto anterior = [&](const Eigen::Vector3d& d) { return -(pelvis.transpose() * d).y(); };
    auto angle = [](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
      return std::acos(std::clamp(a.dot(b), -1.0, 1.0)) / kDeg;
    };
    GaitSample x;
    x.frame = f;
    x.kneesFlexBackward = true;
    for (const char* side : {"left_", "right_"}) {
      const std::string pre = side;
      const Eigen::Vector3d femur = scanBone(s, g, pre + "hip", pre + "knee");
      const Eigen::Vector3d tibia = scanBone(s, g, pre + "knee", pre + "ankle");
      const Eigen::Vector3d arm = scanBone(s, g, pre + "shoulder", pre + "elbow");
      const double knee = angle(femur, tibia);
      // Flexion turns the shin posteriorly about the thigh's left axis (+x at rest, LPS).
      const Eigen::Vector3d thighLeft = g[s.find(pre + "hip")].linear() * Eigen::Vector3d::UnitX();
      if (knee > 20 && femur.cross(tibia).dot(thighLeft) <= 0) x.kneesFlexBackward = false;
      (pre == "left_" ? x.antL : x.antR) = anterior(femur);
      (pre == "left_" ? x.armL : x.armR) = anterior(arm);
      (pre == "left_" ? x.kneeL : x.kneeR) = knee;
    }
    out.push_back(x);
  }
  return out;
}

double correlation(const std::vector<double>& a, const std::vector<double>& b) {
  const double n = double(a.size());
  double ma = 0, mb = 0;
  for (std::size_t i = 0; i < a.size(); ++i) ma += a[i] / n, mb += b[i] / n;
  double sab = 0, saa = 0, sbb = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    sab += (a[i] - ma) * (b[i] - mb);
    saa += (a[i] - ma) * (a[i] - ma);
    sbb += (b[i] - mb) * (b[i] - mb);
  }
  return sab / std::sqrt(saa * sbb);
}

// Legs swing in opposition (left-minus-right femur swing against each leg's), arms against the legs.
void expectWalking(const std::vector<GaitSample>& samples, const char* what) {
  std::vector<double> antL, antR, legLead, armLead;
  for (const GaitSample& x : samples) {
    antL.push_back(x.antL);
    antR.push_back(x.antR);
    legLead.push_back(x.antL - x.antR);
    armLead.push_back(x.armL - x.armR);
  }
  const double legs = correlation(antL, antR), arms = correlation(legLead, armLead);
  std::printf("%s: %zu frames, femur swing correlation left/right %.2f, arms/legs %.2f\n", what, samples.size(), legs,
              arms);
  EXPECT_LT(legs, -0.3) << what;
  EXPECT_LT(arms, -0.3) << what;
  EXPECT_GT(*std::max_element(legLead.begin(), legLead.end()), 0.5) << what;  // left leg leads by > 30 degrees
  EXPECT_LT(*std::min_element(legLead.begin(), legLead.end()), -0.5) << what;  // and right leg leads
}

TEST(Retarget, CmuWalkOnPhantomLikeSkeletonWalks) {
  const repose::BvhMotion m = repose::readBvhFile(kMocap + "cmu_131_01_walk.bvh");
  const repose::Skeleton s = scanSkeleton(100, 90, 190);
  const repose::BvhRetargeter retarget(m, s, repose::defaultCmuJointMap(m, s));

  const auto start = std::chrono::steady_clock::now();
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (int f = 0; f < m.frameCount; ++f) sum += retarget.pose(f).translation;
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("retargeted %d frames onto %zu joints: %.2f us per frame\n", m.frameCount, s.size(),
              seconds * 1e6 / m.frameCount);
  EXPECT_GT(sum.norm(), 0);  // the root moves (and the loop is not optimized away)

  // Whole clip, every 50th frame: left and right lead in turn, knees bend the right way.
  const std::vector<GaitSample> sparse = gait(s, retarget, 0, m.frameCount - 1, 50);
  int leftLeads = 0, rightLeads = 0, bent = 0;
  for (const GaitSample& x : sparse) {
    leftLeads += x.antL - x.antR > 0.3;
    rightLeads += x.antR - x.antL > 0.3;
    bent += x.kneeL > 5 || x.kneeR > 5;
    EXPECT_TRUE(x.kneesFlexBackward) << "frame " << x.frame;
  }
  std::printf("walk, every 50th frame: left leg ahead in %d, right in %d, a knee bent > 5 deg in %d of %zu\n",
              leftLeads, rightLeads, bent, sparse.size());
  EXPECT_GE(leftLeads, 3);
  EXPECT_GE(rightLeads, 3);
  EXPECT_GE(bent, 5);
  // Frames 500-700 are steady walking (the root advances along +Z; before them the subject turns
  // and squats, after them stops in a wide stance).
  expectWalking(gait(s, retarget, 500, 700, 10), "cmu_131_01_walk frames 500-700");
}

TEST(Retarget, CmuShortClipMotionBuilderNamesWalks) {
  const repose::BvhMotion m = repose::readBvhFile(kMocap + "cmu_short_75frames.bvh");
  const repose::Skeleton s = scanSkeleton(100, 90, 190);
  const repose::BvhRetargeter retarget(m, s, repose::defaultCmuJointMap(m, s));
  const std::vector<GaitSample> samples = gait(s, retarget, 0, m.frameCount - 1, 3);
  double maxKnee = 0;
  for (const GaitSample& x : samples) {
    maxKnee = std::max({maxKnee, x.kneeL, x.kneeR});
    EXPECT_TRUE(x.kneesFlexBackward) << "frame " << x.frame;
  }
  EXPECT_GT(maxKnee, 45);
  expectWalking(samples, "cmu_short_75frames");
}

// A lying scan rigged with the standard joint names (LPS mm): every vertebra from L5 ("spine") to
// C1, a neck (C7) leaning 25 degrees forward as a lordotic cervical spine does, the head (skull),
// jaw, clavicles, scapulae, limbs, and a patella joint as a hand-made rig may have (not a standard
// name: the rig lets the patella ride with its femur). Parents first.
repose::Skeleton standardSkeleton(bool clavicles = true) {
  repose::Skeleton s;
  s.joints.push_back(makeJoint("pelvis", -1, 0, 25, 960));
  // Spinal levels 0 (L5) .. 23 (C1): a curved column, the neck part leaning forward (-y).
  auto levelName = [](int level) -> std::string {
    if (level == 0) return "spine";
    if (level < 5) return "vertebra_L" + std::to_string(5 - level);
    if (level < 17) return "vertebra_T" + std::to_string(17 - level);
    if (level == 17) return "neck";
    return "vertebra_C" + std::to_string(24 - level);
  };
  Eigen::Vector3d c(0, 50, 1010);
  for (int level = 0; level < 24; ++level) {
    s.joints.push_back(makeJoint(levelName(level), int(s.joints.size()) - 1, c.x(), c.y(), c.z()));
    const double lean = level < 17 ? 8.0 * std::cos(level * 0.4) * kDeg : 25 * kDeg;
    c += 24.0 * Eigen::Vector3d(0, -std::sin(lean), std::cos(lean));
  }
  const int c1 = int(s.joints.size()) - 1, t1 = s.find("vertebra_T1");
  s.joints.push_back(makeJoint("head", c1, c.x(), c.y(), c.z()));
  s.joints.push_back(makeJoint("jaw", int(s.joints.size()) - 1, 0, c.y() - 60, c.z() + 30));
  for (double side : {1.0, -1.0}) {
    const std::string pre = side > 0 ? "left_" : "right_";
    int parent = t1;
    if (clavicles) {
      s.joints.push_back(makeJoint(pre + "clavicle", t1, side * 25, -20, 1420));
      parent = int(s.joints.size()) - 1;
    }
    s.joints.push_back(makeJoint(pre + "scapula", parent, side * 150, 40, 1410));
    const int base = int(s.joints.size());
    s.joints.push_back(makeJoint(pre + "shoulder", base - 1, side * 180, 5, 1385));
    s.joints.push_back(makeJoint(pre + "elbow", base, side * 190, 5, 1100));
    s.joints.push_back(makeJoint(pre + "wrist", base + 1, side * 190, 5, 840));
  }
  for (double side : {1.0, -1.0}) {
    const std::string pre = side > 0 ? "left_" : "right_";
    const int base = int(s.joints.size());
    s.joints.push_back(makeJoint(pre + "hip", 0, side * 100, 5, 920));
    s.joints.push_back(makeJoint(pre + "knee", base, side * 90, 5, 490));
    s.joints.push_back(makeJoint(pre + "ankle", base + 1, side * 90, 8, 80));
    s.joints.push_back(makeJoint(pre + "patella", base, side * 90, -30, 510));
  }
  return s;
}

TEST(Retarget, DefaultMapDrivesTheStandardVocabulary) {
  for (const char* file : {"cmu_131_01_walk.bvh", "cmu_short_75frames.bvh"}) {
    const repose::BvhMotion m = repose::readBvhFile(kMocap + file);
    const bool mb = std::string(file) == "cmu_short_75frames.bvh";
    const repose::Skeleton s = standardSkeleton();
    const repose::BvhJointMap map = repose::defaultCmuJointMap(m, s);
    const repose::JointMapCoverage c = repose::jointMapCoverage(s, map);
    std::map<std::string, std::string> driven(c.driven.begin(), c.driven.end());
    std::printf("%s on %zu joints: %zu driven, undriven limbs %zu, following:", file, s.size(), c.driven.size(),
                c.undrivenLimbs.size());
    for (const std::string& f : c.following) std::printf(" %s", f.c_str());
    std::printf("\n");
    EXPECT_TRUE(c.undrivenLimbs.empty()) << file;
    // Every joint but the jaw and the scapulae (they ride on the driven clavicles), and the patellae,
    // which are not standard joints.
    EXPECT_EQ(c.following, (std::vector<std::string>{"jaw", "left_scapula", "right_scapula"})) << file;
    EXPECT_EQ(c.unknownNames, (std::vector<std::string>{"left_patella", "right_patella"})) << file;
    EXPECT_EQ(driven.size(), s.size() - 5) << file;
    EXPECT_EQ(driven["pelvis"], "Hips");
    EXPECT_EQ(driven["left_knee"], mb ? "LeftLeg" : "LeftKnee") << file;
    EXPECT_EQ(driven["right_ankle"], mb ? "RightFoot" : "RightAnkle") << file;
    EXPECT_EQ(driven["left_clavicle"], mb ? "LeftShoulder" : "LeftCollar") << file;
    EXPECT_EQ(driven["left_shoulder"], mb ? "LeftArm" : "LeftShoulder") << file;
    EXPECT_EQ(driven["right_wrist"], mb ? "RightHand" : "RightWrist") << file;
    EXPECT_EQ(driven["head"], "Head") << file;
    EXPECT_EQ(driven["vertebra_L3"], mb ? "LowerBack 20%" : "lowerback 20%") << file;
    EXPECT_EQ(driven["vertebra_C2"], mb ? "Neck1 33%" : "Neck 33%") << file;
    // Each CMU trunk joint's rotation is shared out exactly once over the vertebrae.
    std::map<std::string, double> total;
    for (const auto& [joint, shares] : map.shares)
      for (const repose::BvhShare& share : shares) total[share.bvhJoint] += share.fraction;
    EXPECT_EQ(total.size(), 6u) << file;
    for (const auto& [bvh, sum] : total) EXPECT_NEAR(sum, 1.0, 1e-12) << file << " " << bvh;
    // Without clavicles the collar drives the scapula.
    const repose::BvhJointMap noClavicle = repose::defaultCmuJointMap(m, standardSkeleton(false));
    EXPECT_EQ(noClavicle.joints.at(mb ? "LeftShoulder" : "LeftCollar"), "left_scapula") << file;
    EXPECT_TRUE(repose::jointMapCoverage(standardSkeleton(false), noClavicle).undrivenLimbs.empty()) << file;
  }
}

// A lumbar and lower thoracic scan (as TotalSegmentator's abdominal CT): the vertebrae share the
// lower back and a sixth of the upper back each.
TEST(Retarget, DefaultMapSharesTheSpineByLevel) {
  repose::Skeleton s;
  s.joints.push_back(makeJoint("pelvis", -1, 0, 25, 960));
  s.joints.push_back(makeJoint("spine", 0, 0, 50, 1010));
  const char* levels[] = {"vertebra_L4", "vertebra_L3", "vertebra_L2", "vertebra_L1", "vertebra_T12", "vertebra_T11"};
  for (int k = 0; k < 6; ++k) s.joints.push_back(makeJoint(levels[k], k + 1, 0, 50, 1040 + 30 * k));
  s.joints.push_back(makeJoint("left_hip", 0, 100, 5, 920));
  s.joints.push_back(makeJoint("right_hip", 0, -100, 5, 920));
  const repose::BvhMotion m = repose::readBvhFile(kMocap + "cmu_131_01_walk.bvh");
  const repose::BvhJointMap map = repose::defaultCmuJointMap(m, s);
  ASSERT_EQ(map.shares.size(), 7u);
  for (const char* joint : {"spine", "vertebra_L4", "vertebra_L1"}) {
    ASSERT_EQ(map.shares.at(joint).size(), 1u) << joint;
    EXPECT_EQ(map.shares.at(joint)[0].bvhJoint, "lowerback");
    EXPECT_NEAR(map.shares.at(joint)[0].fraction, 0.2, 1e-12) << joint;
  }
  EXPECT_EQ(map.shares.at("vertebra_T11")[0].bvhJoint, "Chest");
  EXPECT_NEAR(map.shares.at("vertebra_T11")[0].fraction, 1.0 / 6, 1e-12);
  // Over the walk the lumbar chain together bends as the clip's lower back, each vertebra a fifth.
  const repose::BvhRetargeter retarget(m, s, map);
  for (int f = 500; f < 700; f += 25) {
    const repose::Pose pose = retarget.pose(f);
    const auto g = repose::forwardKinematics(s, pose);
    const auto b = repose::bvhGlobalPose(m, f);
    const Eigen::Matrix3d clip = bvhRotation(m, b, "Hips").transpose() * bvhRotation(m, b, "lowerback");
    const Eigen::Matrix3d scan = g[0].linear().transpose() * g[s.find("vertebra_L1")].linear();
    EXPECT_LT(angleOf(clip.transpose() * scan), 0.5) << "frame " << f;
    EXPECT_NEAR(angleOf(pose.rotations.at("vertebra_L3").toRotationMatrix()), angleOf(clip) / 5, 1e-6) << "frame " << f;
  }
}

// A neck scan cut below the skull: the rig calls C7 "neck" and names the vertebrae above it, with no
// head joint. The neck is the cervical joint it is (lower neck and upper neck over C7-C1), not the
// skull it would be without cervical vertebrae, and the clip's head drives nothing.
TEST(Retarget, DefaultMapKnowsANeckWithoutHead) {
  repose::Skeleton s;
  s.joints.push_back(makeJoint("pelvis", -1, 0, 25, 960));
  s.joints.push_back(makeJoint("vertebra_T1", 0, 0, 50, 1400));
  s.joints.push_back(makeJoint("neck", 1, 0, 45, 1425));
  for (int c = 6; c >= 1; --c)
    s.joints.push_back(makeJoint("vertebra_C" + std::to_string(c), int(s.joints.size()) - 1, 0, 40, 1425 + 20 * (7 - c)));
  const repose::BvhMotion m = repose::readBvhFile(kMocap + "cmu_131_01_walk.bvh");
  const repose::BvhJointMap map = repose::defaultCmuJointMap(m, s);
  ASSERT_EQ(map.shares.at("neck").size(), 1u);
  EXPECT_EQ(map.shares.at("neck")[0].bvhJoint, "lowerneck");
  EXPECT_NEAR(map.shares.at("neck")[0].fraction, 0.25, 1e-12);
  EXPECT_EQ(map.shares.at("vertebra_C1")[0].bvhJoint, "Neck");
  EXPECT_NEAR(map.shares.at("vertebra_C1")[0].fraction, 1.0 / 3, 1e-12);
  for (const auto& [joint, shares] : map.shares)
    for (const repose::BvhShare& share : shares) EXPECT_NE(share.bvhJoint, "Head") << joint;
  // Without the cervical vertebrae the same name is the skull's joint: it takes the clip's head.
  s.joints.resize(3);
  const repose::BvhJointMap skull = repose::defaultCmuJointMap(m, s);
  EXPECT_EQ(skull.shares.at("neck").back().bvhJoint, "Head");
}

// Pitch (degrees, forward flexion positive) of rotation r about the body's left-right axis: where r
// takes the superior axis, in the sagittal plane.
double pitch(const Eigen::Matrix3d& r) {
  const Eigen::Vector3d up = r * Eigen::Vector3d::UnitZ();
  return std::atan2(-up.y(), up.z()) / kDeg;
}

// Head pitch relative to the upper trunk, scan against clip, over the clip; returns the worst gap.
double worstHeadPitchGap(const repose::BvhMotion& m, const repose::Skeleton& s, const repose::BvhJointMap& map,
                         const std::string& scanTrunk, const std::string& bvhTrunk, double* clipRange) {
  const repose::BvhRetargeter retarget(m, s, map);
  double worst = 0, lo = 1e9, hi = -1e9;
  for (int f = 0; f < m.frameCount; f += 5) {
    const auto g = repose::forwardKinematics(s, retarget.pose(f));
    const auto b = repose::bvhGlobalPose(m, f);
    const double clip = pitch(bvhRotation(m, b, bvhTrunk).transpose() * bvhRotation(m, b, "Head"));
    const double scan = pitch(g[s.find(scanTrunk)].linear().transpose() * g[s.find("head")].linear());
    worst = std::max(worst, std::abs(scan - clip));
    lo = std::min(lo, clip), hi = std::max(hi, clip);
  }
  clipRange[0] = lo, clipRange[1] = hi;
  return worst;
}

// A hand-written map that sends the clip's neck to the scan's C7 and its head to the skull once
// pitched the head back by about 60 degrees: the neck's rest alignment (the scan's forward-leaning
// cervical spine onto the clip's vertical one) was carried over to the head, and the upper neck's
// rotation counted twice. The head must follow the clip's head relative to the upper trunk.
TEST(Retarget, HeadKeepsTheClipsPitchWithAHandWrittenMap) {
  const repose::Skeleton s = standardSkeleton();
  const struct {
    const char* file;
    repose::BvhJointMap map;
    const char* thorax;
  } cases[] = {
      {"cmu_short_75frames.bvh",
       follow({{"Hips", "pelvis"}, {"LowerBack", "spine"}, {"Spine1", "vertebra_T12"}, {"Neck", "neck"},
               {"Head", "head"}, {"LeftUpLeg", "left_hip"}, {"RightUpLeg", "right_hip"}}),
       "Spine1"},
      {"cmu_131_01_walk.bvh",
       follow({{"Hips", "pelvis"}, {"lowerback", "spine"}, {"Chest2", "vertebra_T12"}, {"lowerneck", "neck"},
               {"Head", "head"}, {"LeftHip", "left_hip"}, {"RightHip", "right_hip"}}),
       "Chest2"},
  };
  for (const auto& c : cases) {
    const repose::BvhMotion m = repose::readBvhFile(kMocap + c.file);
    double range[2];
    const double gap = worstHeadPitchGap(m, s, c.map, "vertebra_T12", c.thorax, range);
    std::printf("%s, hand-written map: clip head pitch %.1f..%.1f deg, scan head off it by %.2f deg at most\n",
                c.file, range[0], range[1], gap);
    EXPECT_LT(gap, 20) << c.file;
    EXPECT_LT(gap, 1e-6) << c.file;  // one factor per mapped pair: exact
  }
}

// The built-in map on the full vocabulary: the head's pitch against T1 follows the clip's against
// its thorax (the vertebrae share out whole CMU joints, so exactly), and the knees flex as the clip's
// (whose subject walks with knees bent 20-50 degrees in stance and up to about 100 in swing).
TEST(Retarget, DefaultMapHeadPitchAndKneeFlexionOverTheWalk) {
  const repose::Skeleton s = standardSkeleton();
  for (const char* file : {"cmu_131_01_walk.bvh", "cmu_short_75frames.bvh"}) {
    const repose::BvhMotion m = repose::readBvhFile(kMocap + file);
    const repose::BvhJointMap map = repose::defaultCmuJointMap(m, s);
    const bool mb = std::string(file) == "cmu_short_75frames.bvh";
    double range[2];
    const double gap = worstHeadPitchGap(m, s, map, "vertebra_T1", mb ? "Spine1" : "Chest2", range);
    const repose::BvhRetargeter retarget(m, s, map);
    const int first = mb ? 0 : 500, last = mb ? m.frameCount - 1 : 700;
    double kneeLo = 1e9, kneeHi = 0, clipLo = 1e9, clipHi = 0;
    for (const GaitSample& x : gait(s, retarget, first, last, 2)) {
      kneeLo = std::min({kneeLo, x.kneeL, x.kneeR}), kneeHi = std::max({kneeHi, x.kneeL, x.kneeR});
      const auto b = repose::bvhGlobalPose(m, x.frame);
      for (const char* side : {"Left", "Right"}) {
        const std::string pre = side;
        const double clip = std::acos(std::clamp(bvhBone(m, b, pre + (mb ? "UpLeg" : "Hip"), pre + (mb ? "Leg" : "Knee"))
                                                     .dot(bvhBone(m, b, pre + (mb ? "Leg" : "Knee"), pre + (mb ? "Foot" : "Ankle"))),
                                                 -1.0, 1.0)) / kDeg;
        clipLo = std::min(clipLo, clip), clipHi = std::max(clipHi, clip);
      }
    }
    std::printf("%s: head pitch (clip %.1f..%.1f deg) within %.2f deg; knee flexion %.1f..%.1f deg over frames "
                "%d-%d (the clip's %.1f..%.1f)\n", file, range[0], range[1], gap, kneeLo, kneeHi, first, last, clipLo, clipHi);
    EXPECT_LT(gap, 20) << file;
    EXPECT_NEAR(kneeLo, clipLo, 0.5) << file;
    EXPECT_NEAR(kneeHi, clipHi, 0.5) << file;
    EXPECT_GT(kneeHi, 45) << file;
  }
}

// Feet and hands keep the clip's angle to the shank and forearm (their limb's rest alignment, the
// same rest reference as the bone they hang from).
TEST(Retarget, LimbEndsKeepTheClipsAngleToTheirLimb) {
  const repose::Skeleton s = standardSkeleton();
  for (const char* file : {"cmu_131_01_walk.bvh", "cmu_short_75frames.bvh"}) {
    const repose::BvhMotion m = repose::readBvhFile(kMocap + file);
    const bool mb = std::string(file) == "cmu_short_75frames.bvh";
    const repose::BvhRetargeter retarget(m, s, repose::defaultCmuJointMap(m, s));
    const std::pair<std::string, std::string> ends[] = {
        {mb ? "LeftLeg" : "LeftKnee", mb ? "LeftFoot" : "LeftAnkle"},
        {mb ? "RightForeArm" : "RightElbow", mb ? "RightHand" : "RightWrist"}};
    const char* scanEnds[] = {"left_ankle", "right_wrist"};
    double worst = 0;
    for (int f = 0; f < m.frameCount; f += 7) {
      const repose::Pose pose = retarget.pose(f);
      const auto b = repose::bvhGlobalPose(m, f);
      for (int e = 0; e < 2; ++e) {
        const double clip = angleOf(bvhRotation(m, b, ends[e].first).transpose() * bvhRotation(m, b, ends[e].second));
        worst = std::max(worst, std::abs(angleOf(pose.rotations.at(scanEnds[e]).toRotationMatrix()) - clip));
      }
    }
    std::printf("%s: ankle and wrist angles off the clip's by %.2g deg at most\n", file, worst);
    EXPECT_LT(worst, 1e-6) << file;
  }
}

// A clip in centimetres (the CMU clip rescaled) gives the same poses as the original once its units
// are inferred, and the same as the original read with --unit-mm 10.
TEST(Retarget, ClipInCentimetresGivesTheSamePoses) {
  const repose::BvhMotion cmu = repose::readBvhFile(kMocap + "cmu_short_75frames.bvh");
  repose::BvhMotion cm = cmu;
  repose::scaleBvhLengths(cm, 25.4 / 0.45 / 10);
  const repose::Skeleton s = standardSkeleton();
  const repose::BvhRetargeter a(cmu, s, repose::defaultCmuJointMap(cmu, s));
  const repose::BvhRetargeter b(cm, s, repose::defaultCmuJointMap(cm, s));
  EXPECT_EQ(b.units().name, "centimetres");
  repose::RetargetOptions cmuAsCm;
  cmuAsCm.unitScaleMm = 10;  // the old default read the cm clip at 56.44 mm per unit: 5.6 times too far
  const repose::BvhRetargeter wrong(cm, s, repose::defaultCmuJointMap(cm, s), [] {
    repose::RetargetOptions o;
    o.unitScaleMm = 25.4 / 0.45;
    return o;
  }());
  const repose::BvhRetargeter given(cm, s, repose::defaultCmuJointMap(cm, s), cmuAsCm);
  double worstAngle = 0, worstShift = 0;
  for (int f = 0; f < cmu.frameCount; ++f) {
    const repose::Pose pa = a.pose(f), pb = b.pose(f), pg = given.pose(f);
    for (const auto& [joint, q] : pa.rotations) worstAngle = std::max(worstAngle, q.angularDistance(pb.rotations.at(joint)));
    worstShift = std::max({worstShift, (pa.translation - pb.translation).norm(), (pg.translation - pb.translation).norm()});
  }
  const double travelled = a.pose(cmu.frameCount - 1).translation.norm();
  std::printf("cm clip: %.0f mm travelled, poses within %.2g rad and %.2g mm of the CMU clip's; read as CMU units: "
              "%.0f mm\n", travelled, worstAngle, worstShift, wrong.pose(cmu.frameCount - 1).translation.norm());
  EXPECT_LT(worstAngle, 1e-9);
  EXPECT_LT(worstShift, 1e-6);
  EXPECT_GT(travelled, 100);
  EXPECT_NEAR(wrong.pose(cmu.frameCount - 1).translation.norm() / travelled, 25.4 / 0.45 / 10, 1e-6);
}

// What a map leaves undriven, for animate's warning and --strict.
TEST(Retarget, CoverageListsUndrivenLimbJoints) {
  const repose::Skeleton s = standardSkeleton();
  // A hand-written map without elbows and knees.
  const repose::BvhJointMap partial = follow({{"Hips", "pelvis"}, {"LeftUpLeg", "left_hip"}, {"RightUpLeg", "right_hip"},
                                              {"LeftFoot", "left_ankle"}, {"RightFoot", "right_ankle"},
                                              {"LeftShoulder", "left_clavicle"}, {"LeftArm", "left_shoulder"},
                                              {"RightArm", "right_shoulder"}, {"LeftHand", "left_wrist"},
                                              {"RightHand", "right_wrist"}});
  const repose::JointMapCoverage c = repose::jointMapCoverage(s, partial);
  EXPECT_EQ(c.undrivenLimbs, (std::vector<std::string>{"left_elbow", "right_clavicle", "right_scapula", "right_elbow",
                                                        "left_knee", "right_knee"}));
  EXPECT_EQ(c.driven.size(), 10u);
  // A rig whose joints are not named by the vocabulary: nothing is a recognised limb joint, the
  // built-in map drives the pelvis alone, which the retargeter refuses.
  repose::Skeleton odd;
  odd.joints.push_back(makeJoint("pelvis", -1, 0, 25, 960));
  odd.joints.push_back(makeJoint("femur_left", 0, 100, 5, 920));
  odd.joints.push_back(makeJoint("tibia_left", 1, 90, 5, 490));
  const repose::BvhMotion m = repose::readBvhFile(kMocap + "cmu_short_75frames.bvh");
  const repose::BvhJointMap map = repose::defaultCmuJointMap(m, odd);
  EXPECT_TRUE(repose::jointMapCoverage(odd, map).undrivenLimbs.empty());
  EXPECT_EQ(repose::jointMapCoverage(odd, map).unknownNames, (std::vector<std::string>{"femur_left", "tibia_left"}));
  EXPECT_TRUE(repose::jointMapCoverage(odd, map).following.empty());
  EXPECT_THROW(repose::BvhRetargeter(m, odd, map), std::invalid_argument);
  // No standard name at all, or a clip with no CMU names: the built-in map refuses.
  odd.joints[0].name = "root";
  EXPECT_THROW(repose::defaultCmuJointMap(m, odd), std::invalid_argument);
  EXPECT_THROW(repose::defaultCmuJointMap(knownMotion(), repose::Skeleton()), std::invalid_argument);
  EXPECT_THROW(repose::jointMapCoverage(s, follow({{"Hips", "no_such_joint"}})), std::invalid_argument);
  // The patella rides with its femur in the standard vocabulary: a patella joint is a name no
  // built-in map knows.
  EXPECT_EQ(c.unknownNames, (std::vector<std::string>{"left_patella", "right_patella"}));
}

}  // namespace
