#include "bone_path.h"

#include <Eigen/Geometry>
#include <stdexcept>
#include <string>

namespace repose {

namespace {

// Least-squares rigid motion carrying the points `from` onto `to` (3 by N each). Under three
// points the rotation is not determined: the mean displacement alone is kept.
Eigen::Isometry3d fitRigid(const Eigen::Matrix3Xd& from, const Eigen::Matrix3Xd& to) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  if (from.cols() == 0) return T;
  if (from.cols() < 3) {
    T.translation() = (to - from).rowwise().mean();
    return T;
  }
  T.matrix() = Eigen::umeyama(from, to, false);
  return T;
}

// The dual-quaternion blend of the identity (weight 1 - s) and q (weight s): rigid for every s.
Eigen::Isometry3d blendFromIdentity(const DualQuaternion& q, double s) {
  DualQuaternion b;
  b.real.coeffs() = s * q.real.coeffs();
  b.real.w() += 1.0 - s;
  b.dual.coeffs() = s * q.dual.coeffs();
  return b.toIsometry();
}

}  // namespace

BonePath::BonePath(const Points& rest, const Points& posed, const std::vector<int>& fixedBone,
                   const std::vector<int>& boneParents)
    : rest_(rest), posed_(posed), fixedBone_(fixedBone) {
  int bones = 0;
  Eigen::Index fixedCount = 0;
  for (int b : fixedBone) {
    bones = std::max(bones, b + 1);
    fixedCount += b >= 0;
  }
  if (!boneParents.empty() && int(boneParents.size()) < bones)
    throw std::invalid_argument("BonePath: " + std::to_string(boneParents.size()) + " bone parents for " +
                                std::to_string(bones) + " bones");
  std::vector<std::vector<int>> nodes(static_cast<std::size_t>(bones));
  Eigen::Matrix3Xd allFrom(3, fixedCount), allTo(3, fixedCount);
  Eigen::Index k = 0;
  for (std::size_t v = 0; v < fixedBone.size(); ++v) {
    if (fixedBone[v] < 0) continue;
    nodes[static_cast<std::size_t>(fixedBone[v])].push_back(int(v));
    allFrom.col(k) = rest.row(Eigen::Index(v)).transpose();
    allTo.col(k++) = posed.row(Eigen::Index(v)).transpose();
  }
  global_ = fitRigid(allFrom, allTo);
  std::vector<Eigen::Isometry3d> absolute(static_cast<std::size_t>(bones));
  for (int b = 0; b < bones; ++b) {
    const std::vector<int>& list = nodes[static_cast<std::size_t>(b)];
    Eigen::Matrix3Xd from(3, Eigen::Index(list.size())), to(3, Eigen::Index(list.size()));
    for (std::size_t i = 0; i < list.size(); ++i) {
      from.col(Eigen::Index(i)) = rest.row(list[i]).transpose();
      to.col(Eigen::Index(i)) = posed.row(list[i]).transpose();
    }
    absolute[static_cast<std::size_t>(b)] = list.empty() ? global_ : fitRigid(from, to);
  }

  // Each bone follows its nearest ancestor (bones are numbered as in the hierarchy, which may
  // hold more joints than bones on the path); the order puts parents first.
  parent_.assign(static_cast<std::size_t>(bones), -1);
  for (int b = 0; b < bones && !boneParents.empty(); ++b) {
    int p = boneParents[static_cast<std::size_t>(b)], steps = 0;
    while (p >= bones && steps++ < int(boneParents.size())) p = boneParents[static_cast<std::size_t>(p)];
    if (p >= bones || p == b) throw std::invalid_argument("BonePath: bone parents have a cycle");
    parent_[static_cast<std::size_t>(b)] = p;
  }
  std::vector<char> placed(static_cast<std::size_t>(bones), 0);
  for (int pass = 0; int(order_.size()) < bones; ++pass) {
    if (pass > bones) throw std::invalid_argument("BonePath: bone parents have a cycle");
    for (int b = 0; b < bones; ++b) {
      const int p = parent_[static_cast<std::size_t>(b)];
      if (!placed[static_cast<std::size_t>(b)] && (p < 0 || placed[static_cast<std::size_t>(p)])) {
        placed[static_cast<std::size_t>(b)] = 1;
        order_.push_back(b);
      }
    }
  }
  for (int b : order_)  // a bone without nodes moves with its parent
    if (nodes[static_cast<std::size_t>(b)].empty() && parent_[static_cast<std::size_t>(b)] >= 0)
      absolute[static_cast<std::size_t>(b)] = absolute[static_cast<std::size_t>(parent_[static_cast<std::size_t>(b)])];
  relative_.resize(static_cast<std::size_t>(bones));
  for (int b = 0; b < bones; ++b) {
    const int p = parent_[static_cast<std::size_t>(b)];
    const Eigen::Isometry3d base = p < 0 ? global_ : absolute[static_cast<std::size_t>(p)];
    DualQuaternion q = DualQuaternion::fromIsometry(base.inverse() * absolute[static_cast<std::size_t>(b)]);
    if (q.real.w() < 0) {  // the shorter way round
      q.real.coeffs() = -q.real.coeffs();
      q.dual.coeffs() = -q.dual.coeffs();
    }
    relative_[static_cast<std::size_t>(b)] = q;
  }
  // What the composed path misses at s = 1 (rounding, or a node that does not move rigidly).
  const std::vector<Eigen::Isometry3d> end = bonesAt(1.0);
  remainder_ = Points::Zero(rest.rows(), 3);
  for (std::size_t v = 0; v < fixedBone.size(); ++v)
    if (fixedBone[v] >= 0)
      remainder_.row(Eigen::Index(v)) =
          posed.row(Eigen::Index(v)) -
          (end[static_cast<std::size_t>(fixedBone[v])] * Eigen::Vector3d(rest.row(Eigen::Index(v)).transpose())).transpose();
}

std::vector<Eigen::Isometry3d> BonePath::bonesAt(double s) const {
  std::vector<Eigen::Isometry3d> T(relative_.size());
  for (int b : order_) {
    const int p = parent_[static_cast<std::size_t>(b)];
    T[static_cast<std::size_t>(b)] = (p < 0 ? global_ : T[static_cast<std::size_t>(p)]) *
                                     blendFromIdentity(relative_[static_cast<std::size_t>(b)], s);
  }
  return T;
}

void BonePath::place(double s, const std::vector<int>& nodes, Points& x) const {
  if (s >= 1.0) {
    for (int v : nodes) x.row(v) = posed_.row(v);
    return;
  }
  const std::vector<Eigen::Isometry3d> T = bonesAt(s);
  for (int v : nodes)
    x.row(v) = (T[static_cast<std::size_t>(fixedBone_[static_cast<std::size_t>(v)])] *
                    Eigen::Vector3d(rest_.row(v).transpose()) +
                s * remainder_.row(v).transpose())
                   .transpose();
}

}  // namespace repose
