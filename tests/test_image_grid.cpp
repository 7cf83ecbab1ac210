#include <gtest/gtest.h>

#include "image_grid.h"

TEST(ImageGrid, IndexPhysicalRoundTrip) {
  repose::ImageGrid g;
  g.dims = {4, 5, 6};
  g.origin = {10, -20, 30};
  g.spacing = {0.5, 1.5, 3.0};
  g.direction << -1, 0, 0, 0, -1, 0, 0, 0, 1;
  const Eigen::Vector3d ijk(1.25, 3, 4.5);
  const Eigen::Vector3d x = g.indexToPhysical(ijk);
  EXPECT_NEAR(x.x(), 10 - 0.625, 1e-12);
  EXPECT_NEAR(x.y(), -20 - 4.5, 1e-12);
  EXPECT_NEAR(x.z(), 30 + 13.5, 1e-12);
  EXPECT_LT((g.physicalToIndex(x) - ijk).norm(), 1e-12);
  EXPECT_EQ(g.linearIndex(1, 2, 3), std::size_t(3 * 20 + 2 * 4 + 1));
}
