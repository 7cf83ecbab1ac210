#pragma once
// When the FEM relaxation's fold-free continuation (fold_free_continuation.h) has stalled on its
// path, and when it is given up.
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

/// The pace (path per step) of the last `window` steps of pathAfterStep (as above), or of all of them
/// if fewer are known, counted from `from`, where the path started or was last relaxed (0 if no step
/// is known).
double continuationPace(const std::vector<double>& pathAfterStep, double from, std::size_t window = 20);

/// Whether the tissue's relaxation where the path stalled (at s = relaxedAt, with the path's pace then
/// paceBefore, from continuationPace) has paid by the next stall: the path has gone on faster since.
/// If not, the block is not the tissue that predictors alone carried along, and another relaxation
/// only spends the steps until the stall after it: the Visible Human's 90 degree hip flexion stalled
/// at s = 0.4529 (step 91, pace 1.5e-3), reached 0.4784 in the 21 steps after its first relaxation
/// (pace 1.2e-3), and 0.4803 and 0.4824 after the second and third (step 154).
/// pathSinceRelaxed  s after each step since that relaxation
bool continuationRelaxationPaid(const std::vector<double>& pathSinceRelaxed, double relaxedAt, double paceBefore);

}  // namespace repose
