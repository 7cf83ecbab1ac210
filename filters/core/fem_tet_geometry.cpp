#include "fem_tet_geometry.h"

#include <Eigen/LU>
#include <algorithm>
#include <atomic>
#include <stdexcept>
#include <string>

#include "parallel_for.h"
#include "pinched_nodes.h"
#include "signed_svd.h"

namespace repose {
namespace fem {

std::vector<RestTet> restTetsOf(const Points& rest, const Tets& tets) {
  const Eigen::Index nT = tets.rows();
  std::vector<RestTet> restTets(static_cast<std::size_t>(nT));
  std::atomic<long long> badTet{-1};
  parallelFor(std::size_t(nT), [&](std::size_t b, std::size_t e) {
    for (std::size_t t = b; t < e; ++t) {
      const auto T = tets.row(Eigen::Index(t));
      Mat3 Dm;
      const Vec3 x0 = node(rest, T[0]);
      for (int k = 0; k < 3; ++k) Dm.col(k) = node(rest, T[k + 1]) - x0;
      const double det = Dm.determinant();
      RestTet& r = restTets[t];
      r.volume = det / 6.0;
      const double scale = Dm.colwise().norm().maxCoeff();
      if (!(det > 1e-12 * scale * scale * scale)) {
        badTet = (long long)t;
        continue;
      }
      r.DmInv = Dm.inverse();
    }
  });
  if (badTet >= 0)
    throw std::invalid_argument("relaxCorotational: rest tet " + std::to_string(badTet.load()) +
                                " is degenerate or inverted (rest volume must be > 0)");
  return restTets;
}

Mat3 robustRotation(const Mat3& F) {
  Mat3 U, V;
  Vec3 sigma;
  signedSvd(F, U, sigma, V);
  return U * V.transpose();
}

int countInverted(const Points& P, const Tets& tets, const std::vector<char>* only) {
  std::atomic<int> count{0};
  parallelFor(std::size_t(tets.rows()), [&](std::size_t b, std::size_t e) {
    int local = 0;
    for (std::size_t t = b; t < e; ++t) {
      if (only && !(*only)[t]) continue;
      const auto T = tets.row(Eigen::Index(t));
      if (tetVolume(node(P, T[0]), node(P, T[1]), node(P, T[2]), node(P, T[3])) <= 0.0) ++local;
    }
    count += local;
  });
  return count.load();
}

bool turnsAPositiveTet(const Points& from, const Points& to, const Tets& tets) {
  std::atomic<bool> turned{false};
  parallelFor(std::size_t(tets.rows()), [&](std::size_t b, std::size_t e) {
    for (std::size_t t = b; t < e && !turned.load(std::memory_order_relaxed); ++t) {
      const auto T = tets.row(Eigen::Index(t));
      if (tetVolume(node(to, T[0]), node(to, T[1]), node(to, T[2]), node(to, T[3])) <= 0.0 &&
          tetVolume(node(from, T[0]), node(from, T[1]), node(from, T[2]), node(from, T[3])) > 0.0)
        turned = true;
    }
  });
  return turned.load();
}

void countInvertedAfter(const Points& P, const Tets& tets, const std::vector<int>& fixedBone, CorotationalReport& rep) {
  rep.invertedAfter = rep.invertedRigid = 0;
  for (Eigen::Index t = 0; t < tets.rows(); ++t) {
    const auto T = tets.row(t);
    if (tetVolume(node(P, T[0]), node(P, T[1]), node(P, T[2]), node(P, T[3])) > 0.0) continue;
    ++rep.invertedAfter;
    bool rigid = true;
    for (int a = 0; a < 4; ++a) rigid = rigid && fixedBone[std::size_t(T[a])] >= 0;
    if (rigid) ++rep.invertedRigid;
  }
  rep.pinchedNodes = 0;
  rep.pinchedShortfall = 0.0;
  if (rep.invertedAfter == rep.invertedRigid) return;  // no fold a node could be pinched in
  for (const PinchedNode& p : findPinchedNodes(P, tets, fixedBone)) {
    ++rep.pinchedNodes;
    rep.pinchedShortfall = std::max(rep.pinchedShortfall, p.shortfall);
  }
}

}  // namespace fem
}  // namespace repose
