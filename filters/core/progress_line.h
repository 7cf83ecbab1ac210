#pragma once
// A console progress line for long runs (animate's frames, a stage's steps): how far, how long so
// far, and the time left from the mean pace so far, so a user can tell a 3 minute wait from a
// 30 minute one.
#include <cstddef>
#include <string>

namespace repose {

/// "41 s", "1 min 50 s", "2 h 05 min" (seconds >= 0, rounded to the second).
std::string durationText(double seconds);

/// "20 of 75 frames (27 %), 41 s so far, about 1 min 53 s left": done of total items named `unit`
/// after secondsSoFar; nothing is said of the time left before the first item or after the last.
std::string progressLine(std::size_t done, std::size_t total, double secondsSoFar, const std::string& unit);

/// "path 42 %, 25 s so far, about 35 s left at this pace": a stage measured by a fraction (0 to 1)
/// of its way, such as the FEM's fold-free continuation along its bone paths; the time left only once
/// 1 % of the way is behind (before that the pace says little) and while the stage is not done.
std::string fractionProgressLine(const std::string& what, double fraction, double secondsSoFar);

}  // namespace repose
