// When the fold-free continuation's path has stalled.
#include <gtest/gtest.h>

#include <vector>

#include "continuation_stall.h"

namespace {

// The continuation's stall test judges the pace of the last 20 steps against twice the step budget
// (200 steps: 400), not the step length: a path that slows down and squeezes through goes on.
TEST(ContinuationStall, PaceAgainstTwiceTheBudget) {
  using repose::continuationPaceStalls;
  auto path = [](std::vector<double> steps) {  // s after each step
    std::vector<double> s;
    double at = 0.0;
    for (double d : steps) s.push_back(at = std::min(1.0, at + d));
    return s;
  };
  // 20 steps of 1e-3 after 0.5 in 10 steps: 480 steps still to go at that pace, 510 in all.
  std::vector<double> steps(10, 0.05);
  steps.insert(steps.end(), 20, 1e-3);
  EXPECT_TRUE(continuationPaceStalls(path(steps), 30, 200));
  EXPECT_FALSE(continuationPaceStalls(path(steps), 30, 300));  // 510 against 600
  // Fewer than 21 steps known: no pace yet, however short the steps.
  EXPECT_FALSE(continuationPaceStalls(path(std::vector<double>(20, 1e-7)), 20, 200));
  EXPECT_TRUE(continuationPaceStalls(path(std::vector<double>(21, 1e-7)), 21, 200));
  // The walk's slowest path: short steps (6e-5 of the path), then the pace picks up; at no point
  // does it project more than 400 steps.
  std::vector<double> walk(8, 0.06);
  walk.insert(walk.end(), 12, 6e-5);
  walk.insert(walk.end(), 40, 0.0135);
  const std::vector<double> walkPath = path(walk);
  for (std::size_t k = 1; k <= walkPath.size(); ++k)
    EXPECT_FALSE(continuationPaceStalls(std::vector<double>(walkPath.begin(), walkPath.begin() + std::ptrdiff_t(k)),
                                        int(k), 200))
        << "after step " << k;
  // Just inside and just beyond twice the budget: a pace of 1e-3 with 0.35 to go after 20 steps
  // needs 371 steps in all; with 0.45 to go, 471.
  EXPECT_FALSE(continuationPaceStalls(path({0.63, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3,
                                             1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3}),
                                      21, 200));
  EXPECT_TRUE(continuationPaceStalls(path({0.53, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3,
                                            1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3}),
                                     21, 200));
  // A path at its end, or one that does not move: done, and stalled.
  EXPECT_FALSE(continuationPaceStalls(path(std::vector<double>(30, 0.05)), 30, 200));
  std::vector<double> still(25, 0.0);
  still[0] = 0.4;
  EXPECT_TRUE(continuationPaceStalls(path(still), 25, 200));
}

}  // namespace
