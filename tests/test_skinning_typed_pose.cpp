// The skinning filter's typed pose (SetPose, for C++ callers that pose every frame) against its text
// pose (SetPoseJSON): the same posed points to the bit, the bone transforms it reports, and the two
// setters replacing each other.
#include <gtest/gtest.h>

#include <vtkExecutive.h>
#include <vtkFloatArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkUnsignedShortArray.h>
#include <vtkUnstructuredGrid.h>

#include <cstdlib>
#include <cstring>
#include <vector>

#include "array_names.h"
#include "pose.h"
#include "skeleton.h"
#include "vtkReposeSkinning.h"

namespace {

const char* kArm = R"({"joints": [
  {"name": "upperarm", "parent": null, "center": [0, 0, 0], "labels": [3]},
  {"name": "forearm", "parent": "upperarm", "center": [0, 0, 30], "labels": [5]}
]})";

// A bar of 2 x 2 x 7 nodes along z, weights blending the two bones over its middle.
vtkNew<vtkUnstructuredGrid> weightedBar() {
  vtkNew<vtkUnstructuredGrid> mesh;
  vtkNew<vtkPoints> points;
  vtkNew<vtkFloatArray> weights;
  vtkNew<vtkUnsignedShortArray> bones;
  weights->SetName(repose::arrays::kWeights);
  bones->SetName(repose::arrays::kBoneIds);
  weights->SetNumberOfComponents(2);
  bones->SetNumberOfComponents(2);
  for (int k = 0; k < 7; ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 2; ++i) {
        points->InsertNextPoint(10.0 * i + 0.1 * k, 10.0 * j, 10.0 * k);
        const float w = std::min(1.0f, std::max(0.0f, (k - 2) / 2.0f));
        weights->InsertNextTuple2(1 - w, w);
        bones->InsertNextTuple2(0, 1);
      }
  mesh->SetPoints(points);
  mesh->GetPointData()->AddArray(weights);
  mesh->GetPointData()->AddArray(bones);
  return mesh;
}

repose::Pose bentArm() {
  repose::Pose p;
  p.rotations["forearm"] = Eigen::Quaterniond(Eigen::AngleAxisd(1.1, Eigen::Vector3d(1, 0.3, 0).normalized()));
  p.rotations["upperarm"] = Eigen::Quaterniond(0.9, 0.1, -0.2, 0.05);  // not unit: made unit as the parser does
  p.translation = Eigen::Vector3d(3, -1.0 / 3.0, 7);
  return p;
}

std::vector<float> posedPoints(vtkReposeSkinning* skinning) {
  EXPECT_TRUE(skinning->GetExecutive()->Update()) << skinning->GetLastError();
  vtkPoints* p = skinning->GetOutput()->GetPoints();
  const float* data = vtkFloatArray::SafeDownCast(p->GetData())->GetPointer(0);
  return std::vector<float>(data, data + 3 * p->GetNumberOfPoints());
}

}  // namespace

TEST(SkinningTypedPose, PosesToTheBitsOfItsJson) {
  // The bent arm, then random rotations of any scale (made unit on the way, as the parser does).
  std::vector<repose::Pose> poses{bentArm()};
  std::srand(11);
  auto r = [] { return 2.0 * std::rand() / RAND_MAX - 1.0; };
  for (int i = 0; i < 40; ++i) {
    repose::Pose p;
    const double scale = i % 2 ? 1e-3 : 10.0;
    for (const char* joint : {"upperarm", "forearm"})
      p.rotations[joint] = Eigen::Quaterniond(scale * r(), scale * r(), scale * r(), scale * r());
    p.translation = Eigen::Vector3d(100 * r(), 100 * r(), 100 * r());
    poses.push_back(p);
  }
  for (int method : {vtkReposeSkinning::DualQuaternion, vtkReposeSkinning::LinearBlend}) {
    vtkNew<vtkUnstructuredGrid> mesh = weightedBar();
    vtkNew<vtkReposeSkinning> text, typed;
    for (vtkReposeSkinning* s : {text.Get(), typed.Get()}) {
      s->SetInputData(mesh);
      s->SetSkeletonJSON(kArm);
      s->SetSkinningMethod(method);
    }
    for (std::size_t i = 0; i < poses.size(); ++i) {
      text->SetPoseJSON(repose::poseToJson(poses[i]).c_str());
      typed->SetPose(poses[i]);
      const std::vector<float> a = posedPoints(text), b = posedPoints(typed);
      ASSERT_EQ(a.size(), b.size());
      EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(float)), 0) << "method " << method << " pose " << i;
    }
  }
}

TEST(SkinningTypedPose, ReportsTheBoneTransformsItSkinnedWith) {
  vtkNew<vtkUnstructuredGrid> mesh = weightedBar();
  vtkNew<vtkReposeSkinning> skinning;
  skinning->SetInputData(mesh);
  skinning->SetSkeletonJSON(kArm);
  EXPECT_EQ(skinning->GetNumberOfBoneTransforms(), 0);
  skinning->SetPose(bentArm());
  posedPoints(skinning);
  const std::vector<Eigen::Isometry3d> expected =
    repose::forwardKinematics(repose::parseSkeletonJson(kArm), repose::canonicalPose(bentArm()));
  ASSERT_EQ(skinning->GetNumberOfBoneTransforms(), 2);
  for (int j = 0; j < 2; ++j) {
    double m[16];
    ASSERT_TRUE(skinning->GetBoneTransform(j, m));
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) EXPECT_EQ(m[4 * r + c], expected[std::size_t(j)].matrix()(r, c));
  }
  double m[16];
  EXPECT_FALSE(skinning->GetBoneTransform(2, m));
  EXPECT_FALSE(skinning->GetBoneTransform(-1, m));
  // The transforms of the rest pose once the pose is cleared by text.
  skinning->SetPoseJSON(nullptr);
  posedPoints(skinning);
  ASSERT_TRUE(skinning->GetBoneTransform(1, m));
  EXPECT_EQ(m[3], 0.0);
  EXPECT_EQ(m[0], 1.0);
}

TEST(SkinningTypedPose, EachSetterReplacesTheOther) {
  vtkNew<vtkUnstructuredGrid> mesh = weightedBar();
  vtkNew<vtkReposeSkinning> skinning;
  skinning->SetInputData(mesh);
  skinning->SetSkeletonJSON(kArm);
  const std::vector<float> rest = posedPoints(skinning);

  skinning->SetPose(bentArm());
  const repose::Pose back = repose::parsePoseJson(skinning->GetPoseJSON());
  EXPECT_EQ(back.rotations.at("forearm").coeffs(), repose::canonicalPose(bentArm()).rotations.at("forearm").coeffs());
  const std::vector<float> bent = posedPoints(skinning);
  EXPECT_NE(bent, rest);

  // The same text as before the typed pose still counts as a change: the typed pose is dropped.
  skinning->SetPoseJSON(nullptr);
  EXPECT_EQ(skinning->GetPoseJSON(), nullptr);
  EXPECT_EQ(posedPoints(skinning), rest);

  skinning->SetPoseJSON(R"({"rotations": {"forearm": {"axis": [1, 0, 0], "degrees": 40}}})");
  const std::vector<float> text = posedPoints(skinning);
  skinning->SetPose(repose::Pose{});
  EXPECT_EQ(posedPoints(skinning), rest);
  EXPECT_NE(text, rest);
}

TEST(SkinningTypedPose, RefusesABadTypedPoseAndAnUnknownJoint) {
  vtkNew<vtkReposeSkinning> skinning;
  repose::Pose zero;
  zero.rotations["forearm"] = Eigen::Quaterniond(0, 0, 0, 0);
  EXPECT_THROW(skinning->SetPose(zero), std::invalid_argument);

  vtkNew<vtkUnstructuredGrid> mesh = weightedBar();
  skinning->SetInputData(mesh);
  skinning->SetSkeletonJSON(kArm);
  repose::Pose unknown;
  unknown.rotations["tail"] = Eigen::Quaterniond::Identity();
  skinning->SetPose(unknown);
  skinning->GlobalWarningDisplayOff();
  EXPECT_FALSE(skinning->GetExecutive()->Update());
  EXPECT_NE(std::string(skinning->GetLastError()).find("tail"), std::string::npos) << skinning->GetLastError();
}
