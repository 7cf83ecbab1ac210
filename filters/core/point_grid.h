#pragma once
// Nearest-point queries on a point set (a bone's surface voxels) by bucketing into a uniform grid:
// exact, and fast when the points are spread like surfaces (a few per cell).
#include <Eigen/Core>
#include <cstddef>
#include <unordered_map>
#include <vector>

namespace repose {

class PointGrid {
public:
  /// `points` physical positions (mm); `cell` the bucket size (mm), a few point spacings.
  PointGrid(std::vector<Eigen::Vector3d> points, double cell);

  struct Hit {
    double distance;     ///< +infinity when no point lies within the limit
    std::size_t index;   ///< of the nearest point in the constructor's order
  };
  /// The nearest point to x within maxDistance (mm).
  Hit nearest(const Eigen::Vector3d& x, double maxDistance) const;

  /// The closest pair between `queries` and this set within maxDistance: distance, the query's
  /// index and the point's index (distance +infinity when no pair is that close). With
  /// maxQueries, only that many queries evenly spread over the list are tried (an upper bound,
  /// for far searches where every query scans many cells).
  struct Pair {
    double distance;
    std::size_t query, index;
  };
  Pair closestPair(const std::vector<Eigen::Vector3d>& queries, double maxDistance,
                   std::size_t maxQueries = std::size_t(-1)) const;

  const std::vector<Eigen::Vector3d>& points() const { return points_; }
  bool empty() const { return points_.empty(); }
  /// Lower bound of the distance from x to any point (its bounding box).
  double boxDistance(const Eigen::Vector3d& x) const;
  /// Lower bound of the distance between the points of two grids (their bounding boxes).
  double boxDistance(const PointGrid& other) const;

private:
  using Key = long long;
  Key key(long i, long j, long k) const;
  std::vector<Eigen::Vector3d> points_;
  double cell_;
  Eigen::Vector3d lo_, hi_;
  std::unordered_map<Key, std::vector<std::size_t>> buckets_;
};

}  // namespace repose
