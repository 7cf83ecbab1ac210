#include "continuation_stall.h"

namespace repose {

bool continuationPaceStalls(const std::vector<double>& pathAfterStep, int steps, int budget, std::size_t window) {
  const std::size_t known = pathAfterStep.size();
  if (window == 0 || known <= window) return false;
  const double s = pathAfterStep.back();
  if (s >= 1.0) return false;
  const double pace = (s - pathAfterStep[known - 1 - window]) / double(window);
  return double(steps) * pace + (1.0 - s) > 2.0 * double(budget) * pace;
}

}  // namespace repose
