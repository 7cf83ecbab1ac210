#include "retarget.h"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace repose {
namespace {

[[noreturn]] void fail(const std::string& message) { throw std::invalid_argument("retarget: " + message); }

// Orthonormal frame whose first column is `primary` and whose third is `up` made orthogonal to it.
bool frameFrom(const Eigen::Vector3d& primary, const Eigen::Vector3d& up, Eigen::Matrix3d& frame) {
  const Eigen::Vector3d e1 = primary.normalized();
  Eigen::Vector3d e3 = up - up.dot(e1) * e1;
  if (e3.norm() < 1e-6 * up.norm()) return false;
  e3.normalize();
  frame.col(0) = e1;
  frame.col(1) = e3.cross(e1);
  frame.col(2) = e3;
  return true;
}

// Minimal rotation taking direction a onto direction b (any perpendicular axis when opposite).
Eigen::Matrix3d minimalRotation(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return Eigen::Quaterniond::FromTwoVectors(a, b).toRotationMatrix();
}

// The same axis, `fraction` of the angle.
Eigen::Matrix3d rotationPower(const Eigen::Matrix3d& r, double fraction) {
  if (fraction == 1.0) return r;
  Eigen::AngleAxisd aa(r);
  aa.angle() *= fraction;
  return aa.toRotationMatrix();
}

constexpr double kTiny = 1e-9;

// The clip's axial chain: its root and every joint on the way to the highest point of its rest pose
// (the top of the head, whether the rest pose is a T-pose or arms down).
std::vector<bool> axialChain(const BvhMotion& motion) {
  const std::vector<Eigen::Isometry3d> rest = bvhRestPose(motion);
  int top = 0;
  double highest = -std::numeric_limits<double>::infinity();
  for (std::size_t j = 0; j < rest.size(); ++j) {
    const BvhJoint& joint = motion.joints[j];
    const double y = joint.hasEndSite ? (rest[j] * joint.endSite).y() : rest[j].translation().y();
    if (y > highest) highest = y, top = int(j);
  }
  std::vector<bool> axial(motion.joints.size(), false);
  for (int j = top; j >= 0; j = motion.joints[j].parent) axial[j] = true;
  return axial;
}

}  // namespace

RetargetMode parseRetargetMode(const std::string& name) {
  if (name == "direction") return RetargetMode::Direction;
  if (name == "relative") return RetargetMode::Relative;
  throw std::invalid_argument("unknown retarget mode '" + name + "' (expected direction or relative)");
}

Eigen::Matrix3d bvhToLps() {
  Eigen::Matrix3d m;
  m << 1, 0, 0,  //
      0, 0, -1,  //
      0, 1, 0;
  return m;
}

BvhRetargeter::BvhRetargeter(const BvhMotion& motion, const Skeleton& skeleton, const BvhJointMap& map,
                             const RetargetOptions& options)
    : motion_(motion), skeleton_(skeleton), options_(options) {
  if (!(options.unitScaleMm >= 0) || !std::isfinite(options.unitScaleMm))
    fail("unitScaleMm must be a positive number of millimetres per BVH unit (or 0 to infer it)");
  if (motion.joints.empty()) fail("the BVH clip has no joints");
  if (motion.frameCount <= 0) fail("the BVH clip has no frames");
  if (options.referenceFrame < 0 || options.referenceFrame >= motion.frameCount)
    fail("reference frame " + std::to_string(options.referenceFrame) + " is out of range (the clip has " +
         std::to_string(motion.frameCount) + " frames)");
  units_ = options.unitScaleMm > 0 ? BvhUnits{options.unitScaleMm, "given", "", 0} : inferBvhUnits(motion);
  const int n = int(skeleton.size());
  for (int j = 0; j < n; ++j)
    if (skeleton.joints[j].parent >= j) fail("skeleton joints must be stored parents first");
  if (map.empty()) fail("the joint map is empty");

  drive_.assign(n, Drive::None);
  bvhOf_.assign(n, -1);
  factors_.assign(n, {});
  for (const auto& [bvhName, jointName] : map.joints) {
    const int b = motion.find(bvhName);
    if (b < 0) fail("the joint map names BVH joint '" + bvhName + "', which the clip does not have");
    const int s = skeleton.find(jointName);
    if (s < 0) fail("the joint map names skeleton joint '" + jointName + "', which the skeleton does not have");
    if (bvhOf_[s] >= 0)
      fail("the joint map maps both '" + motion.joints[bvhOf_[s]].name + "' and '" + bvhName +
           "' onto skeleton joint '" + jointName + "'");
    bvhOf_[s] = b;
    drive_[s] = s == 0 ? Drive::Body : Drive::Limb;
  }
  buildTrunkFactors(map);
  int driven = 0;
  for (int j = 1; j < n; ++j) driven += drive_[j] != Drive::None;
  if (driven == 0)
    fail("the clip drives no joint of the skeleton but its root '" + skeleton.joints[0].name +
         "' (the frames would only move the body as a whole): map the clip's joints onto the skeleton's, "
         "JSON {\"BVH joint\": \"skeleton joint\", ...}");
  buildAlignments();

  translationJoint_ = bvhOf_[0] >= 0 ? bvhOf_[0] : 0;
  const std::vector<Eigen::Isometry3d> ref = bvhGlobalPose(motion, options.referenceFrame);
  refRootPosition_ = ref[translationJoint_].translation();
  const Eigen::Matrix3d M = bvhToLps();
  refRotation_.resize(ref.size());
  for (std::size_t b = 0; b < ref.size(); ++b) refRotation_[b] = M * ref[b].linear() * M.transpose();
}

// Shares of the map, and joints mapped onto the clip's axial chain (spine, neck, head): both bend
// with the clip's rotation between their BVH joint and the BVH joint below them.
void BvhRetargeter::buildTrunkFactors(const BvhJointMap& map) {
  for (const auto& [jointName, shares] : map.shares) {
    const int s = skeleton_.find(jointName);
    if (s < 0) fail("the joint map names skeleton joint '" + jointName + "', which the skeleton does not have");
    if (bvhOf_[s] >= 0) fail("skeleton joint '" + jointName + "' both follows a BVH joint and takes shares");
    for (const BvhShare& share : shares) {
      const int b = motion_.find(share.bvhJoint);
      if (b < 0) fail("the joint map names BVH joint '" + share.bvhJoint + "', which the clip does not have");
      if (!(share.fraction >= 0) || !std::isfinite(share.fraction))
        fail("the share of '" + share.bvhJoint + "' for '" + jointName + "' must be a fraction >= 0");
      factors_[s].push_back({motion_.joints[b].parent, b, share.fraction});
    }
    if (!factors_[s].empty()) drive_[s] = Drive::Trunk;
  }
  const std::vector<bool> axial = axialChain(motion_);
  for (int s = 1; s < int(skeleton_.size()); ++s) {
    if (drive_[s] != Drive::Limb || !axial[bvhOf_[s]]) continue;
    int a = skeleton_.joints[s].parent;
    while (a >= 0 && drive_[a] == Drive::None) a = skeleton_.joints[a].parent;
    const int from = a < 0 ? -1 : bvhOf_[a] >= 0 ? bvhOf_[a] : factors_[a].empty() ? -1 : factors_[a].back().to;
    factors_[s] = {{from, bvhOf_[s], 1.0}};
    drive_[s] = Drive::Trunk;
  }
}

void BvhRetargeter::buildAlignments() {
  const int n = int(skeleton_.size());
  std::vector<std::vector<int>> children(n);
  for (int j = 1; j < n; ++j) children[skeleton_.joints[j].parent].push_back(j);
  const Eigen::Matrix3d M = bvhToLps();
  const std::vector<Eigen::Isometry3d> rest = bvhRestPose(motion_);
  auto bvhPos = [&](int j) -> Eigen::Vector3d { return M * rest[bvhOf_[j]].translation(); };
  auto centre = [&](int j) -> const Eigen::Vector3d& { return skeleton_.joints[j].center; };
  // Nearest descendants that follow a limb BVH joint, reached through undriven joints.
  auto limbDescendants = [&](int j) {
    std::vector<int> found, todo(children[j].rbegin(), children[j].rend());
    while (!todo.empty()) {
      const int k = todo.back();
      todo.pop_back();
      if (drive_[k] == Drive::Limb) found.push_back(k);
      else if (drive_[k] == Drive::None) todo.insert(todo.end(), children[k].rbegin(), children[k].rend());
    }
    return found;
  };

  mainChild_.assign(n, -1);
  lateralLeft_.assign(n, -1);
  lateralRight_.assign(n, -1);
  restDirBvh_.assign(n, Eigen::Vector3d::Zero());
  restAlign_.assign(n, Eigen::Matrix3d::Identity());
  for (int j = 0; j < n; ++j) {
    if (drive_[j] != Drive::Body && drive_[j] != Drive::Limb) continue;
    const std::vector<int> candidates = limbDescendants(j);
    if (drive_[j] == Drive::Body && candidates.size() >= 2) {
      // The pelvis: align the left-right axis between its outermost children and the vertical.
      int left = candidates[0], right = candidates[0];
      for (int k : candidates) {
        if (centre(k).x() > centre(left).x()) left = k;
        if (centre(k).x() < centre(right).x()) right = k;
      }
      const Eigen::Vector3d u0 = centre(left) - centre(right);
      const Eigen::Vector3d a0 = bvhPos(left) - bvhPos(right);
      Eigen::Matrix3d frameScan, frameBvh;
      const Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
      if (u0.norm() > kTiny && a0.norm() > kTiny && frameFrom(u0, up, frameScan) && frameFrom(a0, up, frameBvh)) {
        lateralLeft_[j] = left;
        lateralRight_[j] = right;
        restDirBvh_[j] = a0.normalized();
        restAlign_[j] = frameBvh * frameScan.transpose();
        bodyAlign_ = restAlign_[j];
        continue;
      }
    }
    // Main child: the one best continuing the incoming bone (the first one for a root).
    int best = candidates.empty() ? -1 : candidates[0];
    const int p = skeleton_.joints[j].parent;
    if (best >= 0 && p >= 0 && (centre(j) - centre(p)).norm() > kTiny) {
      const Eigen::Vector3d incoming = (centre(j) - centre(p)).normalized();
      double bestScore = -2;
      for (int k : candidates) {
        const Eigen::Vector3d d = centre(k) - centre(j);
        if (d.norm() <= kTiny) continue;
        if (d.normalized().dot(incoming) > bestScore) bestScore = d.normalized().dot(incoming), best = k;
      }
    }
    const Eigen::Vector3d u0 = best >= 0 ? Eigen::Vector3d(centre(best) - centre(j)) : Eigen::Vector3d::Zero();
    const Eigen::Vector3d a0 = best >= 0 ? Eigen::Vector3d(bvhPos(best) - bvhPos(j)) : Eigen::Vector3d::Zero();
    if (u0.norm() > kTiny && a0.norm() > kTiny) {
      mainChild_[j] = best;
      restDirBvh_[j] = a0.normalized();
      restAlign_[j] = minimalRotation(u0, a0);
      if (drive_[j] == Drive::Body) bodyAlign_ = restAlign_[j];
    } else if (drive_[j] == Drive::Limb) {
      // A limb end (foot, hand): its limb's alignment, so it keeps its angle to the bone it hangs from
      // as the clip's does. Beneath the trunk, the body's alignment.
      drive_[j] = Drive::LimbEnd;
      int a = p;
      while (a >= 0 && drive_[a] == Drive::None) a = skeleton_.joints[a].parent;
      restAlign_[j] = a >= 0 && (drive_[a] == Drive::Limb || drive_[a] == Drive::LimbEnd) ? restAlign_[a] : bodyAlign_;
    }
  }
}

std::vector<Eigen::Matrix3d> BvhRetargeter::clipRotations(const std::vector<Eigen::Isometry3d>& bvh) const {
  const Eigen::Matrix3d M = bvhToLps();
  std::vector<Eigen::Matrix3d> t(bvh.size());
  for (std::size_t b = 0; b < bvh.size(); ++b) {
    t[b] = M * bvh[b].linear() * M.transpose();
    if (options_.mode == RetargetMode::Relative) t[b] = t[b] * refRotation_[b].transpose();
  }
  return t;
}

Pose BvhRetargeter::pose(int frame) const {
  if (frame < 0 || frame >= motion_.frameCount)
    fail("frame " + std::to_string(frame) + " is out of range (the clip has " + std::to_string(motion_.frameCount) +
         " frames)");
  const std::vector<Eigen::Isometry3d> bvh = bvhGlobalPose(motion_, frame);
  const std::vector<Eigen::Matrix3d> T = clipRotations(bvh);
  const Eigen::Matrix3d M = bvhToLps();
  const bool direction = options_.mode == RetargetMode::Direction;
  auto bvhPos = [&](int j) -> Eigen::Vector3d { return M * bvh[bvhOf_[j]].translation(); };
  const int n = int(skeleton_.size());
  std::vector<Eigen::Matrix3d> global(n, Eigen::Matrix3d::Identity());
  for (int j = 0; j < n; ++j) {
    const int p = skeleton_.joints[j].parent;
    const Eigen::Matrix3d parent = p >= 0 ? global[p] : Eigen::Matrix3d::Identity();
    const int b = bvhOf_[j];
    switch (drive_[j]) {
      case Drive::None:
        global[j] = parent;
        break;
      case Drive::Trunk: {
        Eigen::Matrix3d bend = Eigen::Matrix3d::Identity();
        for (const Factor& f : factors_[j])
          bend = bend * rotationPower(f.from < 0 ? T[f.to] : Eigen::Matrix3d(T[f.from].transpose() * T[f.to]), f.weight);
        global[j] = parent * (direction ? Eigen::Matrix3d(bodyAlign_.transpose() * bend * bodyAlign_) : bend);
        break;
      }
      case Drive::LimbEnd:
        global[j] = direction ? Eigen::Matrix3d(T[b] * restAlign_[j]) : T[b];
        break;
      case Drive::Body:
      case Drive::Limb: {
        if (!direction) {
          global[j] = T[b];
          break;
        }
        // Swing the BVH bone's rest direction, as carried by T, onto the frame's actual bone direction
        // (they differ when unmapped BVH joints lie between), keeping T's twist.
        Eigen::Vector3d a1 = Eigen::Vector3d::Zero();
        if (lateralLeft_[j] >= 0) a1 = bvhPos(lateralLeft_[j]) - bvhPos(lateralRight_[j]);
        else if (mainChild_[j] >= 0) a1 = bvhPos(mainChild_[j]) - bvhPos(j);
        const Eigen::Vector3d carried = T[b] * restDirBvh_[j];
        global[j] = a1.norm() > kTiny ? Eigen::Matrix3d(minimalRotation(carried, a1) * T[b] * restAlign_[j])
                                      : Eigen::Matrix3d(T[b] * restAlign_[j]);
        break;
      }
    }
  }
  Pose pose;
  for (int j = 0; j < n; ++j) {
    if (drive_[j] == Drive::None) continue;  // identity local rotation: follows its parent
    const int p = skeleton_.joints[j].parent;
    const Eigen::Matrix3d local = p >= 0 ? Eigen::Matrix3d(global[p].transpose() * global[j]) : global[j];
    pose.rotations[skeleton_.joints[j].name] = Eigen::Quaterniond(local).normalized();
  }
  if (options_.translateRoot)
    pose.translation = units_.mmPerUnit * (M * (bvh[translationJoint_].translation() - refRootPosition_));
  return pose;
}

Pose retargetBvhFrame(const BvhMotion& motion, const Skeleton& skeleton, const BvhJointMap& map, int frame,
                      const RetargetOptions& options) {
  return BvhRetargeter(motion, skeleton, map, options).pose(frame);
}

}  // namespace repose
