#pragma once
// Where a tet moving along a step turns flat: the line search's bound in the FEM relaxation.
#include <Eigen/Core>

namespace repose {

/// For a tet with edge matrix D (columns x1 - x0, x2 - x0, x3 - x0) moving by E (the same of its
/// nodes' step): the smallest a in (0, limit) at which det(D + a E) reaches 0, or limit if it stays
/// positive there (or det D is not positive to begin with).
/// det(D + a E) = det D + a (cof D : E) + a^2 (cof E : D) + a^3 det E, so most tets (a step small
/// against their size) are cleared by a bound on the coefficients alone; for the others the cubic
/// is cut at its critical points into monotone pieces, and the first root is bisected in the first
/// piece that ends at or below 0.
double tetTurningPoint(const Eigen::Matrix3d& D, const Eigen::Matrix3d& E, double limit);

}  // namespace repose
