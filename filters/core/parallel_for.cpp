#include "parallel_for.h"

#include <algorithm>
#include <thread>
#include <vector>

namespace repose {
namespace {
ParallelRunner& runnerSlot() {
  static ParallelRunner runner;
  return runner;
}

void stdThreadRunner(std::size_t n, std::size_t grain, const RangeBody& body) {
  const std::size_t workers =
      std::max<std::size_t>(1, std::min<std::size_t>(std::thread::hardware_concurrency(), n / std::max<std::size_t>(grain, 1)));
  if (workers <= 1) {
    body(0, n);
    return;
  }
  std::vector<std::thread> threads;
  const std::size_t chunk = (n + workers - 1) / workers;
  for (std::size_t w = 0; w < workers; ++w) {
    const std::size_t b = w * chunk, e = std::min(n, b + chunk);
    if (b < e) threads.emplace_back([&body, b, e] { body(b, e); });
  }
  for (auto& t : threads) t.join();
}
}  // namespace

void setParallelRunner(ParallelRunner runner) { runnerSlot() = std::move(runner); }

void parallelFor(std::size_t n, const RangeBody& body, std::size_t grain) {
  if (n == 0) return;
  if (runnerSlot())
    runnerSlot()(n, grain, body);
  else
    stdThreadRunner(n, grain, body);
}

}  // namespace repose
