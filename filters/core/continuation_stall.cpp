#include "continuation_stall.h"

#include <algorithm>

namespace repose {

bool continuationPaceStalls(const std::vector<double>& pathAfterStep, int steps, int budget, std::size_t window) {
  const std::size_t known = pathAfterStep.size();
  if (window == 0 || known <= window) return false;
  const double s = pathAfterStep.back();
  if (s >= 1.0) return false;
  const double pace = (s - pathAfterStep[known - 1 - window]) / double(window);
  return double(steps) * pace + (1.0 - s) > 2.0 * double(budget) * pace;
}

double continuationPace(const std::vector<double>& pathAfterStep, double from, std::size_t window) {
  const std::size_t known = pathAfterStep.size(), counted = std::min(known, window);
  if (counted == 0) return 0.0;
  const double start = known > counted ? pathAfterStep[known - 1 - counted] : from;
  return (pathAfterStep.back() - start) / double(counted);
}

bool continuationRelaxationPaid(const std::vector<double>& pathSinceRelaxed, double relaxedAt, double paceBefore) {
  if (pathSinceRelaxed.empty()) return false;
  return (pathSinceRelaxed.back() - relaxedAt) / double(pathSinceRelaxed.size()) > paceBefore;
}

}  // namespace repose
