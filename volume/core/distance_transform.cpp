#include "distance_transform.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "parallel_for.h"

namespace repose {
namespace {

/// One line: d[q] = min over p of (h (q - p))^2 + f[p], q and p in [0, n) (f infinite where unset
/// in the first pass). v, z: scratch of n and n + 1.
void lowerEnvelope(const double* f, long n, double h, double* d, long* v, double* z) {
  const double inf = std::numeric_limits<double>::infinity(), h2 = h * h;
  auto meet = [&](long p, long q) {  // where the parabolas of p < q meet
    return ((f[q] + h2 * double(q) * double(q)) - (f[p] + h2 * double(p) * double(p))) / (2 * h2 * double(q - p));
  };
  long k = -1;
  for (long q = 0; q < n; ++q) {
    if (f[q] == inf) continue;
    if (k < 0) {
      v[k = 0] = q, z[0] = -inf, z[1] = inf;
      continue;
    }
    double s = meet(v[k], q);
    while (s <= z[k]) s = meet(v[--k], q);
    v[++k] = q;
    z[k] = s;
    z[k + 1] = inf;
  }
  k = 0;
  for (long q = 0; q < n; ++q) {
    while (z[k + 1] < double(q)) ++k;
    const double dq = h * double(q - v[k]);
    d[q] = dq * dq + f[v[k]];
  }
}

}  // namespace

std::vector<double> squaredDistanceToUnset(const std::vector<std::uint8_t>& mask, const std::array<int, 3>& dims,
                                           const Eigen::Vector3d& spacing) {
  const std::size_t count = std::size_t(std::max(0, dims[0])) * std::size_t(std::max(0, dims[1])) *
                            std::size_t(std::max(0, dims[2]));
  if (mask.size() != count) throw std::invalid_argument("the mask's size does not match its dimensions");
  if (!(spacing.minCoeff() > 0)) throw std::invalid_argument("the spacing must be positive");
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<double> d(count);
  for (std::size_t i = 0; i < count; ++i) d[i] = mask[i] ? inf : 0.0;
  const std::array<std::size_t, 3> stride{1, std::size_t(dims[0]), std::size_t(dims[0]) * std::size_t(dims[1])};
  for (int axis = 0; axis < 3 && count > 0; ++axis) {
    const int u = (axis + 1) % 3, w = (axis + 2) % 3;
    const std::size_t lines = std::size_t(dims[u]) * std::size_t(dims[w]), n = std::size_t(dims[axis]);
    parallelFor(
        lines,
        [&](std::size_t l0, std::size_t l1) {
          // The line copied out with an unset sample at each end (the world beyond the box).
          std::vector<double> in(n + 2, 0.0), out(n + 2), z(n + 3);
          std::vector<long> v(n + 2);
          for (std::size_t l = l0; l < l1; ++l) {
            const std::size_t start = (l % std::size_t(dims[u])) * stride[u] + (l / std::size_t(dims[u])) * stride[w];
            bool any = false;
            for (std::size_t q = 0; q < n; ++q) in[q + 1] = d[start + q * stride[axis]], any |= in[q + 1] != 0;
            if (!any) continue;
            lowerEnvelope(in.data(), long(n + 2), spacing[axis], out.data(), v.data(), z.data());
            for (std::size_t q = 0; q < n; ++q) d[start + q * stride[axis]] = out[q + 1];
          }
        },
        64);
  }
  return d;
}

}  // namespace repose
