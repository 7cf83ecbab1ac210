// When the fold-free continuation's path has stalled.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstddef>
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

// The Visible Human's 90 degree hip flexion (female, 323 k tets), as recorded: s after steps 71 to 91,
// where the pace rule found the path stalled (pace 1.5e-3: 450 steps in all), and after each of the
// 21 steps that followed the tissue's first relaxation there (to 0.4784: pace 1.2e-3). That relaxation
// did not pay, so the path is given up at step 112; before, two more relaxations took it to 0.4803
// and 0.4824 and it was given up at step 154 (175 s of the FEM's 243 s, not kept). A relaxation after
// which the path speeds up (steps growing again) has paid, and so the path goes on.
TEST(ContinuationStall, ARelaxationThatDidNotSpeedThePathUpIsTheLast) {
  using repose::continuationPace;
  using repose::continuationPaceStalls;
  using repose::continuationRelaxationPaid;
  const std::vector<double> beforeStall = {
      0.4223632812, 0.4243164062, 0.4262695312, 0.4301757812, 0.4379882812, 0.4399414062, 0.4400024414,
      0.4400634766, 0.4401855469, 0.4404296875, 0.4409179688, 0.4418945312, 0.4438476562, 0.4477539062,
      0.4497070312, 0.4516601562, 0.4519042969, 0.4520263672, 0.4521484375, 0.4523925781, 0.4528808594};
  const std::vector<double> afterFirst = {
      0.4538808594, 0.4558808594, 0.4598808594, 0.4678808594, 0.4683808594, 0.4688808594, 0.4698808594,
      0.4718808594, 0.4758808594, 0.4763808594, 0.4766308594, 0.4768808594, 0.4768886719, 0.4768964844,
      0.4769121094, 0.4769433594, 0.4770058594, 0.4771308594, 0.4773808594, 0.4778808594, 0.4783808594};
  const std::vector<double> afterSecond = {
      0.4785058594, 0.4785371094, 0.4785449219, 0.4785527344, 0.4785683594, 0.4785996094, 0.4786621094,
      0.4787871094, 0.4790371094, 0.4795371094, 0.4796621094, 0.4797871094, 0.4798183594, 0.4798339844,
      0.4798417969, 0.4798496094, 0.4798652344, 0.4798964844, 0.4799589844, 0.4800839844, 0.4803339844};
  // The last 21 of the 91 steps: the pace rule fires at step 91 (and the window is all it reads).
  EXPECT_TRUE(continuationPaceStalls(beforeStall, 91, 200));
  const double paceAtFirst = continuationPace(beforeStall, 0.0);
  EXPECT_NEAR(paceAtFirst, (0.4528808594 - 0.4223632812) / 20, 1e-15);
  // 21 steps after the first relaxation the pace rule fires again; the relaxation did not pay.
  EXPECT_TRUE(continuationPaceStalls(afterFirst, 112, 200));
  EXPECT_FALSE(continuationRelaxationPaid(afterFirst, 0.4528808594, paceAtFirst));
  // Nor would the second have (where the earlier rule went on).
  const double paceAtSecond = continuationPace(afterFirst, 0.4528808594);
  EXPECT_FALSE(continuationRelaxationPaid(afterSecond, 0.4783808594, paceAtSecond));
  // A path that speeds up after its relaxation (steps doubling from 2e-3) has paid, from its first
  // steps on; no step yet is no pace.
  std::vector<double> quicker;
  for (double at = 0.4528808594, d = 2e-3; quicker.size() < 21; d *= 2) quicker.push_back(at = std::min(1.0, at + d));
  for (std::size_t k = 1; k <= quicker.size(); ++k)
    EXPECT_TRUE(continuationRelaxationPaid(std::vector<double>(quicker.begin(), quicker.begin() + std::ptrdiff_t(k)),
                                           0.4528808594, paceAtFirst))
        << "after step " << k;
  EXPECT_FALSE(continuationRelaxationPaid({}, 0.4528808594, paceAtFirst));
  // Fewer steps than the window: the pace since where the path started or was last relaxed.
  EXPECT_DOUBLE_EQ(continuationPace({0.1, 0.3}, 0.0), 0.15);
  EXPECT_DOUBLE_EQ(continuationPace({0.5, 0.7}, 0.4, 20), 0.15);
  EXPECT_DOUBLE_EQ(continuationPace({0.5, 0.7, 0.8}, 0.4, 2), 0.15);
  EXPECT_EQ(continuationPace({}, 0.4), 0.0);
}

}  // namespace
