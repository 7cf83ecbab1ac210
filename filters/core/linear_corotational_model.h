#pragma once
// The linear corotational model (internal to corotational_fem, see CorotationalOptions::Linear;
// Mueller & Gross 2004): per outer iteration, each tet's rotation is taken from the current pose
// and the linear elasticity of the rotated rest shape is solved; volume is kept only to first order.
#include <vector>

#include "corotational_fem.h"
#include "fem_newton_matrix.h"
#include "fem_spd_solver.h"
#include "fem_tet_geometry.h"

namespace repose {
namespace fem {

/// options.outerIterations solves on posed's free nodes (system.freeNodes), each warm-started from
/// the last; then, with options.untangle, the tets left inverted are untangled (tet_untangling.h).
/// lambda, mu: Lame's parameters. Fills the report's iteration counts, residuals and times.
void relaxLinearCorotational(const Points& rest, const Tets& tets, const std::vector<int>& fixedBone,
                             const std::vector<RestTet>& restTets, FreeNodeSystem& system, SpdSolver& solver,
                             const CorotationalOptions& options, double lambda, double mu, Points& posed,
                             CorotationalReport& rep);

}  // namespace fem
}  // namespace repose
