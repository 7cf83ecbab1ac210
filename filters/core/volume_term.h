#pragma once
// The volume part of the fixed-corotated energy density, with its guard against inversion.
#include <cmath>
#include <limits>

namespace repose {

/// h(J) = lambda/2 (J - 1)^2 plus a guard below J = eps, which the fixed-corotated term alone lacks
/// (it is finite and smooth through J = 0, so a fold can be its minimum): the penalty
/// kappa (eps - J)^2, or the clamped log barrier -kappa (J - eps)^2 ln(J / eps) (Li et al. 2020),
/// C2 at eps and infinite for J <= 0 (see CorotationalOptions::inversionBarrier).
/// Returns h; p = h'(J) (the pressure), stiffness = h''(J).
struct VolumeTerm {
  double lambda, kappa, eps;
  double operator()(double J, bool barrier, double& p, double& stiffness) const {
    p = lambda * (J - 1.0);
    stiffness = lambda;
    const double h = 0.5 * lambda * (J - 1.0) * (J - 1.0);
    if (J >= eps) return h;
    if (!barrier) {
      const double below = eps - J;
      p -= 2.0 * kappa * below;
      stiffness += 2.0 * kappa;
      return h + kappa * below * below;
    }
    if (!(J > 0.0)) return std::numeric_limits<double>::infinity();
    const double d = J - eps, l = std::log(J / eps);
    p += kappa * (-2.0 * d * l - d * d / J);
    stiffness += kappa * (-2.0 * l - 4.0 * d / J + d * d / (J * J));
    return h - kappa * d * d * l;
  }
};

}  // namespace repose
