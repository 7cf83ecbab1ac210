#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "rigid_bone_overlay.h"

using namespace repose;

namespace {
LabelVolume boxVolume() {
  LabelVolume v;
  v.grid.dims = {30, 30, 30};
  v.grid.origin = {-14.5, -14.5, -14.5};
  v.grid.spacing = {1, 1, 1};
  v.data.assign(v.grid.voxelCount(), 1);  // soft tissue everywhere
  for (int k = 8; k < 22; ++k)
    for (int j = 12; j < 18; ++j)
      for (int i = 10; i < 20; ++i) v.at(i, j, k) = 7;  // the bone
  return v;
}
}  // namespace

TEST(RigidBoneOverlay, FitsTransformAndPlacesBoneExactly) {
  const LabelVolume rest = boxVolume();
  // Fixed nodes of bone 0: centres of some bone voxels; one free node.
  Points restNodes(5, 3);
  restNodes << rest.grid.indexToPhysical({10, 12, 8}).transpose(), rest.grid.indexToPhysical({19, 12, 8}).transpose(),
      rest.grid.indexToPhysical({10, 17, 21}).transpose(), rest.grid.indexToPhysical({19, 17, 15}).transpose(),
      Eigen::RowVector3d(0, 0, 0);
  const std::vector<int> fixedBone = {0, 0, 0, 0, -1};
  Eigen::Isometry3d G = Eigen::Isometry3d::Identity();
  G.linear() = Eigen::AngleAxisd(0.6, Eigen::Vector3d(1, 2, 0.5).normalized()).toRotationMatrix();
  G.translation() = Eigen::Vector3d(1.5, -2, 0.7);
  Points posedNodes = restNodes;
  for (int v = 0; v < 4; ++v) posedNodes.row(v) = (G * restNodes.row(v).transpose()).transpose();
  posedNodes.row(4) << 3, 3, 3;  // free nodes do not disturb the fit

  const auto bones = rigidBonesFromMesh(rest, restNodes, posedNodes, fixedBone);
  ASSERT_EQ(bones.size(), 1u);
  EXPECT_LT((bones[0].transform.matrix() - G.matrix()).norm(), 1e-9);
  ASSERT_EQ(bones[0].labels, std::vector<std::int32_t>{7});

  // A posed volume where the pull smeared the bone (shifted by one voxel): the overlay fixes it.
  LabelVolume posed = rest;
  for (int k = 0; k < 30; ++k)
    for (int j = 0; j < 30; ++j)
      for (int i = 0; i < 30; ++i) posed.at(i, j, k) = (i > 0 && rest.at(i - 1, j, k) == 7) ? 7 : 1;
  const std::size_t changed = overlayRigidBones(posed, rest, bones);
  EXPECT_GT(changed, 0u);
  int mismatches = 0, boneVoxels = 0;
  for (int k = 0; k < 30; ++k)
    for (int j = 0; j < 30; ++j)
      for (int i = 0; i < 30; ++i) {
        const Eigen::Vector3d r = rest.grid.physicalToIndex(G.inverse() * posed.grid.indexToPhysical({double(i), double(j), double(k)}));
        const int ri = int(std::lround(r.x())), rj = int(std::lround(r.y())), rk = int(std::lround(r.z()));
        const bool expected = rest.grid.contains(ri, rj, rk) && rest.at(ri, rj, rk) == 7;
        boneVoxels += expected;
        mismatches += expected != (posed.at(i, j, k) == 7);
      }
  EXPECT_GT(boneVoxels, 700);
  EXPECT_EQ(mismatches, 0);
}

TEST(RigidBoneOverlay, CollinearNodesAndBadInput) {
  const LabelVolume rest = boxVolume();
  Points line(3, 3);
  line << 0, 0, 0, 1, 0, 0, 2, 0, 0;
  EXPECT_TRUE(rigidBonesFromMesh(rest, line, line, {0, 0, 0}).empty());
  EXPECT_THROW(rigidBonesFromMesh(rest, line, line, {0, 0}), std::invalid_argument);
}

TEST(RigidBoneOverlay, BlockOfTheGridEqualsThatPartOfTheWholeOverlay) {
  const LabelVolume rest = boxVolume();
  RigidBone bone;
  bone.transform.linear() = Eigen::AngleAxisd(0.4, Eigen::Vector3d(0.3, 1, 0.2).normalized()).toRotationMatrix();
  bone.transform.translation() = Eigen::Vector3d(-1.2, 0.8, 2.1);
  bone.labels = {7};
  LabelVolume whole = rest;
  for (auto& v : whole.data) v = v == 7 ? 1 : v;  // bone smeared away by the pull
  LabelVolume block;
  const int e[6] = {5, 24, 9, 20, 3, 27};
  block.grid = whole.grid;
  for (int a = 0; a < 3; ++a) block.grid.dims[a] = e[2 * a + 1] - e[2 * a] + 1;
  block.grid.origin = whole.grid.indexToPhysical(Eigen::Vector3d(e[0], e[2], e[4]));
  for (int k = e[4]; k <= e[5]; ++k)
    for (int j = e[2]; j <= e[3]; ++j)
      for (int i = e[0]; i <= e[1]; ++i) block.data.push_back(whole.at(i, j, k));
  ASSERT_GT(overlayRigidBones(whole, rest, {bone}), 500u);
  overlayRigidBones(block.data.data(), block.grid, rest, {bone});
  int mismatches = 0;
  for (int k = e[4]; k <= e[5]; ++k)
    for (int j = e[2]; j <= e[3]; ++j)
      for (int i = e[0]; i <= e[1]; ++i) mismatches += block.at(i - e[0], j - e[2], k - e[4]) != whole.at(i, j, k);
  EXPECT_EQ(mismatches, 0);
}

TEST(RigidBoneOverlay, PrecomputedLabelBoxesGiveTheSameOverlay) {
  LabelVolume rest = boxVolume();
  for (int k = 2; k < 5; ++k)
    for (int j = 3; j < 9; ++j)
      for (int i = 20; i < 26; ++i) rest.at(i, j, k) = 9;  // a second bone label, away from the first
  const auto boxes = restLabelBoxes(rest);
  ASSERT_EQ(boxes.size(), 10u);
  EXPECT_TRUE(boxes[3].isEmpty());
  EXPECT_EQ(boxes[7].min(), Eigen::Vector3i(10, 12, 8));
  EXPECT_EQ(boxes[7].max(), Eigen::Vector3i(19, 17, 21));
  EXPECT_EQ(boxes[9].min(), Eigen::Vector3i(20, 3, 2));
  EXPECT_EQ(boxes[9].max(), Eigen::Vector3i(25, 8, 4));
  RigidBone bone;
  bone.transform.linear() = Eigen::AngleAxisd(0.4, Eigen::Vector3d(0.3, 1, 0.2).normalized()).toRotationMatrix();
  bone.transform.translation() = Eigen::Vector3d(-1.2, 0.8, 2.1);
  bone.labels = {7, 9};
  LabelVolume scanned = rest;
  for (auto& v : scanned.data) v = v == 7 || v == 9 ? 1 : v;
  LabelVolume cached = scanned;
  const std::size_t n = overlayRigidBones(scanned, rest, {bone});
  EXPECT_GT(n, 500u);
  EXPECT_EQ(overlayRigidBones(cached.data.data(), cached.grid, rest, {bone}, &boxes), n);
  EXPECT_EQ(cached.data, scanned.data);
  // Label values too large to index are not boxed; the overlay then scans.
  LabelVolume huge = rest;
  huge.data[0] = kMaxBoxedLabel + 1;
  EXPECT_TRUE(restLabelBoxes(huge).empty());
}

// Two bones driven into each other: the voxels both rigid motions claim are counted once, whichever
// label the pull left there, and bones apart claim none.
TEST(RigidBoneOverlay, CountsVoxelsTwoBonesClaim) {
  LabelVolume rest;
  rest.grid.dims = {24, 10, 10};
  rest.grid.spacing = {1, 1, 1};
  rest.data.assign(rest.grid.voxelCount(), 1);
  for (int k = 2; k < 6; ++k)
    for (int j = 2; j < 6; ++j) {
      for (int i = 2; i < 6; ++i) rest.at(i, j, k) = 7;    // bone A, x 2..5
      for (int i = 10; i < 14; ++i) rest.at(i, j, k) = 9;  // bone B, x 10..13
    }
  for (const auto& [shift, expected] : {std::pair<double, std::size_t>{-6, 2 * 4 * 4}, {-4, 0}, {-8, 4 * 4 * 4}}) {
    std::vector<RigidBone> bones(2);
    bones[0].labels = {7};
    bones[1].labels = {9};
    bones[1].transform.translation() = Eigen::Vector3d(shift, 0, 0);
    for (const bool pulledAsB : {false, true}) {
      // What the pull left: the rest labels, or bone B's label over the whole overlap (a smear).
      LabelVolume posed = rest;
      if (pulledAsB)
        for (std::size_t v = 0; v < posed.data.size(); ++v)
          if (posed.data[v] == 7) posed.data[v] = 9;
      std::size_t contested = 99;
      overlayRigidBones(posed.data.data(), posed.grid, rest, bones, nullptr, &contested);
      EXPECT_EQ(contested, expected) << "bone B moved by " << shift << " voxels, pulled as B: " << pulledAsB;
    }
  }
}
