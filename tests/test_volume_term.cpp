// The volume part of the fixed-corotated energy density and its guards against inversion.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "volume_term.h"

namespace {

// The volume term and its two guards below J = eps: p and the stiffness are h's derivatives (central
// differences), both guards join the plain term smoothly at eps (value, p and, for the barrier, the
// stiffness), the barrier grows without bound as J -> 0 and is infinite at and below 0, and the
// penalty stays finite through inversion.
TEST(VolumeTerm, DerivativesContinuityAndTheBarrier) {
  const repose::VolumeTerm term{24.5, 245.0, 0.1};
  for (bool barrier : {false, true}) {
    for (double J : {0.002, 0.01, 0.03, 0.07, 0.099, 0.101, 0.5, 1.0, 1.7}) {
      double p, k, pp, kp, pm, km;
      term(J, barrier, p, k);
      const double e = 1e-6 * J;
      const double hp = term(J + e, barrier, pp, kp), hm = term(J - e, barrier, pm, km);
      EXPECT_NEAR(p, (hp - hm) / (2 * e), 1e-5 * (1 + std::abs(p))) << "J " << J << " barrier " << barrier;
      EXPECT_NEAR(k, (pp - pm) / (2 * e), 1e-4 * (1 + std::abs(k))) << "J " << J << " barrier " << barrier;
    }
    double pl, kl, pr, kr;
    const double left = term(0.1 - 1e-12, barrier, pl, kl), right = term(0.1, barrier, pr, kr);
    EXPECT_NEAR(left, right, 1e-9);
    EXPECT_NEAR(pl, pr, 1e-8);
    if (barrier) EXPECT_NEAR(kl, kr, 1e-6);
  }
  double p, k;
  const double at2 = term(1e-2, true, p, k), at8 = term(1e-8, true, p, k);  // logarithmic growth
  EXPECT_GT(k, 1e6);
  EXPECT_GT(at8, at2 + 0.01 * 245.0 * std::log(1e5));
  EXPECT_GT(term(1e-200, true, p, k), at8 + 0.01 * 245.0 * std::log(1e150));
  EXPECT_TRUE(std::isinf(term(0.0, true, p, k)));
  EXPECT_TRUE(std::isinf(term(-0.2, true, p, k)));
  EXPECT_TRUE(std::isfinite(term(-0.2, false, p, k)));
  EXPECT_LT(p, 0.0);  // the penalty pushes an inverted tet back
}

}  // namespace
