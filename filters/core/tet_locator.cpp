#include "tet_locator.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace repose {
namespace {

// Closest point on triangle abc to p (Ericson, Real-Time Collision Detection, 5.1.5).
Eigen::Vector3d closestOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                  const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + (d1 / (d1 - d3)) * ab;
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + (d2 / (d2 - d6)) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b);
  const double denom = 1.0 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

}  // namespace

TetLocator::TetLocator(const Points& nodes, const Tets& tets) : nodes_(nodes), tets_(tets) {
  const std::size_t nT = std::size_t(tets.rows());
  if (tets.size() > 0 && (tets.minCoeff() < 0 || tets.maxCoeff() >= nodes.rows()))
    throw std::invalid_argument("tet locator: tet node index out of range [0, " + std::to_string(nodes.rows()) +
                                ")");
  if (!nodes.allFinite()) throw std::invalid_argument("tet locator: non-finite node coordinates");
  if (nT == 0) {
    cellStart_.assign(2, 0);
    return;
  }
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::max());
  Eigen::Vector3d hi = -lo;
  double extentSum = 0;
  for (std::size_t t = 0; t < nT; ++t) {
    Eigen::Vector3d tlo = nodes.row(tets(t, 0)).transpose(), thi = tlo;
    for (int c = 1; c < 4; ++c) {
      tlo = tlo.cwiseMin(nodes.row(tets(t, c)).transpose());
      thi = thi.cwiseMax(nodes.row(tets(t, c)).transpose());
    }
    lo = lo.cwiseMin(tlo);
    hi = hi.cwiseMax(thi);
    extentSum += std::cbrt((thi - tlo).cwiseMax(1e-9 * (thi - tlo).maxCoeff()).prod());
  }
  const Eigen::Vector3d ext = (hi - lo).cwiseMax(1e-12);
  // Cells about one (geometric-mean) tet across: few cells per tet and few tets per cell.
  h_ = std::max(extentSum / double(nT), std::cbrt(ext.prod() / double(nT)));
  if (!(h_ > 0)) h_ = ext.maxCoeff();
  for (int a = 0; a < 3; ++a) {
    // Keep the grid bounded for extreme aspect ratios.
    dims_[a] = int(std::min(4096.0, std::max(1.0, std::ceil(ext[a] / h_))));
  }
  lo_ = lo;
  auto cellRange = [&](std::size_t t, Eigen::Array3i& c0, Eigen::Array3i& c1) {
    Eigen::Vector3d tlo = nodes.row(tets(t, 0)).transpose(), thi = tlo;
    for (int c = 1; c < 4; ++c) {
      tlo = tlo.cwiseMin(nodes.row(tets(t, c)).transpose());
      thi = thi.cwiseMax(nodes.row(tets(t, c)).transpose());
    }
    c0 = cellOf(tlo);
    c1 = cellOf(thi);
  };
  const std::size_t nCells = std::size_t(dims_.x()) * dims_.y() * dims_.z();
  cellStart_.assign(nCells + 1, 0);
  Eigen::Array3i c0, c1;
  for (std::size_t t = 0; t < nT; ++t) {
    cellRange(t, c0, c1);
    for (int z = c0.z(); z <= c1.z(); ++z)
      for (int y = c0.y(); y <= c1.y(); ++y)
        for (int x = c0.x(); x <= c1.x(); ++x) ++cellStart_[cellIndex({x, y, z}) + 1];
  }
  for (std::size_t c = 0; c < nCells; ++c) cellStart_[c + 1] += cellStart_[c];
  cellTets_.resize(cellStart_.back());
  std::vector<std::size_t> fill(cellStart_.begin(), cellStart_.end() - 1);
  for (std::size_t t = 0; t < nT; ++t) {
    cellRange(t, c0, c1);
    for (int z = c0.z(); z <= c1.z(); ++z)
      for (int y = c0.y(); y <= c1.y(); ++y)
        for (int x = c0.x(); x <= c1.x(); ++x) cellTets_[fill[cellIndex({x, y, z})]++] = int(t);
  }
}

Eigen::Array3i TetLocator::cellOf(const Eigen::Vector3d& p) const {
  Eigen::Array3i c;
  for (int a = 0; a < 3; ++a) {
    const double f = std::floor((p[a] - lo_[a]) / h_);
    c[a] = int(std::min(double(dims_[a] - 1), std::max(0.0, f)));
  }
  return c;
}

Eigen::Vector4d TetLocator::barycentric(int t, const Eigen::Vector3d& p) const {
  const Eigen::Vector3d a = nodes_.row(tets_(t, 0)).transpose();
  const Eigen::Vector3d e1 = nodes_.row(tets_(t, 1)).transpose() - a;
  const Eigen::Vector3d e2 = nodes_.row(tets_(t, 2)).transpose() - a;
  const Eigen::Vector3d e3 = nodes_.row(tets_(t, 3)).transpose() - a;
  const Eigen::Vector3d q = p - a;
  const Eigen::Vector3d n23 = e2.cross(e3);
  const double det = e1.dot(n23);
  if (!(std::abs(det) > 0)) return Eigen::Vector4d::Constant(std::numeric_limits<double>::quiet_NaN());
  Eigen::Vector4d l;
  l[1] = q.dot(n23) / det;
  l[2] = e1.dot(q.cross(e3)) / det;
  l[3] = e1.dot(e2.cross(q)) / det;
  l[0] = 1.0 - l[1] - l[2] - l[3];
  return l;
}

double TetLocator::distanceToTet(int t, const Eigen::Vector3d& p) const {
  const Eigen::Vector4d l = barycentric(t, p);
  if (l.allFinite() && l.minCoeff() >= 0) return 0;
  static const int faces[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
  double best = std::numeric_limits<double>::infinity();
  for (const auto& f : faces) {
    const Eigen::Vector3d q = closestOnTriangle(p, nodes_.row(tets_(t, f[0])).transpose(),
                                                nodes_.row(tets_(t, f[1])).transpose(),
                                                nodes_.row(tets_(t, f[2])).transpose());
    best = std::min(best, (q - p).squaredNorm());
  }
  return std::sqrt(best);
}

bool TetLocator::findContaining(const Eigen::Vector3d& p, Hit& hit, double eps) const {
  if (tets_.rows() == 0) return false;
  // Points outside the grid clamp to a boundary cell, as the tets there were registered.
  const std::size_t c = cellIndex(cellOf(p));
  for (std::size_t q = cellStart_[c]; q < cellStart_[c + 1]; ++q) {
    const int t = cellTets_[q];
    const Eigen::Vector4d l = barycentric(t, p);
    if (l.allFinite() && l.minCoeff() >= -eps) {
      hit.tet = t;
      hit.bary = l;
      hit.distance = 0;
      return true;
    }
  }
  return false;
}

namespace {
// Tets within 5 % (and a micrometre) of the nearest distance count as equally near, so the
// best-conditioned of them can be chosen.
double tieTolerance(double best) {
  return std::isfinite(best) ? 1e-6 + 0.05 * best : 0.0;
}
}  // namespace

TetLocator::Hit TetLocator::findNearest(const Eigen::Vector3d& p) const {
  Hit hit;
  if (tets_.rows() == 0) return hit;
  if (findContaining(p, hit)) return hit;
  const Eigen::Array3i c0 = cellOf(p);
  const int maxRing = dims_.maxCoeff();
  double best = std::numeric_limits<double>::infinity();
  std::vector<std::pair<double, int>> candidates;  // (distance, tet) within the running tie band
  for (int r = 0; r <= maxRing; ++r) {
    for (int z = c0.z() - r; z <= c0.z() + r; ++z) {
      if (z < 0 || z >= dims_.z()) continue;
      for (int y = c0.y() - r; y <= c0.y() + r; ++y) {
        if (y < 0 || y >= dims_.y()) continue;
        const bool yzShell = std::abs(z - c0.z()) == r || std::abs(y - c0.y()) == r;
        for (int x = c0.x() - r; x <= c0.x() + r; x += (yzShell || r == 0) ? 1 : 2 * r) {
          if (x < 0 || x >= dims_.x()) continue;
          const std::size_t c = cellIndex({x, y, z});
          for (std::size_t q = cellStart_[c]; q < cellStart_[c + 1]; ++q) {
            const int t = cellTets_[q];
            // Cheap bounding-box lower bound before the exact distance.
            Eigen::Vector3d tlo = nodes_.row(tets_(t, 0)).transpose(), thi = tlo;
            for (int k = 1; k < 4; ++k) {
              tlo = tlo.cwiseMin(nodes_.row(tets_(t, k)).transpose());
              thi = thi.cwiseMax(nodes_.row(tets_(t, k)).transpose());
            }
            const double boxDist = (tlo - p).cwiseMax(p - thi).cwiseMax(0.0).norm();
            if (boxDist > best + tieTolerance(best)) continue;
            const double d = distanceToTet(t, p);
            if (d > best + tieTolerance(best)) continue;
            best = std::min(best, d);
            candidates.push_back({d, t});
          }
        }
      }
    }
    // Unvisited cells lie beyond one of the faces of the visited block: stop when all are farther.
    double bound = std::numeric_limits<double>::infinity();
    for (int a = 0; a < 3; ++a) {
      if (c0[a] - r - 1 >= 0) bound = std::min(bound, p[a] - (lo_[a] + (c0[a] - r) * h_));
      if (c0[a] + r + 1 < dims_[a]) bound = std::min(bound, lo_[a] + (c0[a] + r + 1) * h_ - p[a]);
    }
    if (best + tieTolerance(best) <= bound) break;
  }
  // The nearest point is usually a vertex or edge shared by many tets: among the (nearly) nearest,
  // a well-shaped tet extrapolates stably, a sliver would amplify every later deformation.
  double hitConditioning = std::numeric_limits<double>::infinity();
  for (const auto& [d, t] : candidates) {
    if (d > best + tieTolerance(best)) continue;
    const Eigen::Vector4d l = barycentric(t, p);
    if (!l.allFinite()) continue;
    const double conditioning = l.cwiseAbs().maxCoeff();
    if (conditioning < hitConditioning || (conditioning == hitConditioning && t < hit.tet)) {
      hit.tet = t;
      hit.bary = l;
      hit.distance = d;
      hitConditioning = conditioning;
    }
  }
  return hit;
}

}  // namespace repose
