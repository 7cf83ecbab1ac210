#include "tet_turning_point.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace repose {

double tetTurningPoint(const Eigen::Matrix3d& D, const Eigen::Matrix3d& E, double limit) {
  auto cofactor = [](const Eigen::Matrix3d& M) {
    Eigen::Matrix3d C;
    C.col(0) = M.col(1).cross(M.col(2));
    C.col(1) = M.col(2).cross(M.col(0));
    C.col(2) = M.col(0).cross(M.col(1));
    return C;
  };
  const Eigen::Matrix3d cofD = cofactor(D), cofE = cofactor(E);
  const double c0 = D.col(0).dot(cofD.col(0)), c1 = cofD.cwiseProduct(E).sum(), c2 = cofE.cwiseProduct(D).sum(),
               c3 = E.col(0).dot(cofE.col(0));
  if (!(c0 > 0.0)) return limit;  // flat already (rounding against a barrier flag): left to the sign check
  if (c0 - limit * (std::abs(c1) + limit * (std::abs(c2) + limit * std::abs(c3))) > 0.0) return limit;
  auto p = [&](double a) { return c0 + a * (c1 + a * (c2 + a * c3)); };
  // p is monotone between its critical points (the roots of c1 + 2 c2 a + 3 c3 a^2): the first piece
  // of [0, limit] that ends at p <= 0 holds the first root, and bisection finds it there.
  double ends[3];
  int nEnds = 0;
  const double qa = 3.0 * c3, qb = 2.0 * c2, qc = c1;
  if (qa != 0.0) {
    const double disc = qb * qb - 4.0 * qa * qc;
    if (disc >= 0.0) {
      const double q = -0.5 * (qb + std::copysign(std::sqrt(disc), qb));  // no cancellation
      if (q != 0.0) {
        ends[nEnds++] = q / qa;
        ends[nEnds++] = qc / q;
      }
    }
  } else if (qb != 0.0) {
    ends[nEnds++] = -qc / qb;
  }
  std::sort(ends, ends + nEnds);
  double lo = 0.0, hi = -1.0;
  for (int k = 0; k <= nEnds && hi < 0.0; ++k) {
    const double end = k < nEnds ? ends[k] : limit;
    if (!(end > lo)) continue;
    if (end >= limit) {
      if (!(p(limit) > 0.0)) hi = limit;
      break;
    }
    if (!(p(end) > 0.0))
      hi = end;
    else
      lo = end;
  }
  if (hi < 0.0) return limit;
  for (int k = 0; k < 60; ++k) {
    const double m = 0.5 * (lo + hi);
    (p(m) > 0.0 ? lo : hi) = m;
  }
  return lo;
}

}  // namespace repose
