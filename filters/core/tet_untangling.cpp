#include "tet_untangling.h"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace repose {
namespace {

using Vec3 = Eigen::Vector3d;

// Weight of |x - x0|^2 against the squared distances (mm^2) to violated half-spaces: picks the
// nearest of the equally good positions, leaving a violation of about this fraction.
constexpr double kRegularization = 1e-6;

Vec3 node(const Points& P, int i) { return P.row(i).transpose(); }

double signedVolume(const Points& P, const Tets& tets, int t) {
  return tetVolume(node(P, tets(t, 0)), node(P, tets(t, 1)), node(P, tets(t, 2)), node(P, tets(t, 3)));
}

/// Gradient of tet t's signed volume with respect to its local node a (exact: the volume is affine
/// in any one node).
Vec3 volumeGradient(const Points& P, const Tets& tets, int t, int a) {
  const Vec3 p0 = node(P, tets(t, 0)), p1 = node(P, tets(t, 1)), p2 = node(P, tets(t, 2)), p3 = node(P, tets(t, 3));
  const Vec3 g1 = (p2 - p0).cross(p3 - p0) / 6.0, g2 = (p3 - p0).cross(p1 - p0) / 6.0,
             g3 = (p1 - p0).cross(p2 - p0) / 6.0;
  switch (a) {
    case 1: return g1;
    case 2: return g2;
    case 3: return g3;
    default: return -(g1 + g2 + g3);
  }
}

/// The position nearest to x0 among those minimizing the summed squared distances to the violated
/// half-spaces n_k . x >= target V0_k + offset_k: their projection when they have a common point, a
/// least-squares compromise when not. A convex piecewise quadratic: Newton steps on the active set.
Vec3 nearestCompromise(const std::vector<Vec3>& normal, const std::vector<double>& offset, int first, double target,
                       const std::vector<double>& restVolume, const std::vector<int>& inc, const Vec3& x0,
                       int maxSteps) {
  Vec3 x = x0;
  for (int step = 0; step < maxSteps; ++step) {
    Eigen::Matrix3d H = kRegularization * Eigen::Matrix3d::Identity();
    Vec3 grad = kRegularization * (x - x0);
    int active = 0;
    for (std::size_t k = 0; k < normal.size(); ++k) {
      const double nn = normal[k].squaredNorm();
      if (!(nn > 0.0)) continue;
      const double bound = target * restVolume[std::size_t(inc[std::size_t(first) + k] / 4)] + offset[k];
      const double violation = bound - normal[k].dot(x);
      if (violation <= 0.0) continue;
      ++active;
      H += normal[k] * normal[k].transpose() / nn;
      grad -= (violation / nn) * normal[k];
    }
    if (active == 0) break;
    const Vec3 dx = -H.ldlt().solve(grad);
    if (!dx.allFinite()) break;
    x += dx;
    if (dx.norm() < 1e-9 * (1.0 + x0.norm())) break;
  }
  return x;
}

}  // namespace

UntangleReport untangleTets(const Points& rest, const Tets& tets, const std::vector<int>& fixedBone, Points& posed,
                            const UntangleOptions& options) {
  const int nV = int(rest.rows()), nT = int(tets.rows());
  if (posed.rows() != rest.rows() || fixedBone.size() != std::size_t(nV))
    throw std::invalid_argument("untangle: posed (" + std::to_string(posed.rows()) + " nodes) and fixedBone (" +
                                std::to_string(fixedBone.size()) + ") must match rest (" + std::to_string(nV) +
                                " nodes)");
  if (!(options.minVolumeRatio >= 0.0 && options.minVolumeRatio < 1.0))
    throw std::invalid_argument("untangle: minVolumeRatio must be in [0, 1)");
  UntangleReport rep;
  std::vector<int> bad;
  for (int t = 0; t < nT; ++t)
    if (signedVolume(posed, tets, t) <= 0.0) bad.push_back(t);
  rep.invertedBefore = rep.invertedAfter = int(bad.size());
  auto allFixed = [&](int t) {
    for (int a = 0; a < 4; ++a)
      if (fixedBone[std::size_t(tets(t, a))] < 0) return false;
    return true;
  };
  auto finish = [&]() {
    rep.invertedAfter = rep.invertedRigid = 0;
    for (int t = 0; t < nT; ++t)
      if (signedVolume(posed, tets, t) <= 0.0) {
        ++rep.invertedAfter;
        if (allFixed(t)) ++rep.invertedRigid;
      }
    return rep;
  };
  if (bad.empty()) return rep;

  // Node -> incident tets (CSR), built only when something is inverted.
  std::vector<int> start(std::size_t(nV) + 1, 0), inc(std::size_t(4) * std::size_t(nT));
  for (int t = 0; t < nT; ++t)
    for (int a = 0; a < 4; ++a) ++start[std::size_t(tets(t, a)) + 1];
  for (int v = 0; v < nV; ++v) start[std::size_t(v) + 1] += start[std::size_t(v)];
  {
    std::vector<int> fill(start.begin(), start.end() - 1);
    for (int t = 0; t < nT; ++t)
      for (int a = 0; a < 4; ++a) inc[std::size_t(fill[std::size_t(tets(t, a))]++)] = 4 * t + a;
  }
  std::vector<double> restVolume(static_cast<std::size_t>(nT));
  for (int t = 0; t < nT; ++t) restVolume[std::size_t(t)] = signedVolume(rest, tets, t);

  const double ratio = options.minVolumeRatio;
  std::vector<Vec3> normal;
  std::vector<double> offset;
  std::vector<char> positiveHere;  // per tet of the node's star: positive before the move
  // Tets below the target ratio (inverted ones and those left nearly flat). A tet can only fall
  // below it when one of its nodes moves, so after the first sweep only the stars of the nodes
  // worked on (and the low tets already known) are looked at again.
  std::vector<int> low;
  for (int t = 0; t < nT; ++t)
    if (signedVolume(posed, tets, t) <= ratio * restVolume[std::size_t(t)]) low.push_back(t);
  for (rep.sweeps = 0; rep.sweeps < options.maxSweeps; ++rep.sweeps) {
    // Free nodes of the low tets.
    std::vector<int> nodes;
    for (int t : low)
      for (int a = 0; a < 4; ++a)
        if (fixedBone[std::size_t(tets(t, a))] < 0) nodes.push_back(tets(t, a));
    std::sort(nodes.begin(), nodes.end());
    nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
    bool improved = false;
    for (int v : nodes) {
      const int b = start[std::size_t(v)], e = start[std::size_t(v) + 1];
      // Half-spaces n_k . x >= c_k: tet k's volume, affine in this node, at least target * rest volume.
      normal.clear();
      offset.clear();
      int invertedHere = 0;
      double deficitHere = 0.0;
      positiveHere.clear();
      const Vec3 x0 = node(posed, v);
      // A node is moved within its star (no farther than its farthest neighbour): where the half-spaces
      // contradict each other, their least-squares compromise can lie far outside it (medium phantom,
      // linear model: a node sent 1.17 m away, every tet around it turned inside out and grown).
      double reach = 0.0;
      for (int k = b; k < e; ++k) {
        const int t = inc[std::size_t(k)] / 4;
        for (int c = 0; c < 4; ++c) reach = std::max(reach, (node(posed, tets(t, c)) - x0).norm());
      }
      for (int k = b; k < e; ++k) {
        const int t = inc[std::size_t(k)] / 4, a = inc[std::size_t(k)] % 4;
        const Vec3 g = volumeGradient(posed, tets, t, a);
        const double vol = signedVolume(posed, tets, t);
        if (vol <= 0.0) ++invertedHere;
        positiveHere.push_back(vol > 0.0);
        deficitHere += std::max(0.0, ratio * restVolume[std::size_t(t)] - vol);
        normal.push_back(g);
        offset.push_back(g.dot(x0) - vol);
      }
      // The target ratio is lowered when the node cannot give every tet around it that much (a sliver
      // beside an inverted tet may make the full target infeasible while a smaller one is not).
      Vec3 fallback = x0;
      bool haveFallback = false, repaired = false;
      for (const double target : {ratio, ratio / 4, ratio / 16, ratio / 64}) {
        const Vec3 x = nearestCompromise(normal, offset, b, target, restVolume, inc, x0, options.maxLocalSteps);
        if (!((x - x0).norm() <= reach)) continue;
        posed.row(v) = x.transpose();
        int invertedAfter = 0;
        double deficitAfter = 0.0;
        bool turnedPositive = false;
        for (int k = b; k < e; ++k) {
          const int t = inc[std::size_t(k)] / 4;
          const double vol = signedVolume(posed, tets, t);
          if (vol <= 0.0) ++invertedAfter;
          turnedPositive = turnedPositive || (vol <= 0.0 && positiveHere[std::size_t(k - b)]);
          deficitAfter += std::max(0.0, ratio * restVolume[std::size_t(t)] - vol);
        }
        if (turnedPositive) continue;  // never trade a good tet for bad ones (see untangleTets)
        if (invertedAfter < invertedHere || (invertedHere == 0 && invertedAfter == 0 && deficitAfter < 0.999 * deficitHere)) {
          repaired = true;
          break;
        }
        // Not repaired: the full-target compromise is still kept if it adds no inverted tet and lowers
        // the deficit (a neighbour's later move may then open the way).
        if (!haveFallback && invertedAfter == invertedHere && deficitAfter < 0.999 * deficitHere) fallback = x;
        haveFallback = true;
      }
      if (!repaired) posed.row(v) = fallback.transpose();  // (x0 when no candidate was within reach)
      const double move = (node(posed, v) - x0).norm();
      if (move > 0.0) {
        ++rep.nodesMoved;
        rep.maxMove = std::max(rep.maxMove, move);
        improved = true;
      }
    }
    std::vector<int> candidates = low;
    for (int v : nodes)
      for (int k = start[std::size_t(v)]; k < start[std::size_t(v) + 1]; ++k) candidates.push_back(inc[std::size_t(k)] / 4);
    std::sort(candidates.begin(), candidates.end());
    candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
    low.clear();
    int inverted = 0;
    for (int t : candidates) {
      const double vol = signedVolume(posed, tets, t);
      if (vol <= ratio * restVolume[std::size_t(t)]) low.push_back(t);
      if (vol <= 0.0) ++inverted;
    }
    if (inverted == 0 || !improved) {
      ++rep.sweeps;
      break;
    }
  }
  return finish();
}

}  // namespace repose
