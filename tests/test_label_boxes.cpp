// labelBoxes and labelCrop (core/label_boxes.h): each label's index box, the crop of one label on its
// box (grid, origin and 0/1 values), the same boxes on any thread count's chunks, and labels too large
// to box.
#include <gtest/gtest.h>

#include "label_boxes.h"

using namespace repose;

namespace {
LabelVolume twoLabels() {
  LabelVolume v;
  v.grid.dims = {9, 7, 5};
  v.grid.origin = {10, -4, 2};
  v.grid.spacing = {1.5, 1, 2};
  v.grid.direction << 0, -1, 0, 1, 0, 0, 0, 0, 1;  // rotated: the crop's origin follows the direction
  v.data.assign(v.grid.voxelCount(), 0);
  for (int k = 1; k <= 3; ++k)
    for (int j = 2; j <= 4; ++j)
      for (int i = 3; i <= 7; ++i) v.at(i, j, k) = (i + j + k) % 2 ? 7 : 3;  // a checkerboard of 3 and 7
  v.at(0, 0, 4) = 7;
  return v;
}
}  // namespace

TEST(LabelBoxes, EachLabelsBoxAndItsCrop) {
  const LabelVolume v = twoLabels();
  const auto boxes = labelBoxes(v);
  ASSERT_EQ(boxes.size(), 8u);
  EXPECT_TRUE(boxes[1].isEmpty());
  EXPECT_EQ(boxes[3].min(), Eigen::Vector3i(3, 2, 1));
  EXPECT_EQ(boxes[3].max(), Eigen::Vector3i(7, 4, 3));
  EXPECT_EQ(boxes[7].min(), Eigen::Vector3i(0, 0, 1));
  EXPECT_EQ(boxes[7].max(), Eigen::Vector3i(7, 4, 4));

  const MaskVolume crop = labelCrop(v, 3, boxes[3]);
  ASSERT_EQ(crop.grid.dims, (std::array<int, 3>{5, 3, 3}));
  EXPECT_TRUE(crop.grid.origin.isApprox(v.grid.indexToPhysical(Eigen::Vector3d(3, 2, 1))));
  EXPECT_EQ(crop.grid.direction, v.grid.direction);
  for (int k = 0; k < 3; ++k)
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 5; ++i) EXPECT_EQ(crop.at(i, j, k), v.at(i + 3, j + 2, k + 1) == 3 ? 1 : 0);
  EXPECT_EQ(labelCrop(v, 1, boxes[1]).data.size(), 0u);  // an absent label: an empty crop
}

TEST(LabelBoxes, LabelsTooLargeToBoxAndBadInput) {
  LabelVolume v = twoLabels();
  v.at(8, 6, 0) = kMaxBoxedLabel + 1;
  EXPECT_TRUE(labelBoxes(v).empty());
  v.data.pop_back();
  EXPECT_THROW(labelBoxes(v), std::invalid_argument);
}
