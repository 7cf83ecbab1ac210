#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "deformation_stats.h"

TEST(DeformationStats, VolumesRatiosAndInversions) {
  repose::Points rest(5, 3);
  rest << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1;
  repose::Tets tets(2, 4);
  tets << 0, 1, 2, 3, 1, 2, 3, 4;
  if (repose::tetVolume(rest.row(1), rest.row(2), rest.row(3), rest.row(4)) < 0) std::swap(tets(1, 2), tets(1, 3));
  // Rigid motion: nothing changes.
  Eigen::Matrix3d R = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 1, 0).normalized()).toRotationMatrix();
  repose::Points moved = (rest * R.transpose()).rowwise() + Eigen::RowVector3d(3, -2, 1);
  auto s = repose::deformationStats(rest, moved, tets, {5, 6});
  EXPECT_NEAR(s.volumeRatio, 1, 1e-12);
  EXPECT_NEAR(s.maxAbsDetFMinus1, 0, 1e-12);
  EXPECT_EQ(s.invertedTets, 0u);
  EXPECT_NEAR(s.maxStretch, 1, 1e-9);
  EXPECT_EQ(s.tets, 2u);
  EXPECT_EQ(s.stretchedVolumeMm3, 0);
  // Stretch x by 2: every tet doubles; then push node 0 through its face: the first tet inverts.
  repose::Points stretched = rest;
  stretched.col(0) *= 2;
  s = repose::deformationStats(rest, stretched, tets, {5, 6});
  EXPECT_NEAR(s.volumeRatio, 2, 1e-12);
  EXPECT_NEAR(s.labelVolumeRatio.at(5), 2, 1e-12);
  EXPECT_NEAR(s.meanAbsDetFMinus1, 1, 1e-12);
  EXPECT_NEAR(s.maxStretch, 2, 1e-9);
  EXPECT_EQ(s.stretchedVolumeMm3, 0);
  // Pulled 5 times along a diagonal and rotated: a web; both tets' rest volume counts (1/6 + 1/3 mm^3).
  const Eigen::Vector3d u = Eigen::Vector3d(1, 2, -1).normalized();
  const Eigen::Matrix3d pull = R * (Eigen::Matrix3d::Identity() + 4 * u * u.transpose());
  s = repose::deformationStats(rest, rest * pull.transpose(), tets, {});
  EXPECT_NEAR(s.maxStretch, 5, 1e-9);
  EXPECT_NEAR(s.stretchedVolumeMm3, 0.5, 1e-12);
  repose::Points flipped = rest;
  flipped.row(0) << 0.5, 0.5, 0.5;
  s = repose::deformationStats(rest, flipped, tets, {});
  EXPECT_EQ(s.invertedTets, 1u);
  EXPECT_TRUE(s.labelVolumeRatio.empty());
  EXPECT_THROW(repose::deformationStats(rest, flipped.topRows(4), tets, {}), std::invalid_argument);
  EXPECT_THROW(repose::deformationStats(rest, flipped, tets, {1}), std::invalid_argument);
}
