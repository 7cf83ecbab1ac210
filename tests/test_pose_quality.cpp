// The quality report of a pose: its summary and the warnings a user acts on.
#include <gtest/gtest.h>

#include "pose_quality.h"

using namespace repose;

namespace {

bool mentions(const std::vector<std::string>& lines, const std::string& word) {
  for (const auto& l : lines)
    if (l.find(word) != std::string::npos) return true;
  return false;
}

}  // namespace

TEST(PoseQuality, AGoodPoseHasNoWarnings) {
  DeformationStats s;
  s.volumeRatio = 1.004;
  s.tets = 316882;
  s.invertedTets = 182;  // 0.06 %: in the creases
  s.maxStretch = 2.1;
  s.stretchedVolumeMm3 = 3000;  // 3 ml: a joint's own deformation
  s.labelVolumeRatio = {{0, 1.5}, {5, 0.97}, {24, 1.01}};
  LabelTable table;
  table.labels.push_back({5, "muscle", LabelKind::Soft});
  const PoseQuality q = poseQuality(s, table);
  EXPECT_TRUE(q.warnings.empty());
  EXPECT_NE(q.summary.find("body volume 1.0040 of rest, 182 inverted tets, largest stretch 2.1x, 3.0 ml"), std::string::npos)
      << q.summary;
  // The worst label is named (label 0, outside every label, is not one).
  EXPECT_NE(q.summary.find("muscle (label 5) at 0.970"), std::string::npos) << q.summary;
}

TEST(PoseQuality, EachProblemIsWarnedWithWhatToTry) {
  DeformationStats s;
  s.volumeRatio = 1.074;
  s.tets = 3000000;
  s.invertedTets = 47000;
  s.maxStretch = 450;
  s.stretchedVolumeMm3 = 1939e3;
  s.labelVolumeRatio = {{7, 0.6}};
  const PoseQuality q = poseQuality(s, LabelTable());
  ASSERT_EQ(q.warnings.size(), 4u);
  EXPECT_TRUE(mentions(q.warnings, "47000 tets turned inside out"));
  EXPECT_TRUE(mentions(q.warnings, "1939 ml of tissue stretched past 3x (largest 450x)"));
  EXPECT_TRUE(mentions(q.warnings, "--contact-separation on"));
  EXPECT_TRUE(mentions(q.warnings, "the body's volume is 1.074 of rest"));
  EXPECT_TRUE(mentions(q.warnings, "label 7 has 0.600 of its rest volume"));
  // Limits of one's own.
  PoseQualityLimits lax;
  lax.bodyVolumeTolerance = 0.1, lax.labelVolumeTolerance = 0.5, lax.webMl = 5000;
  s.invertedTets = 0;
  EXPECT_TRUE(poseQuality(s, LabelTable(), lax).warnings.empty());
}

TEST(PoseQuality, BonesDrivenIntoEachOtherAreWarned) {
  DeformationStats s;
  s.tets = 100000;
  // Without a posed label volume nothing is said of bone voxels.
  EXPECT_EQ(poseQuality(s, LabelTable()).summary.find("claimed by two bones"), std::string::npos);
  // A few voxels where thin cartilage rounds away: in the summary, no warning.
  PosedLabelStats few{400, 1.0};
  PoseQuality q = poseQuality(s, LabelTable(), {}, few);
  EXPECT_NE(q.summary.find("400 voxels claimed by two bones (0.4 ml)"), std::string::npos) << q.summary;
  EXPECT_TRUE(q.warnings.empty());
  // A tibia cutting 36.6 k voxels out of the femur.
  PosedLabelStats many{36600, 1.0};
  q = poseQuality(s, LabelTable(), {}, many);
  ASSERT_EQ(q.warnings.size(), 1u);
  EXPECT_TRUE(mentions(q.warnings, "two bones overlap in 36600 voxels (36.6 ml)")) << q.warnings[0];
}
