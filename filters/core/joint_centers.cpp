#include "joint_centers.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

namespace repose {

namespace {

using V3 = Eigen::Vector3d;

enum class BallHint { Yes, No, Unknown };
BallHint ballHint(const BoneName& b) {
  if (b.type == BoneType::Femur || b.type == BoneType::Humerus) return BallHint::Yes;
  return b.known() ? BallHint::No : BallHint::Unknown;
}

struct SphereFit {
  V3 c = V3::Zero();
  double r = 0, rms = 1e30;
  bool ok = false;
};

SphereFit fitSphereOnce(const std::vector<V3>& pts) {
  SphereFit f;
  const int n = int(pts.size());
  if (n < 6) return f;
  V3 mean = V3::Zero();
  for (const V3& p : pts) mean += p;
  mean /= n;
  // Algebraic fit: |p|^2 = 2 c.p + (r^2 - |c|^2), in coordinates centred on the mean.
  Eigen::MatrixXd A(n, 4);
  Eigen::VectorXd b(n);
  for (int i = 0; i < n; ++i) {
    const V3 q = pts[i] - mean;
    A.row(i) << 2 * q.x(), 2 * q.y(), 2 * q.z(), 1;
    b(i) = q.squaredNorm();
  }
  const Eigen::Vector4d x = A.colPivHouseholderQr().solve(b);
  V3 c = x.head<3>();
  double r2 = x(3) + c.squaredNorm();
  if (!(r2 > 0) || !std::isfinite(r2)) return f;
  double r = std::sqrt(r2);
  // Gauss-Newton on the geometric residuals |p - c| - r.
  for (int it = 0; it < 8; ++it) {
    Eigen::MatrixXd J(n, 4);
    Eigen::VectorXd res(n);
    for (int i = 0; i < n; ++i) {
      const V3 d = pts[i] - mean - c;
      const double len = std::max(d.norm(), 1e-9);
      res(i) = len - r;
      J.row(i) << -d.x() / len, -d.y() / len, -d.z() / len, -1;
    }
    const Eigen::Vector4d step = J.colPivHouseholderQr().solve(-res);
    c += step.head<3>();
    r += step(3);
    if (step.norm() < 1e-6) break;
  }
  double ss = 0;
  for (const V3& p : pts) {
    const double e = (p - mean - c).norm() - r;
    ss += e * e;
  }
  f.c = c + mean;
  f.r = std::abs(r);
  f.rms = std::sqrt(ss / n);
  f.ok = std::isfinite(f.rms) && std::isfinite(f.r);
  return f;
}

// Fit, drop the outliers (points of the bone's neck or shaft near the socket rim), refit.
SphereFit fitSphere(std::vector<V3> pts, double voxel) {
  SphereFit f = fitSphereOnce(pts);
  for (int round = 0; round < 2 && f.ok; ++round) {
    const double tol = std::max(voxel, 2.5 * f.rms);
    std::vector<V3> kept;
    for (const V3& p : pts)
      if (std::abs((p - f.c).norm() - f.r) <= tol) kept.push_back(p);
    if (kept.size() == pts.size() || kept.size() < 6) break;
    pts.swap(kept);
    f = fitSphereOnce(pts);
  }
  return f;
}

class CenterFinder {
public:
  CenterFinder(const ImageGrid& grid, const RigBones& rb, const std::vector<std::vector<BoneContact>>& contacts,
               const AutoRigOptions& options)
      : grid_(grid), rb_(rb), contacts_(contacts), options_(options), h_(grid.spacing), hmax_(h_.maxCoeff()) {}

  JointCenter root(const PlannedJoint& j) const {
    JointCenter c;
    double n = 0;
    for (int a : j.bones) {
      const double w = double(rb_.components[rb_.bones[a].comp].count);
      c.center += w * rb_.bones[a].centroid;
      n += w;
    }
    c.center /= n;
    c.method = "root centroid";
    return c;
  }

  JointCenter child(const PlannedJoint& j) const {
    JointCenter out;
    if (j.beyondContact) {  // no patches: the middle of the closest voxel centres
      out.center = 0.5 * (j.closestOnChild + j.closestOnParent);
      out.method = "closest points";
      return out;
    }
    const BoneContact* cn = findContact(contacts_, j.parentBone, j.childBone);  // child's voxels near the parent
    const BoneContact* pn = findContact(contacts_, j.childBone, j.parentBone);  // parent's voxels near the child
    const V3 cc = patch(cn), pc = patch(pn);
    out.center = (cc.allFinite() && pc.allFinite()) ? V3(0.5 * (cc + pc)) : (cc.allFinite() ? cc : pc);
    out.method = "contact centroid";
    const BallHint hint = ballHint(rb_.bones[j.childBone].anatomy);
    if (hint == BallHint::No || !cn || !cc.allFinite()) return out;
    SphereFit f = ball(j.childBone, cc);
    bool ok = f.ok && f.r >= options_.minBallRadiusMm && f.r <= options_.maxBallRadiusMm;
    if (ok && hint == BallHint::Unknown) ok = inSocket(f, pn);
    if (ok) {
      out.center = f.c;
      out.method = f.rms > 0 ? "sphere fit" : "inscribed ball";
      out.radiusMm = f.r;
      out.fitRmsMm = f.rms;
    }
    return out;
  }

private:
  V3 physical(std::size_t p) const {
    const int nx = grid_.dims[0], ny = grid_.dims[1];
    return grid_.indexToPhysical(V3(double(p % nx), double((p / nx) % ny), double(p / (std::size_t(nx) * ny))));
  }

  // Closest patch: voxels within one voxel of the closest distance.
  V3 patch(const BoneContact* c) const {
    V3 s = V3::Zero();
    int n = 0;
    if (c)
      for (const auto& [p, d] : c->near)
        if (d <= c->dmin + hmax_) {
          s += physical(p);
          ++n;
        }
    return n ? V3(s / n) : V3(V3::Constant(std::numeric_limits<double>::quiet_NaN()));
  }

  // The head: the largest ball inscribed in the child that reaches its contact patch (the neck
  // and shaft are thinner), refined by a sphere fit to the surface around it.
  SphereFit ball(int bone, const V3& cc) const {
    const RigBone& cb = rb_.bones[bone];
    const double reach = options_.maxBallRadiusMm + hmax_;
    std::vector<V3> surface;
    for (std::size_t p : cb.boundary) {
      const V3 x = physical(p);
      if ((x - cc).norm() <= 2 * reach) surface.push_back(x);
    }
    const V3 ci = grid_.physicalToIndex(cc);
    int lo[3], hi[3];
    for (int d = 0; d < 3; ++d) {
      const int r = int(std::ceil(reach / h_[d]));
      lo[d] = std::max(cb.lo[d], int(std::floor(ci[d])) - r);
      hi[d] = std::min(cb.hi[d], int(std::ceil(ci[d])) + r);
    }
    double bestRho = -1;
    std::vector<std::pair<double, V3>> balls;  // (inscribed radius, centre)
    for (int k = lo[2]; k <= hi[2]; ++k)
      for (int j = lo[1]; j <= hi[1]; ++j)
        for (int i = lo[0]; i <= hi[0]; ++i) {
          const int comp = rb_.componentOf[grid_.linearIndex(i, j, k)];
          if (comp < 0 || rb_.boneOfComponent[comp] != bone) continue;
          const V3 x = grid_.indexToPhysical(V3(i, j, k));
          const double toContact = (x - cc).norm();
          if (toContact > reach) continue;
          double rho = std::numeric_limits<double>::max();
          for (const V3& q : surface) rho = std::min(rho, (q - x).squaredNorm());
          rho = std::sqrt(rho);
          if (toContact > rho + 1.5 * hmax_) continue;  // this ball does not reach the contact
          balls.emplace_back(rho, x);
          bestRho = std::max(bestRho, rho);
        }
    SphereFit f;
    if (bestRho <= 0) return f;
    V3 c = V3::Zero();
    int n = 0;
    for (const auto& [rho, x] : balls)
      if (rho >= bestRho - 0.25 * h_.minCoeff()) {
        c += x;
        ++n;
      }
    c /= n;
    std::vector<V3> pts;
    for (const V3& q : surface)
      if ((q - c).norm() <= bestRho + 1.5 * hmax_) pts.push_back(q);
    f = fitSphere(pts, hmax_);
    const double tolerance = std::max(0.5 * h_.minCoeff(), 0.5 * hmax_);
    if (!f.ok || f.rms > tolerance || (f.c - c).norm() > bestRho) {
      f.ok = bestRho + 0.5 * h_.minCoeff() > 0;  // the fit failed: keep the inscribed ball
      f.c = c;
      f.r = bestRho + 0.5 * h_.minCoeff();
      f.rms = 0;
    }
    return f;
  }

  // Unrecognised bones: a ball joint needs a socket around the ball (the parent's patch at a
  // steady distance beyond the radius).
  bool inSocket(const SphereFit& f, const BoneContact* pn) const {
    if (!pn || pn->near.size() < 6) return false;
    double s = 0, s2 = 0;
    for (const auto& [p, d] : pn->near) {
      const double r = (physical(p) - f.c).norm();
      s += r;
      s2 += r * r;
    }
    const double n = double(pn->near.size()), mean = s / n, sd = std::sqrt(std::max(0.0, s2 / n - mean * mean));
    return mean > f.r && sd <= 0.5 * hmax_ + 0.1 * f.r;
  }

  const ImageGrid& grid_;
  const RigBones& rb_;
  const std::vector<std::vector<BoneContact>>& contacts_;
  const AutoRigOptions& options_;
  const V3 h_;
  const double hmax_;
};

}  // namespace

std::vector<JointCenter> findJointCenters(const ImageGrid& grid, const RigBones& bones,
                                          const std::vector<std::vector<BoneContact>>& contacts, const RigTree& tree,
                                          const AutoRigOptions& options) {
  const CenterFinder finder(grid, bones, contacts, options);
  std::vector<JointCenter> centers;
  for (const PlannedJoint& j : tree.joints) centers.push_back(j.parent < 0 ? finder.root(j) : finder.child(j));
  return centers;
}

}  // namespace repose
