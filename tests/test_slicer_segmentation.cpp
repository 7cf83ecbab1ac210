// Slicer segmentation header fields: the per-segment keys of a single-layer label map.
#include "slicer_segmentation.h"

#include <gtest/gtest.h>

#include <map>
#include <stdexcept>
#include <vector>

namespace {

std::map<std::string, std::string> asMap(const std::vector<std::pair<std::string, std::string>>& fields) {
  return {fields.begin(), fields.end()};
}

}  // namespace

TEST(SlicerSegmentation, FieldsNameColourAndPlaceEachSegmentInOneLayer) {
  const auto fields = asMap(repose::slicerSegmentationFields(
      {{3, "femur left", {1.0, 0.5, 0.25}}, {9, "liver", {0, 0, 1}}}, {4, 3, 2}));
  EXPECT_EQ(fields.at("Segmentation_MasterRepresentation"), "Binary labelmap");
  EXPECT_EQ(fields.at("Segmentation_ContainedRepresentationNames"), "Binary labelmap|");
  EXPECT_EQ(fields.at("Segmentation_ReferenceImageExtentOffset"), "0 0 0");
  EXPECT_EQ(fields.at("Segment0_ID"), "Segment_3");
  EXPECT_EQ(fields.at("Segment0_Name"), "femur left");
  EXPECT_EQ(fields.at("Segment0_Color"), "1 0.5 0.25");
  EXPECT_EQ(fields.at("Segment0_LabelValue"), "3");
  EXPECT_EQ(fields.at("Segment0_Layer"), "0");
  EXPECT_EQ(fields.at("Segment1_Name"), "liver");
  EXPECT_EQ(fields.at("Segment1_Layer"), "0");
  // The shared label map is cropped to the first segment's extent: every segment spans the grid.
  EXPECT_EQ(fields.at("Segment0_Extent"), "0 3 0 2 0 1");
  EXPECT_EQ(fields.at("Segment1_Extent"), "0 3 0 2 0 1");
  EXPECT_EQ(fields.count("Segment2_ID"), 0u);
  EXPECT_EQ(fields.size(), 3u + 2u * 8u);
}

TEST(SlicerSegmentation, RefusesBackgroundRepeatedValuesAndEmptyGrids) {
  EXPECT_THROW(repose::slicerSegmentationFields({{0, "background", {0, 0, 0}}}, {1, 1, 1}), std::invalid_argument);
  EXPECT_THROW(repose::slicerSegmentationFields({{4, "a", {0, 0, 0}}, {4, "b", {0, 0, 0}}}, {1, 1, 1}),
               std::invalid_argument);
  EXPECT_THROW(repose::slicerSegmentationFields({{4, "a", {0, 0, 0}}}, {3, 0, 2}), std::invalid_argument);
}
