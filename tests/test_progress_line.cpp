// The progress line of long runs: durations as a person reads them, the time left from the pace so far.
#include <cmath>
#include <gtest/gtest.h>

#include "progress_line.h"

using namespace repose;

TEST(ProgressLine, DurationsReadAsAPersonSaysThem) {
  EXPECT_EQ(durationText(0), "0 s");
  EXPECT_EQ(durationText(41.4), "41 s");
  EXPECT_EQ(durationText(59.6), "1 min 0 s");
  EXPECT_EQ(durationText(113), "1 min 53 s");
  EXPECT_EQ(durationText(7530), "2 h 05 min");
  EXPECT_EQ(durationText(-3), "0 s");
}

TEST(ProgressLine, TimeLeftFromThePaceSoFar) {
  // 20 frames in 41 s: 2.05 s each, 55 left = 112.75 s.
  EXPECT_EQ(progressLine(20, 75, 41, "frames"), "20 of 75 frames (26 %), 41 s so far, about 1 min 53 s left");
  // Nothing to extrapolate from before the first item; nothing left after the last.
  EXPECT_EQ(progressLine(0, 75, 3, "frames"), "0 of 75 frames (0 %), 3 s so far");
  EXPECT_EQ(progressLine(75, 75, 150, "frames"), "75 of 75 frames (100 %), 2 min 30 s so far");
  EXPECT_EQ(progressLine(0, 0, 0, "steps"), "0 of 0 steps, 0 s so far");
}

TEST(ProgressLine, AFractionOfTheWayGivesTheTimeLeftAtItsPace) {
  // A quarter of the way in 30 s: three quarters left, 90 s.
  EXPECT_EQ(fractionProgressLine("path", 0.25, 30), "path 25 %, 30 s so far, about 1 min 30 s left at this pace");
  // Under 1 % the pace says little; at the end nothing is left; out-of-range fractions are clamped.
  EXPECT_EQ(fractionProgressLine("path", 0.005, 12), "path 0 %, 12 s so far");
  EXPECT_EQ(fractionProgressLine("path", 1.0, 64), "path 100 %, 1 min 4 s so far");
  EXPECT_EQ(fractionProgressLine("path", 1.7, 5), "path 100 %, 5 s so far");
  EXPECT_EQ(fractionProgressLine("path", std::nan(""), 5), "path 0 %, 5 s so far");
}
