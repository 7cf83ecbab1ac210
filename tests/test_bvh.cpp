// BVH reader: both CMU conversions, malformed variants (errors name the line), forward kinematics.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "bvh.h"

namespace {

const std::string kMocap = std::string(REPOSE_SHARED_DATA) + "/mocap/";

// Expects parseBvh to throw std::invalid_argument whose message contains every fragment.
void expectBvhError(const std::string& text, std::initializer_list<std::string> fragments) {
  try {
    repose::parseBvh(text, "test.bvh");
    ADD_FAILURE() << "expected std::invalid_argument for:\n" << text;
  } catch (const std::invalid_argument& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("test.bvh"), std::string::npos) << message;
    for (const std::string& f : fragments)
      EXPECT_NE(message.find(f), std::string::npos) << "message '" << message << "' lacks '" << f << "'";
  }
}

// A two-joint file; line numbers in the comments are what the error tests rely on.
std::string smallBvh(const std::string& rootChannels = "CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation",
                     const std::string& frames = "Frames: 2",
                     const std::string& row0 = "1 2 3 10 20 30 40 50 60",
                     const std::string& row1 = "4 5 6 0 0 0 0 0 90", const std::string& closing = "}") {
  return "HIERARCHY\n"                             // 1
         "ROOT Hips\n"                             // 2
         "{\n"                                     // 3
         "  OFFSET 0 0 0\n"                        // 4
         "  " + rootChannels + "\n"                // 5
         "  JOINT Knee\n"                          // 6
         "  {\n"                                   // 7
         "    OFFSET 0 -10 0\n"                    // 8
         "    CHANNELS 3 Xrotation Yrotation Zrotation\n"  // 9
         "    End Site\n"                          // 10
         "    {\n"                                 // 11
         "      OFFSET 0 -5 0\n"                   // 12
         "    }\n"                                 // 13
         "  }\n"                                   // 14
         + closing + "\n"                          // 15
         "MOTION\n"                                // 16
         + frames + "\n"                           // 17
         "Frame Time: 0.04\n"                      // 18
         + row0 + "\n"                             // 19
         + row1 + "\n";                            // 20
}

TEST(Bvh, ParsesSmallFile) {
  const repose::BvhMotion m = repose::parseBvh(smallBvh(), "test.bvh");
  ASSERT_EQ(m.joints.size(), 2u);
  EXPECT_EQ(m.joints[0].name, "Hips");
  EXPECT_EQ(m.joints[1].name, "Knee");
  EXPECT_EQ(m.joints[1].parent, 0);
  EXPECT_EQ(m.joints[1].firstChannel, 6);
  EXPECT_TRUE(m.joints[1].hasEndSite);
  EXPECT_DOUBLE_EQ(m.joints[1].endSite.y(), -5);
  EXPECT_EQ(m.frameCount, 2);
  EXPECT_EQ(m.channelCount(), 9);
  EXPECT_DOUBLE_EQ(m.framesPerSecond(), 25);
  EXPECT_DOUBLE_EQ(m.frames(1, 8), 90);
  ASSERT_EQ(m.joints[0].channels.size(), 6u);
  EXPECT_EQ(m.joints[0].channels[4], repose::BvhChannel::Xrotation);
}

TEST(Bvh, RejectsMalformedFilesWithLineNumbers) {
  // Frame count that does not match the rows (too few rows, too many rows).
  expectBvhError(smallBvh("CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation", "Frames: 3"),
                 {"line 20", "Frames: 3", "line 17", "only 2 frame row(s)"});
  expectBvhError(smallBvh("CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation", "Frames: 1"),
                 {"line 20", "more frame rows"});
  expectBvhError(smallBvh("CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation", "Frames: 99999999"),
                 {"line 20", "only 2 frame row(s)"});  // and no huge allocation
  expectBvhError(smallBvh("CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation", "Frames: two"),
                 {"line 17", "bad frame count"});
  // Missing MOTION section.
  {
    std::string text = smallBvh();
    text = text.substr(0, text.find("MOTION"));
    expectBvhError(text, {"missing MOTION", "line 16"});
    std::string renamed = smallBvh();
    renamed.replace(renamed.find("MOTION"), 6, "MOTON");
    expectBvhError(renamed, {"missing MOTION", "line 16", "MOTON"});
  }
  // Bad number in a frame row and in an OFFSET.
  expectBvhError(smallBvh("CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation", "Frames: 2",
                          "1 2 3 10 2x0 30 40 50 60"),
                 {"line 19", "bad number", "2x0"});
  {
    std::string text = smallBvh();
    text.replace(text.find("OFFSET 0 -10 0"), 14, "OFFSET 0 -1O 0");
    expectBvhError(text, {"line 8", "bad number", "-1O"});
  }
  // A value of 1e308 is finite but scaled to millimetres it overflows: refused where it stands.
  expectBvhError(smallBvh("CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation", "Frames: 2",
                          "1e308 2 3 10 20 30 40 50 60"),
                 {"line 19", "bad number", "1e308", "1e9"});
  // Short and long rows: the channels do not add up.
  expectBvhError(smallBvh("CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation", "Frames: 2",
                          "1 2 3 10 20 30 40 50 60", "4 5 6 0 0 0 0 0"),
                 {"line 20", "8 values", "9 channels"});
  expectBvhError(smallBvh("CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation", "Frames: 2",
                          "1 2 3 10 20 30 40 50 60 70"),
                 {"line 19", "10 values", "9 channels"});
  // Unknown channel name; a CHANNELS count larger than the names given.
  expectBvhError(smallBvh("CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Wrotation"),
                 {"line 5", "unknown channel", "Wrotation"});
  expectBvhError(smallBvh("CHANNELS 7 Xposition Yposition Zposition Zrotation Xrotation Yrotation Xrotation"),
                 {"line 5", "0 to 6"});
  // Unbalanced braces: a missing '}' and an extra '}'.
  expectBvhError(smallBvh("CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation", "Frames: 2",
                          "1 2 3 10 20 30 40 50 60", "4 5 6 0 0 0 0 0 90", ""),
                 {"line 16", "unbalanced braces", "line 3", "Hips"});
  expectBvhError(smallBvh("CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation", "Frames: 2",
                          "1 2 3 10 20 30 40 50 60", "4 5 6 0 0 0 0 0 90", "}\n}"),
                 {"line 16", "unbalanced braces"});
  // Missing HIERARCHY / ROOT.
  {
    std::string text = smallBvh();
    expectBvhError("\n" + text.substr(text.find("ROOT")), {"line 2", "missing HIERARCHY"});
    text.replace(text.find("ROOT"), 4, "JOINT");
    expectBvhError(text, {"line 2", "missing ROOT"});
  }
  expectBvhError("", {"line 1", "missing HIERARCHY"});
}

TEST(Bvh, ForwardKinematicsComposesChannelsInFileOrder) {
  // Root channels Z X Y: R = Rz(10) Rx(20) Ry(30); knee X Y Z: Rx(40) Ry(50) Rz(60).
  const repose::BvhMotion m = repose::parseBvh(smallBvh(), "test.bvh");
  const auto pose = repose::bvhGlobalPose(m, 0);
  const double d = M_PI / 180;
  using AA = Eigen::AngleAxisd;
  const Eigen::Matrix3d rRoot = (AA(10 * d, Eigen::Vector3d::UnitZ()) * AA(20 * d, Eigen::Vector3d::UnitX()) *
                                 AA(30 * d, Eigen::Vector3d::UnitY()))
                                    .toRotationMatrix();
  const Eigen::Matrix3d rKnee = (AA(40 * d, Eigen::Vector3d::UnitX()) * AA(50 * d, Eigen::Vector3d::UnitY()) *
                                 AA(60 * d, Eigen::Vector3d::UnitZ()))
                                    .toRotationMatrix();
  EXPECT_LT((pose[0].translation() - Eigen::Vector3d(1, 2, 3)).norm(), 1e-12);
  EXPECT_LT((pose[0].linear() - rRoot).norm(), 1e-12);
  EXPECT_LT((pose[1].translation() - (Eigen::Vector3d(1, 2, 3) + rRoot * Eigen::Vector3d(0, -10, 0))).norm(), 1e-12);
  EXPECT_LT((pose[1].linear() - rRoot * rKnee).norm(), 1e-12);
  // Rest pose: offsets only.
  const auto rest = repose::bvhRestPose(m);
  EXPECT_LT((rest[1].translation() - Eigen::Vector3d(0, -10, 0)).norm(), 1e-15);
  EXPECT_TRUE(rest[1].linear().isIdentity(1e-15));
  EXPECT_THROW(repose::bvhGlobalPose(m, 2), std::invalid_argument);
}

void expectCmuFile(const repose::BvhMotion& m, int frames, const char* hipName, const char* kneeName) {
  EXPECT_EQ(m.joints.size(), 31u);
  EXPECT_EQ(m.frameCount, frames);
  EXPECT_EQ(m.frames.rows(), frames);
  EXPECT_NEAR(m.framesPerSecond(), 120.0, 0.01);
  // Channels add up: 6 for the root, 3 for every other joint, contiguous in file order.
  int expected = 0;
  for (const repose::BvhJoint& j : m.joints) {
    EXPECT_EQ(j.firstChannel, expected) << j.name;
    EXPECT_EQ(j.channels.size(), j.parent < 0 ? 6u : 3u) << j.name;
    expected += int(j.channels.size());
  }
  EXPECT_EQ(m.channelCount(), expected);
  EXPECT_EQ(m.channelCount(), 96);
  EXPECT_EQ(m.joints[0].name, "Hips");
  const int hip = m.find(hipName), knee = m.find(kneeName);
  ASSERT_GE(hip, 0);
  ASSERT_GE(knee, 0);
  EXPECT_EQ(m.joints[knee].parent, hip);
  for (std::size_t j = 1; j < m.joints.size(); ++j) EXPECT_LT(m.joints[j].parent, int(j));
}

TEST(Bvh, ReadsCmuWalk3dsMaxConversion) {
  const auto start = std::chrono::steady_clock::now();
  const repose::BvhMotion m = repose::readBvhFile(kMocap + "cmu_131_01_walk.bvh");
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("cmu_131_01_walk.bvh (%d frames x %d channels) parsed in %.1f ms\n", m.frameCount,
              m.channelCount(), seconds * 1e3);
  EXPECT_LT(seconds, 1.0);
  expectCmuFile(m, 994, "LeftHip", "LeftKnee");
  // First row starts "5.2300 16.9002 -33.8986 -5.4029 9.8098 10.4956"; the arms use Z X Y order.
  EXPECT_DOUBLE_EQ(m.frames(0, 0), 5.2300);
  EXPECT_DOUBLE_EQ(m.frames(0, 1), 16.9002);
  EXPECT_DOUBLE_EQ(m.frames(0, 2), -33.8986);
  EXPECT_DOUBLE_EQ(m.frames(0, 3), -5.4029);
  EXPECT_DOUBLE_EQ(m.frames(1, 0), 5.2229);
  const repose::BvhJoint& shoulder = m.joints[m.find("LeftShoulder")];
  ASSERT_EQ(shoulder.channels.size(), 3u);
  EXPECT_EQ(shoulder.channels[1], repose::BvhChannel::Xrotation);
  EXPECT_EQ(shoulder.channels[2], repose::BvhChannel::Yrotation);
  const repose::BvhJoint& leftHip = m.joints[m.find("LeftHip")];
  EXPECT_DOUBLE_EQ(leftHip.offset.x(), 1.24777);
  EXPECT_TRUE(m.joints[m.find("Head")].hasEndSite);
  const auto pose = repose::bvhGlobalPose(m, 0);
  EXPECT_LT((pose[0].translation() - Eigen::Vector3d(5.2300, 16.9002, -33.8986)).norm(), 1e-12);
}

TEST(Bvh, ReadsCmuShortMotionBuilderConversion) {
  const repose::BvhMotion m = repose::readBvhFile(kMocap + "cmu_short_75frames.bvh");
  expectCmuFile(m, 75, "LeftUpLeg", "LeftLeg");
  EXPECT_GE(m.find("LeftArm"), 0);
  EXPECT_GE(m.find("LeftForeArm"), 0);
  EXPECT_DOUBLE_EQ(m.joints[m.find("LeftUpLeg")].offset.x(), 3.13874);
  // First row starts "34.0924 14.783 2.9468"; the last row ends "4.5838 -42.6201 0.2698".
  const auto pose = repose::bvhGlobalPose(m, 0);
  EXPECT_LT((pose[0].translation() - Eigen::Vector3d(34.0924, 14.783, 2.9468)).norm(), 1e-12);
  EXPECT_DOUBLE_EQ(m.frames(74, 95), 0.2698);
  EXPECT_DOUBLE_EQ(m.frames(74, 94), -42.6201);
}

TEST(Bvh, MissingFileNamesThePath) {
  try {
    repose::readBvhFile(kMocap + "no_such_file.bvh");
    ADD_FAILURE();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("no_such_file.bvh"), std::string::npos);
  }
}

// Units from the proportions: both CMU conversions, the same clips in other units, a clip with no
// knee (rest pose height), and a clip without length.
TEST(Bvh, InfersUnitsFromLegLength) {
  const double cmu = 25.4 / 0.45;
  for (const char* file : {"cmu_131_01_walk.bvh", "cmu_short_75frames.bvh"}) {
    const repose::BvhMotion m = repose::readBvhFile(kMocap + file);
    const repose::BvhUnits u = repose::inferBvhUnits(m);
    std::printf("%s: %s, leg length %.2f units = %.0f mm\n", file, u.name.c_str(), u.measuredUnits,
                u.measuredUnits * u.mmPerUnit);
    EXPECT_EQ(u.measure, "leg length") << file;
    EXPECT_DOUBLE_EQ(u.mmPerUnit, cmu) << file;
    EXPECT_GT(u.measuredUnits * u.mmPerUnit, 700) << file;  // hip to ankle of an adult
    EXPECT_LT(u.measuredUnits * u.mmPerUnit, 900) << file;
    // The same clip in other units: each is recognised, and the leg keeps its length in mm.
    const struct {
      double mmPerUnit;
      const char* name;
    } others[] = {{10, "centimetres"}, {1000, "metres"}, {25.4, "inches"}, {1, "millimetres"}, {304.8, "feet"}};
    for (const auto& other : others) {
      repose::BvhMotion scaled = m;
      repose::scaleBvhLengths(scaled, cmu / other.mmPerUnit);
      const repose::BvhUnits v = repose::inferBvhUnits(scaled);
      EXPECT_EQ(v.name, other.name) << file;
      EXPECT_DOUBLE_EQ(v.mmPerUnit, other.mmPerUnit) << file;
      EXPECT_NEAR(v.measuredUnits * v.mmPerUnit, u.measuredUnits * u.mmPerUnit, 1e-9 * cmu * u.measuredUnits) << file;
      // Root positions scale with the offsets.
      EXPECT_NEAR(scaled.frames(3, 1) * v.mmPerUnit, m.frames(3, 1) * cmu, 1e-9) << file;
    }
  }
  // No joint named like a knee: the rest pose's height (178 units of centimetres).
  const std::string noKnee = R"(HIERARCHY
ROOT Hips
{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  JOINT Chest
  {
    OFFSET 0 45 0
    CHANNELS 3 Zrotation Xrotation Yrotation
    JOINT Head
    {
      OFFSET 0 25 0
      CHANNELS 3 Zrotation Xrotation Yrotation
      End Site
      {
        OFFSET 0 15 0
      }
    }
  }
  JOINT LThigh
  {
    OFFSET 9 -5 0
    CHANNELS 3 Zrotation Xrotation Yrotation
    JOINT LFoot
    {
      OFFSET 0 -80 0
      CHANNELS 3 Zrotation Xrotation Yrotation
      End Site
      {
        OFFSET 0 -8 12
      }
    }
  }
}
MOTION
Frames: 1
Frame Time: 0.01
0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0
)";
  const repose::BvhUnits h = repose::inferBvhUnits(repose::parseBvh(noKnee, "noknee.bvh"));
  EXPECT_EQ(h.measure, "rest pose height");
  EXPECT_DOUBLE_EQ(h.measuredUnits, 178);
  EXPECT_EQ(h.name, "centimetres");
  // The knee of smallBvh() is found by its name: 10 + 5 units of leg, CMU-sized.
  const repose::BvhUnits k = repose::inferBvhUnits(repose::parseBvh(smallBvh(), "test.bvh"));
  EXPECT_EQ(k.measure, "leg length");
  EXPECT_DOUBLE_EQ(k.measuredUnits, 15);
  // A skeleton without length has no unit.
  repose::BvhMotion flat = repose::parseBvh(smallBvh(), "test.bvh");
  flat.joints[1].offset.setZero();
  flat.joints[1].endSite.setZero();
  EXPECT_THROW(repose::inferBvhUnits(flat), std::invalid_argument);
  EXPECT_THROW(repose::scaleBvhLengths(flat, 0), std::invalid_argument);
}

}  // namespace
