#include "point_grid.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace repose {

PointGrid::PointGrid(std::vector<Eigen::Vector3d> points, double cell) : points_(std::move(points)), cell_(cell) {
  if (!(cell > 0)) throw std::invalid_argument("PointGrid: the cell size must be positive");
  lo_ = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  hi_ = -lo_;
  for (std::size_t n = 0; n < points_.size(); ++n) {
    const Eigen::Vector3d& p = points_[n];
    lo_ = lo_.cwiseMin(p);
    hi_ = hi_.cwiseMax(p);
    buckets_[key(long(std::floor(p.x() / cell_)), long(std::floor(p.y() / cell_)), long(std::floor(p.z() / cell_)))]
        .push_back(n);
  }
}

PointGrid::Key PointGrid::key(long i, long j, long k) const {
  // 21 bits per axis: +-1 M cells, far more than any scan holds.
  const long o = 1L << 20;
  return ((Key(i + o) & 0x1FFFFF) << 42) | ((Key(j + o) & 0x1FFFFF) << 21) | (Key(k + o) & 0x1FFFFF);
}

double PointGrid::boxDistance(const Eigen::Vector3d& x) const {
  if (points_.empty()) return std::numeric_limits<double>::infinity();
  const Eigen::Vector3d d = (lo_ - x).cwiseMax(x - hi_).cwiseMax(0.0);
  return d.norm();
}

double PointGrid::boxDistance(const PointGrid& o) const {
  if (points_.empty() || o.points_.empty()) return std::numeric_limits<double>::infinity();
  return (lo_ - o.hi_).cwiseMax(o.lo_ - hi_).cwiseMax(0.0).norm();
}

PointGrid::Hit PointGrid::nearest(const Eigen::Vector3d& x, double maxDistance) const {
  Hit best{std::numeric_limits<double>::infinity(), 0};
  if (boxDistance(x) > maxDistance) return best;
  const long ci = long(std::floor(x.x() / cell_)), cj = long(std::floor(x.y() / cell_)),
             ck = long(std::floor(x.z() / cell_));
  // No point lies farther (in cells) than the far corner of the points' box.
  const double farthest = (x - lo_).cwiseAbs().cwiseMax((x - hi_).cwiseAbs()).maxCoeff();
  const long rings = long(std::ceil(std::min(maxDistance, farthest) / cell_)) + 1;
  double limit2 = maxDistance * maxDistance;
  // Search shells of cells outward (Chebyshev rings); a point in ring r is at least (r - 1) cells
  // away, and no point lies in a ring nearer than the points' box allows.
  const long r0 = std::max(0L, long(boxDistance(x) / (cell_ * 1.7320508075688772)) - 1);
  auto visit = [&](long di, long dj, long dk) {
    const auto it = buckets_.find(key(ci + di, cj + dj, ck + dk));
    if (it == buckets_.end()) return;
    for (std::size_t n : it->second) {
      const double d2 = (points_[n] - x).squaredNorm();
      if (d2 <= limit2) {
        limit2 = d2;
        best = {std::sqrt(d2), n};
      }
    }
  };
  for (long r = r0; r <= rings; ++r) {
    const double shellMin = (r - 1) * cell_;
    if (shellMin > 0 && shellMin * shellMin > limit2) break;
    for (long dk = -r; dk <= r; ++dk)
      for (long dj = -r; dj <= r; ++dj) {
        if (std::labs(dk) == r || std::labs(dj) == r) {
          for (long di = -r; di <= r; ++di) visit(di, dj, dk);
        } else {
          visit(-r, dj, dk);
          if (r > 0) visit(r, dj, dk);
        }
      }
  }
  return best;
}

PointGrid::Pair PointGrid::closestPair(const std::vector<Eigen::Vector3d>& queries, double maxDistance,
                                      std::size_t maxQueries) const {
  Pair best{std::numeric_limits<double>::infinity(), 0, 0};
  double limit = maxDistance;
  const std::size_t step = std::max<std::size_t>(1, queries.size() / std::max<std::size_t>(1, maxQueries));
  for (std::size_t q = 0; q < queries.size(); q += step) {
    const Hit h = nearest(queries[q], limit);
    if (h.distance <= limit && h.distance < best.distance) {
      best = {h.distance, q, h.index};
      limit = h.distance;
    }
  }
  return best;
}

}  // namespace repose
