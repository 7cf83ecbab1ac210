#pragma once
// The corotational FEM's clock and cancel points (internal to corotational_fem): each stage times
// itself into the report and asks CorotationalOptions::checkpoint whether to go on.
#include <chrono>

#include "corotational_fem.h"

namespace repose {
namespace fem {

/// Wall seconds since `since`.
inline double seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

/// Tells options.checkpoint where the solve is; throws RelaxationCancelled when it answers true.
inline void reachCheckpoint(const CorotationalOptions& options, const RelaxationProgress& progress) {
  if (options.checkpoint && options.checkpoint(progress)) throw RelaxationCancelled();
}

}  // namespace fem
}  // namespace repose
