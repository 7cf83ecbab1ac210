// Exact Euclidean distance transform with anisotropic spacing.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "distance_transform.h"
#include "volume_test_grids.h"

using namespace repose;
using namespace repose::testing;

TEST(DistanceTransform, MatchesBruteForceWithAnisotropicSpacing) {
  const ImageGrid g = makeGrid(13, 9, 7, {0.7, 1.3, 2.1});
  MaskVolume f = filled<std::uint8_t>(g, 0);
  std::mt19937 rng(3);
  for (int s = 0; s < 6; ++s) f.data[rng() % f.data.size()] = 1;
  const std::vector<float> d = distanceToFeatures(f);
  for (int k = 0; k < g.dims[2]; ++k)
    for (int j = 0; j < g.dims[1]; ++j)
      for (int i = 0; i < g.dims[0]; ++i) {
        double best = std::numeric_limits<double>::infinity();
        for (int c = 0; c < g.dims[2]; ++c)
          for (int b = 0; b < g.dims[1]; ++b)
            for (int a = 0; a < g.dims[0]; ++a)
              if (f.at(a, b, c)) best = std::min(best, (centre(g, i, j, k) - centre(g, a, b, c)).norm());
        EXPECT_NEAR(d[g.linearIndex(i, j, k)], best, 1e-4) << i << " " << j << " " << k;
      }
}

TEST(DistanceTransform, NoFeatureIsInfinite) {
  const MaskVolume f = filled<std::uint8_t>(makeGrid(4, 3, 2), 0);
  for (float x : distanceToFeatures(f)) EXPECT_TRUE(std::isinf(x));
}
