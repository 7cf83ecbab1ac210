#pragma once
// A relaxation's warm start between runs (animation frames, a dragged joint): the last run's
// correction, its output minus its input, offered as the next run's start on the same rest mesh.
#include <cstdint>

#include "corotational_fem.h"
#include "tet_mesh.h"

namespace repose {

class RelaxationWarmStart {
 public:
  /// Sets options.startCorrection to the last correction when `wanted`, the model is fixed-corotated
  /// (the linear model takes no start), the rest mesh is the one it was made on (restKey, e.g. its
  /// modification time) and it has nodeCount rows.
  void offer(bool wanted, std::uint64_t restKey, Eigen::Index nodeCount, CorotationalOptions& options) const;
  /// Drops the correction: a failed run leaves nothing to start from.
  void forget();
  /// Keeps output - input (#V by 3 each) as the correction made on the rest mesh restKey.
  void remember(std::uint64_t restKey, const Points& input, const Points& output);

 private:
  Points correction_;
  std::uint64_t restKey_ = 0;
};

}  // namespace repose
