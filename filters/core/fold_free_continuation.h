#pragma once
// The fold-free continuation of the fixed-corotated solve (internal to corotational_fem, see
// CorotationalOptions::continuation): where the direct solve leaves a fold that is a local minimum,
// the pose is solved again from the rest shape, which has none, with the bone nodes moved along
// rigid paths (bone_path.h) in adaptive steps, no tet ever inverted on the way; the result replaces
// the direct one if it has fewer inverted tets (or always).
#include "fixed_corotated_newton.h"

namespace repose {
namespace fem {

/// Runs the continuation on a finished direct solve when CorotationalOptions::continuation asks for
/// it (IfInverted: some tet with a free node is inverted and no node is pinched between bones;
/// Always), with the barrier on. Fills the report's continuation fields; posed, the energy terms and
/// the solve's state end as the kept result's.
void foldFreeContinuation(FixedCorotatedNewton& solve);

}  // namespace fem
}  // namespace repose
