// Retargeting BVH motion onto a skeleton with a different rest pose.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>

#include "bvh.h"
#include "pose.h"
#include "retarget.h"
#include "skeleton.h"

namespace {

const std::string kMocap = std::string(REPOSE_SHARED_DATA) + "/mocap/";
constexpr double kDeg = M_PI / 180;

// A T-pose BVH in CMU MotionBuilder names: legs straight down, arms horizontal. The "Spine" joint
// between LowerBack and Head is left out of the default map on purpose. Columns (rotations in the
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
const Bone kBones[] = {
    {"left_hip", "left_knee", "LeftUpLeg", "LeftLeg"},       {"left_knee", "left_ankle", "LeftLeg", "LeftFoot"},
    {"right_hip", "right_knee", "RightUpLeg", "RightLeg"},   {"right_knee", "right_ankle", "RightLeg", "RightFoot"},
    {"spine", "neck", "LowerBack", "Head"},                   {"left_shoulder", "left_elbow", "LeftArm", "LeftForeArm"},
    {"left_elbow", "left_wrist", "LeftForeArm", "LeftHand"}, {"right_shoulder", "right_elbow", "RightArm", "RightForeArm"},
    {"right_elbow", "right_wrist", "RightForeArm", "RightHand"},
};

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
  EXPECT_EQ(walk.size(), 15u);
  EXPECT_EQ(walk.at("LeftShoulder"), "left_shoulder");  // 3dsMax: LeftShoulder rotates the upper arm
  EXPECT_EQ(walk.at("LeftHip"), "left_hip");
  EXPECT_EQ(walk.at("lowerback"), "spine");
  EXPECT_EQ(walk.at("RightWrist"), "right_wrist");
  const repose::BvhJointMap mb = repose::defaultCmuJointMap(repose::readBvhFile(kMocap + "cmu_short_75frames.bvh"), s);
  EXPECT_EQ(mb.size(), 15u);
  EXPECT_EQ(mb.at("LeftArm"), "left_shoulder");  // MotionBuilder: LeftShoulder is the collar
  EXPECT_EQ(mb.count("LeftShoulder"), 0u);
  EXPECT_EQ(mb.at("LeftUpLeg"), "left_hip");
  EXPECT_EQ(mb.at("LowerBack"), "spine");
  EXPECT_EQ(mb.at("Head"), "neck");
}

TEST(Retarget, DirectionModeReproducesBvhBoneDirections) {
  const repose::BvhMotion m = knownMotion();
  const repose::Skeleton s = scanSkeleton();
  const repose::BvhRetargeter retarget(m, s, repose::defaultCmuJointMap(m, s));
  EXPECT_EQ(retarget.mainChild()[s.find("spine")], s.find("neck"));
  for (int f = 0; f < m.frameCount; ++f) {
    const repose::Pose pose = retarget.pose(f);
    const auto g = repose::forwardKinematics(s, pose);
    const auto b = repose::bvhGlobalPose(m, f);
    for (const Bone& bone : kBones)
      EXPECT_LT((scanBone(s, g, bone.scanA, bone.scanB) - bvhBone(m, b, bone.bvhA, bone.bvhB)).norm(), 1e-6)
          << "frame " << f << " bone " << bone.scanA << "->" << bone.scanB;
    // The pelvis's left-right axis (between the hip centres) follows the BVH's.
    const int pelvis = s.find("pelvis");
    const Eigen::Vector3d lateral =
        (g[pelvis].linear() * (s.joints[s.find("left_hip")].center - s.joints[s.find("right_hip")].center)).normalized();
    EXPECT_LT((lateral - bvhBone(m, b, "RightUpLeg", "LeftUpLeg")).norm(), 1e-6) << "frame " << f;
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
  // Leaf (ankle): keeps the knee's rotation composed with the BVH ankle's 20 degrees.
  const repose::Pose p1 = retarget.pose(1);
  EXPECT_NEAR(Eigen::AngleAxisd(p1.rotations.at("left_ankle")).angle(), 20 * kDeg, 1e-9);
  EXPECT_NEAR(Eigen::AngleAxisd(p1.rotations.at("right_ankle")).angle(), 0, 1e-9);
  // Root translation: CMU units to mm, BVH (1,2,3) -> LPS (1,-3,2), relative to frame 0.
  EXPECT_LT((p1.translation - 56.44 * Eigen::Vector3d(1, -3, 2)).norm(), 1e-9);
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
  // Reference = rest frame 0: every mapped scan bone turns by the BVH joint's global rotation.
  repose::RetargetOptions options;
  options.mode = repose::RetargetMode::Relative;
  const repose::BvhRetargeter retarget(m, s, map, options);
  for (int f = 1; f < m.frameCount; ++f) {
    const auto g = repose::forwardKinematics(s, retarget.pose(f));
    const auto b = repose::bvhGlobalPose(m, f);
    for (const Bone& bone : kBones) {
      const int ia = s.find(bone.scanA);
      const Eigen::Matrix3d expected = repose::bvhToLps() * b[m.find(bone.bvhA)].linear() * repose::bvhToLps().transpose();
      EXPECT_LT((g[ia].linear() - expected).norm(), 1e-9) << "frame " << f << " " << bone.scanA;
    }
  }
}

TEST(Retarget, RejectsBadMapsAndOptions) {
  const repose::BvhMotion m = knownMotion();
  const repose::Skeleton s = scanSkeleton();
  EXPECT_THROW(repose::BvhRetargeter(m, s, {{"NoSuchJoint", "left_hip"}}), std::invalid_argument);
  EXPECT_THROW(repose::BvhRetargeter(m, s, {{"LeftUpLeg", "no_such_joint"}}), std::invalid_argument);
  EXPECT_THROW(repose::BvhRetargeter(m, s, {{"LeftUpLeg", "left_hip"}, {"LeftLeg", "left_hip"}}), std::invalid_argument);
  EXPECT_THROW(repose::BvhRetargeter(m, s, {}), std::invalid_argument);
  repose::RetargetOptions bad;
  bad.referenceFrame = m.frameCount;
  EXPECT_THROW(repose::BvhRetargeter(m, s, {{"LeftUpLeg", "left_hip"}}, bad), std::invalid_argument);
  EXPECT_THROW(repose::BvhRetargeter(m, s, {{"LeftUpLeg", "left_hip"}}).pose(-1), std::invalid_argument);
  EXPECT_THROW(repose::parseRetargetMode("sideways"), std::invalid_argument);
  const repose::BvhJointMap map = repose::parseJointMapJson(R"({"map": {"LeftUpLeg": "left_hip", "Hips": "pelvis"}})");
  EXPECT_EQ(map.size(), 2u);
  EXPECT_EQ(map.at("Hips"), "pelvis");
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

}  // namespace
