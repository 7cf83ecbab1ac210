#pragma once
// What a command prints about its pipeline run: the stage times and the quality of the pose.
#include <cstddef>

#include "pose_quality.h"

namespace repose {

class Pipeline;
struct DeformationStats;

/// One line per timed stage from the `from`-th on: "  stage            1.234 s".
void printTimings(const Pipeline& pipeline, std::size_t from = 0);

/// The quality of the pipeline's current pose (its posed mesh against the rest mesh), labels named
/// from the case's table.
PoseQuality poseQualityOf(Pipeline& pipeline, const DeformationStats& stats);

}  // namespace repose
