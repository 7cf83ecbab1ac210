// skeleton.json / pose.json parsing, validation and forward kinematics.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <fstream>
#include <stdexcept>
#include <string>

#include "pose.h"
#include "skeleton.h"

namespace {

// Children listed before their parents on purpose: parsing must sort parents first.
const char* kArm = R"({"joints": [
  {"name": "hand", "parent": "forearm", "center": [0, 0, 60], "labels": [7]},
  {"name": "forearm", "parent": "upperarm", "center": [0, 0, 30], "labels": [5, 6]},
  {"name": "upperarm", "parent": null, "center": [0, 0, 0], "labels": [3]}
]})";

// Expects parse to throw std::invalid_argument whose message contains every given fragment.
template <typename F>
void expectError(F&& parse, std::initializer_list<const char*> fragments) {
  try {
    parse();
    ADD_FAILURE() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    for (const char* f : fragments)
      EXPECT_NE(std::string(e.what()).find(f), std::string::npos)
          << "message '" << e.what() << "' lacks '" << f << "'";
  }
}

void expectSkeletonError(const std::string& json, std::initializer_list<const char*> fragments) {
  expectError([&] { repose::parseSkeletonJson(json); }, fragments);
}
void expectPoseError(const std::string& json, std::initializer_list<const char*> fragments) {
  expectError([&] { repose::parsePoseJson(json); }, fragments);
}

bool near(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b, double tol = 1e-12) {
  return (a.matrix() - b.matrix()).cwiseAbs().maxCoeff() < tol;
}

Eigen::Isometry3d rotationAbout(const Eigen::Vector3d& c, const Eigen::Quaterniond& q) {
  return Eigen::Translation3d(c) * q * Eigen::Translation3d(-c);
}

}  // namespace

TEST(Skeleton, ParsesAndSortsParentsFirst) {
  const repose::Skeleton s = repose::parseSkeletonJson(kArm);
  ASSERT_EQ(s.size(), 3u);
  EXPECT_EQ(s.joints[0].name, "upperarm");
  EXPECT_EQ(s.joints[0].parent, -1);
  for (std::size_t j = 1; j < s.size(); ++j) EXPECT_LT(s.joints[j].parent, int(j));
  const int forearm = s.find("forearm"), hand = s.find("hand");
  ASSERT_GE(forearm, 0);
  ASSERT_GE(hand, 0);
  EXPECT_EQ(s.joints[hand].parent, forearm);
  EXPECT_EQ(s.joints[forearm].center, Eigen::Vector3d(0, 0, 30));
  EXPECT_EQ(s.joints[forearm].labels, (std::vector<int>{5, 6}));
  EXPECT_EQ(s.find("nope"), -1);

  const std::vector<int> bone = repose::boneOfLabel(s, 8);
  ASSERT_EQ(bone.size(), 9u);
  EXPECT_EQ(bone[3], 0);
  EXPECT_EQ(bone[5], forearm);
  EXPECT_EQ(bone[6], forearm);
  EXPECT_EQ(bone[7], hand);
  EXPECT_EQ(bone[0], -1);
  EXPECT_EQ(bone[8], -1);
}

TEST(Skeleton, JsonRoundTrip) {
  repose::Skeleton s = repose::parseSkeletonJson(kArm);
  s.joints[1].center = Eigen::Vector3d(0.1, -2.0 / 3.0, 1e-7);
  const repose::Skeleton t = repose::parseSkeletonJson(repose::skeletonToJson(s));
  ASSERT_EQ(t.size(), s.size());
  for (std::size_t j = 0; j < s.size(); ++j) {
    EXPECT_EQ(t.joints[j].name, s.joints[j].name);
    EXPECT_EQ(t.joints[j].parent, s.joints[j].parent);
    EXPECT_EQ(t.joints[j].center, s.joints[j].center);  // exact with 17 digits
    EXPECT_EQ(t.joints[j].labels, s.joints[j].labels);
  }
}

TEST(Skeleton, ErrorsNameTheProblem) {
  expectSkeletonError(R"({"joints": [ {"name": "a", )", {"malformed JSON"});
  expectSkeletonError(R"({"bones": []})", {"joints"});
  expectSkeletonError(R"({"joints": [{"parent": null, "center": [0,0,0]}]})", {"name"});
  expectSkeletonError(R"({"joints": [{"name": "pelvis", "parent": null, "center": [0,0]}]})",
                      {"pelvis", "center"});
  expectSkeletonError(R"({"joints": [{"name": "pelvis", "parent": null, "center": [0,"x",0]}]})",
                      {"pelvis", "center"});
  expectSkeletonError(R"({"joints": [{"name": "pelvis", "parent": null, "center": [0,NaN,0]}]})",
                      {"pelvis", "center", "finite"});
  expectSkeletonError(R"({"joints": [{"name": "pelvis", "parent": null, "center": [0,0,0],
                          "labels": [1, 2.5]}]})",
                      {"pelvis", "labels"});
  expectSkeletonError(R"({"joints": [{"name": "pelvis", "parent": null, "center": [0,0,0],
                          "labels": ["1"]}]})",
                      {"pelvis", "labels"});
  expectSkeletonError(R"({"joints": [{"name": "a", "parent": null, "center": [0,0,0]},
                                     {"name": "a", "parent": "a", "center": [0,0,0]}]})",
                      {"duplicate", "'a'"});
  expectSkeletonError(R"({"joints": [{"name": "a", "parent": null, "center": [0,0,0]},
                                     {"name": "x", "parent": "y", "center": [0,0,0]}]})",
                      {"joint 'x' names unknown parent 'y'"});
  expectSkeletonError(R"({"joints": [{"name": "root", "parent": null, "center": [0,0,0]},
                                     {"name": "b", "parent": "c", "center": [0,0,0]},
                                     {"name": "c", "parent": "b", "center": [0,0,0]}]})",
                      {"cycle", "'b'"});
  expectSkeletonError(R"({"joints": [{"name": "b", "parent": "b", "center": [0,0,0]}]})",
                      {"cycle", "'b'"});
  expectSkeletonError(R"({"joints": [{"name": "l", "parent": null, "center": [0,0,0]},
                                     {"name": "r", "parent": null, "center": [0,0,0]}]})",
                      {"several root", "'l'", "'r'"});
  expectSkeletonError(R"({"joints": [{"name": "a", "parent": null, "center": [0,0,0], "labels": [4]},
                                     {"name": "b", "parent": "a", "center": [0,0,0], "labels": [2, 4]}]})",
                      {"label 4", "'a'", "'b'"});
  expectSkeletonError(R"({"joints": [{"name": "pelvis", "parent": null, "center": [0,0,0], "labels": [0]}]})",
                      {"pelvis", "label 0", "background"});
  expectSkeletonError(R"({"joints": [{"name": "pelvis", "parent": null, "center": [0,0,0], "labels": [3, -2]}]})",
                      {"pelvis", "label -2"});
}

TEST(Skeleton, ReadFileErrorsNameTheFile) {
  expectError([] { repose::readSkeletonFile("/nonexistent/dir/skeleton.json"); },
              {"/nonexistent/dir/skeleton.json", "cannot read"});
  const std::string path = ::testing::TempDir() + "bad_skeleton.json";
  {
    std::ofstream out(path);
    out << R"({"joints": [{"name": "x", "parent": "y", "center": [0,0,0]}]})";
  }
  expectError([&] { repose::readSkeletonFile(path); }, {path.c_str(), "unknown parent 'y'"});
  {
    std::ofstream out(path);
    out << kArm;
  }
  EXPECT_EQ(repose::readSkeletonFile(path).size(), 3u);
  std::remove(path.c_str());
}

TEST(Pose, ParsesAxisAngleAndQuaternion) {
  const repose::Pose p = repose::parsePoseJson(R"({
    "rotations": {"forearm": {"axis": [0, 0, 2], "degrees": 90},
                  "hand": {"quaternion": [2, 0, 0, 0]}},
    "translation": [1, 2, 3]})");
  ASSERT_EQ(p.rotations.size(), 2u);
  const Eigen::Quaterniond expected(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()));
  EXPECT_NEAR(std::abs(p.rotations.at("forearm").dot(expected)), 1.0, 1e-15);
  EXPECT_NEAR(p.rotations.at("hand").w(), 1.0, 1e-15);  // normalised
  EXPECT_EQ(p.translation, Eigen::Vector3d(1, 2, 3));

  const repose::Pose empty = repose::parsePoseJson("{}");
  EXPECT_TRUE(empty.rotations.empty());
  EXPECT_EQ(empty.translation, Eigen::Vector3d::Zero());
}

// Found by fuzzing: components near 1e300 overflowed the norm and gave a zero rotation axis.
TEST(Pose, HugeAxisAndQuaternionComponentsStillGiveUnitRotations) {
  const repose::Pose p = repose::parsePoseJson(R"({
    "rotations": {"knee": {"axis": [5e297, 0, 1], "degrees": -90},
                  "hip": {"quaternion": [1e300, 1e300, 0, 0]}}})");
  const Eigen::Quaterniond knee(Eigen::AngleAxisd(-M_PI / 2, Eigen::Vector3d::UnitX()));
  EXPECT_NEAR(p.rotations.at("knee").norm(), 1.0, 1e-15);
  EXPECT_NEAR(std::abs(p.rotations.at("knee").dot(knee)), 1.0, 1e-15);
  EXPECT_NEAR(p.rotations.at("hip").w(), std::sqrt(0.5), 1e-15);
  EXPECT_NEAR(p.rotations.at("hip").x(), std::sqrt(0.5), 1e-15);
}

TEST(Pose, JsonRoundTrip) {
  repose::Pose p;
  p.rotations["forearm"] = Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()));
  p.translation = Eigen::Vector3d(0.1, -5, 1.0 / 3.0);
  const repose::Pose q = repose::parsePoseJson(repose::poseToJson(p));
  ASSERT_EQ(q.rotations.size(), 1u);
  EXPECT_NEAR(q.rotations.at("forearm").dot(p.rotations.at("forearm")), 1.0, 1e-15);
  EXPECT_EQ(q.translation, p.translation);
}

// The typed route (canonicalPose) must pose to the bits the text route does: every rotation as
// parsePoseJson(poseToJson(p)) reads it back, non-unit and huge quaternions included.
TEST(Pose, CanonicalPoseEqualsItsJsonReadBackBitForBit) {
  std::srand(7);
  auto r = [] { return 2.0 * std::rand() / RAND_MAX - 1.0; };
  for (int trial = 0; trial < 200; ++trial) {
    repose::Pose p;
    const double scale = trial % 3 == 0 ? 1.0 : trial % 3 == 1 ? 1e-6 : 1e200;
    for (const char* joint : {"upperarm", "forearm", "hand"})
      p.rotations[joint] = Eigen::Quaterniond(scale * r(), scale * r(), scale * r(), scale * r());
    p.translation = Eigen::Vector3d(1e3 * r(), r(), 1e-3 * r());
    const repose::Pose typed = repose::canonicalPose(p);
    const repose::Pose text = repose::parsePoseJson(repose::poseToJson(p));
    ASSERT_EQ(typed.rotations.size(), text.rotations.size());
    for (const auto& [joint, q] : text.rotations)
      EXPECT_EQ(typed.rotations.at(joint).coeffs(), q.coeffs()) << joint << " in trial " << trial;
    EXPECT_EQ(typed.translation, text.translation);
    EXPECT_NEAR(typed.rotations.at("hand").norm(), 1.0, 1e-15);
  }
}

TEST(Pose, CanonicalPoseRefusesWhatTheParserRefuses) {
  repose::Pose zero;
  zero.rotations["hand"] = Eigen::Quaterniond(0, 0, 0, 0);
  expectError([&] { repose::canonicalPose(zero); }, {"hand", "zero"});
  repose::Pose nan;
  nan.rotations["hand"] = Eigen::Quaterniond(std::nan(""), 0, 0, 1);
  expectError([&] { repose::canonicalPose(nan); }, {"hand", "non-finite"});
  repose::Pose far;
  far.translation.x() = INFINITY;
  expectError([&] { repose::canonicalPose(far); }, {"translation", "non-finite"});
}

TEST(Pose, ErrorsNameTheProblem) {
  expectPoseError(R"({"rotations": {)", {"malformed JSON"});
  // Deep nesting is a parse error on one line, not a stack overflow or a message without a file.
  expectPoseError(std::string(100000, '['), {"pose.json", "malformed JSON", "nested too deeply"});
  expectSkeletonError(std::string(100000, '{'), {"skeleton.json", "malformed JSON"});
  for (const std::string& broken : {std::string("{\"rotations\": {\n\n"), std::string("[1,\n2,,]")}) {
    try {
      repose::parsePoseJson(broken);
      ADD_FAILURE() << "accepted " << broken;
    } catch (const std::invalid_argument& e) {
      EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
    }
  }
  expectPoseError(R"({"rotations": {"knee": {"axis": [0, 0, 0], "degrees": 10}}})", {"knee", "axis", "zero"});
  expectPoseError(R"({"rotations": {"knee": {"axis": [1e-20, 0, 0], "degrees": 10}}})", {"knee", "zero"});
  expectPoseError(R"({"rotations": {"knee": {"quaternion": [0, 0, 0, 0]}}})", {"knee", "quaternion", "zero"});
  expectPoseError(R"({"rotations": {"knee": {"quaternion": [1, 0, 0]}}})", {"knee", "quaternion"});
  expectPoseError(R"({"rotations": {"knee": {"axis": [1, 0, 0]}}})", {"knee", "degrees"});
  expectPoseError(R"({"rotations": {"knee": {"angle": 3}}})", {"knee", "axis", "quaternion"});
  expectPoseError(R"({"rotations": {"knee": {"axis": [1, 0, 0], "degrees": "ten"}}})", {"knee", "degrees"});
  // NaN/Infinity literals (as Python's json module writes them) parse, then are rejected.
  expectPoseError(R"({"rotations": {"knee": {"axis": [1, 0, 0], "degrees": NaN}}})", {"knee", "finite"});
  expectPoseError(R"({"rotations": {"knee": {"axis": [Infinity, 0, 0], "degrees": 3}}})", {"knee", "finite"});
  expectPoseError(R"({"rotations": {"knee": {"quaternion": [1, 0, -Infinity, 0]}}})", {"knee", "finite"});
  expectPoseError(R"({"translation": [0, NaN, 0]})", {"translation", "finite"});
  expectPoseError(R"({"translation": [0, 1]})", {"translation"});
  expectPoseError(R"({"rotations": [1, 2]})", {"rotations"});
}

TEST(Pose, ValidateNamesUnknownJoint) {
  const repose::Skeleton s = repose::parseSkeletonJson(kArm);
  const repose::Pose p = repose::parsePoseJson(R"({"rotations": {"elbow": {"axis": [1,0,0], "degrees": 5}}})");
  expectError([&] { repose::validatePose(p, s); }, {"'elbow'", "forearm"});
  expectError([&] { repose::forwardKinematics(s, p); }, {"'elbow'"});
  repose::Pose bad;
  bad.rotations["hand"] = Eigen::Quaterniond(NAN, 0, 0, 0);
  expectError([&] { repose::validatePose(bad, s); }, {"'hand'"});
  repose::Pose far;
  far.translation = Eigen::Vector3d(0, 1e300, 0);  // finite, but posed nodes would not be
  expectError([&] { repose::validatePose(far, s); }, {"translation", "1e+300", "millimetres"});
  far.translation = Eigen::Vector3d(0, -0.99e6, 5);  // within a kilometre
  repose::validatePose(far, s);
  expectError([] { repose::readPoseFile("/nonexistent/pose.json"); }, {"/nonexistent/pose.json", "cannot read"});
}

TEST(ForwardKinematics, RestPoseIsIdentity) {
  const repose::Skeleton s = repose::parseSkeletonJson(kArm);
  for (const auto& G : repose::forwardKinematics(s, repose::Pose{}))
    EXPECT_TRUE(near(G, Eigen::Isometry3d::Identity()));
}

TEST(ForwardKinematics, NinetyDegreesMovesKnownPoint) {
  const repose::Skeleton s = repose::parseSkeletonJson(kArm);
  const repose::Pose p =
      repose::parsePoseJson(R"({"rotations": {"forearm": {"axis": [1, 0, 0], "degrees": 90}}})");
  const auto G = repose::forwardKinematics(s, p);
  // About x through (0,0,30): (0,0,40) -> (0,-10,30); the hand's centre (0,0,60) -> (0,-30,30).
  EXPECT_LT((G[s.find("forearm")] * Eigen::Vector3d(0, 0, 40) - Eigen::Vector3d(0, -10, 30)).norm(), 1e-12);
  EXPECT_LT((G[s.find("hand")] * Eigen::Vector3d(0, 0, 60) - Eigen::Vector3d(0, -30, 30)).norm(), 1e-12);
  // The centre of rotation stays put and the parent does not move.
  EXPECT_LT((G[s.find("forearm")] * Eigen::Vector3d(0, 0, 30) - Eigen::Vector3d(0, 0, 30)).norm(), 1e-12);
  EXPECT_TRUE(near(G[s.find("upperarm")], Eigen::Isometry3d::Identity()));
}

TEST(ForwardKinematics, ChildComposesWithRotatedParentAndRootTranslation) {
  const repose::Skeleton s = repose::parseSkeletonJson(kArm);
  const Eigen::Quaterniond qu(Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 1, 0).normalized()));
  const Eigen::Quaterniond qf(Eigen::AngleAxisd(-1.1, Eigen::Vector3d::UnitY()));
  const Eigen::Quaterniond qh(Eigen::AngleAxisd(0.3, Eigen::Vector3d(0, 1, 2).normalized()));
  repose::Pose p;
  p.rotations["upperarm"] = qu;
  p.rotations["forearm"] = qf;
  p.rotations["hand"] = qh;
  p.translation = Eigen::Vector3d(5, -7, 11);
  const auto G = repose::forwardKinematics(s, p);
  const int u = s.find("upperarm"), f = s.find("forearm"), h = s.find("hand");
  const Eigen::Isometry3d Gu = Eigen::Translation3d(p.translation) * rotationAbout(s.joints[u].center, qu);
  const Eigen::Isometry3d Gf = Gu * rotationAbout(s.joints[f].center, qf);
  const Eigen::Isometry3d Gh = Gf * rotationAbout(s.joints[h].center, qh);
  EXPECT_TRUE(near(G[u], Gu));
  EXPECT_TRUE(near(G[f], Gf));
  EXPECT_TRUE(near(G[h], Gh));

  // A translation alone moves every bone by it.
  repose::Pose t;
  t.translation = Eigen::Vector3d(1, 2, 3);
  for (const auto& Gj : repose::forwardKinematics(s, t))
    EXPECT_TRUE(near(Gj, Eigen::Isometry3d(Eigen::Translation3d(1, 2, 3))));
}

// A joint name that is not text would not survive being written into a case (found by fuzz_skeleton_json).
TEST(Skeleton, JointNamesMustBeText) {
  auto skeleton = [](const std::string& name) {
    return R"({"joints": [{"name": ")" + name + R"(", "parent": null, "center": [0, 0, 0], "labels": [1]}]})";
  };
  EXPECT_EQ(repose::parseSkeletonJson(skeleton("pelvis")).joints[0].name, "pelvis");
  EXPECT_EQ(repose::parseSkeletonJson(skeleton("h\xc3\xbc" "fte \xe8\x85\xb0")).joints[0].name, "h\xc3\xbc" "fte \xe8\x85\xb0");
  for (const std::string bad : {std::string("l\x84\x92r_spine"), std::string("\xc3"), std::string("\xc0\xaf"),
                                std::string("\xed\xa0\x80"), std::string("a\tb")}) {
    try {
      repose::parseSkeletonJson(skeleton(bad));
      ADD_FAILURE() << "accepted a joint named " << bad;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("name is not text"), std::string::npos) << e.what();
    }
  }
}
