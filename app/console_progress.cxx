#include "console_progress.h"

#include <chrono>
#include <iostream>
#include <memory>

namespace repose {

std::function<void(const std::string&)> throttledConsoleProgress(const std::string& prefix, double interval) {
  using Clock = std::chrono::steady_clock;
  auto last = std::make_shared<Clock::time_point>();
  auto printed = std::make_shared<bool>(false);
  return [=](const std::string& text) {
    const Clock::time_point now = Clock::now();
    if (*printed && std::chrono::duration<double>(now - *last).count() < interval) return;
    *printed = true;
    *last = now;
    std::cout << prefix << text << std::endl;
  };
}

}  // namespace repose
