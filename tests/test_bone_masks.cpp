// forEachBoneMask (core/bone_masks.h): each bone label of a skeleton once, in ascending order, with its
// crop, and null for a label without voxels; labels too large to box are cropped on the whole grid.
#include <gtest/gtest.h>

#include <vector>

#include "bone_masks.h"
#include "label_boxes.h"

using namespace repose;

namespace {
LabelVolume boneGrid(int bigLabel) {
  LabelVolume v;
  v.grid.dims = {6, 5, 4};
  v.data.assign(v.grid.voxelCount(), 0);
  v.at(1, 1, 1) = 4;
  v.at(2, 1, 1) = 4;
  v.at(4, 3, 2) = bigLabel;
  return v;
}

Skeleton skeletonOf(std::vector<std::vector<int>> labels) {
  Skeleton s;
  for (auto& l : labels) s.joints.push_back(Joint{"j", -1, Eigen::Vector3d::Zero(), l});
  return s;
}

struct Visit {
  int label;
  bool present;
  std::array<int, 3> dims;
  int ones;
};

std::vector<Visit> visits(const LabelVolume& v, const Skeleton& s) {
  std::vector<Visit> out;
  forEachBoneMask(v, s, [&](int label, const MaskVolume* mask) {
    Visit visit{label, mask != nullptr, {0, 0, 0}, 0};
    if (mask) {
      visit.dims = mask->grid.dims;
      for (auto x : mask->data) visit.ones += x;
    }
    out.push_back(visit);
  });
  return out;
}
}  // namespace

TEST(BoneMasks, EachBoneLabelOnceOnItsCrop) {
  const LabelVolume v = boneGrid(9);
  const auto seen = visits(v, skeletonOf({{9, 4}, {4, 11}, {}}));
  ASSERT_EQ(seen.size(), 3u);
  EXPECT_EQ(seen[0].label, 4);
  EXPECT_TRUE(seen[0].present);
  EXPECT_EQ(seen[0].dims, (std::array<int, 3>{2, 1, 1}));
  EXPECT_EQ(seen[0].ones, 2);
  EXPECT_EQ(seen[1].label, 9);
  EXPECT_EQ(seen[1].dims, (std::array<int, 3>{1, 1, 1}));
  EXPECT_EQ(seen[2].label, 11);
  EXPECT_FALSE(seen[2].present);  // beyond the largest label: no box, no voxels
}

TEST(BoneMasks, LabelsTooLargeToBoxUseTheWholeGrid) {
  const int big = kMaxBoxedLabel + 5;
  const LabelVolume v = boneGrid(big);
  const auto seen = visits(v, skeletonOf({{big, 4, 7}}));
  ASSERT_EQ(seen.size(), 3u);
  EXPECT_EQ(seen[0].label, 4);
  EXPECT_EQ(seen[0].dims, v.grid.dims);
  EXPECT_EQ(seen[0].ones, 2);
  EXPECT_EQ(seen[1].label, 7);
  EXPECT_FALSE(seen[1].present);
  EXPECT_EQ(seen[2].label, big);
  EXPECT_EQ(seen[2].ones, 1);
}
