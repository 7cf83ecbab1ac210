#include "progress_line.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace repose {

std::string durationText(double seconds) {
  const long s = std::lround(std::max(0.0, seconds));
  char text[64];
  if (s < 60)
    std::snprintf(text, sizeof(text), "%ld s", s);
  else if (s < 3600)
    std::snprintf(text, sizeof(text), "%ld min %ld s", s / 60, s % 60);
  else
    std::snprintf(text, sizeof(text), "%ld h %02ld min", s / 3600, s % 3600 / 60);
  return text;
}

std::string progressLine(std::size_t done, std::size_t total, double secondsSoFar, const std::string& unit) {
  std::string line = std::to_string(done) + " of " + std::to_string(total) + " " + unit;
  if (total > 0) line += " (" + std::to_string(100 * done / total) + " %)";
  line += ", " + durationText(secondsSoFar) + " so far";
  if (done > 0 && done < total)
    line += ", about " + durationText(secondsSoFar / double(done) * double(total - done)) + " left";
  return line;
}

std::string fractionProgressLine(const std::string& what, double fraction, double secondsSoFar) {
  const double f = std::clamp(std::isfinite(fraction) ? fraction : 0.0, 0.0, 1.0);
  std::string line = what + " " + std::to_string(int(std::floor(100.0 * f))) + " %, " + durationText(secondsSoFar) +
                     " so far";
  if (f >= 0.01 && f < 1.0) line += ", about " + durationText(secondsSoFar * (1.0 - f) / f) + " left at this pace";
  return line;
}

}  // namespace repose
