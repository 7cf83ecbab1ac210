#pragma once
// Threading hook for the numeric core. The core has no VTK dependency, so hot loops call
// parallelFor(); the VTK module installs vtkSMPTools as the runner when it is loaded, and
// without it a plain std::thread split is used.
#include <cstddef>
#include <functional>

namespace repose {

/// Runs body(begin, end) over disjoint chunks covering [0, n).
using RangeBody = std::function<void(std::size_t begin, std::size_t end)>;
using ParallelRunner = std::function<void(std::size_t n, std::size_t grain, const RangeBody& body)>;

void parallelFor(std::size_t n, const RangeBody& body, std::size_t grain = 1024);
void setParallelRunner(ParallelRunner runner);

}  // namespace repose
