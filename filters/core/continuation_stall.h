#pragma once
// When the FEM relaxation's fold-free continuation (corotational_fem.h) has stalled on its path.
#include <cstddef>
#include <vector>

namespace repose {

/// The path stalls where bones press tissue to nothing (no fold-free way on): its steps shrink and
/// stay short. Short steps alone are no stall, as the path may squeeze through and the steps grow
/// again (CMU walk, tiny phantom: steps down to 6e-5 of the path, then its end). So the stall is
/// judged by the pace of the last `window` steps: at that pace, would the path need more than twice
/// its step budget in all? (CMU walk: 108 steps at most; the medium phantom's shoulder at 45
/// degrees: 400 and more from step 45 on, where a path of 1e-3 in `window` steps, the earlier test,
/// fired at step 48; a window of 10 steps comes close to firing on the walk.)
///
/// pathAfterStep  s (0 to 1) after each step since the path started or was last relaxed
/// steps          the steps taken since the path started
/// budget         the step budget (CorotationalOptions::maxContinuationSteps)
/// Returns false until window + 1 steps are known, and at the path's end.
bool continuationPaceStalls(const std::vector<double>& pathAfterStep, int steps, int budget,
                            std::size_t window = 20);

}  // namespace repose
