#include "pose_controller.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <stdexcept>

namespace repose {
namespace {

constexpr double kDeg = M_PI / 180.0;

bool contains(const std::string& name, const char* word) {
  std::string lower = name;
  std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return std::tolower(c); });
  return lower.find(word) != std::string::npos;
}

/// Generous anatomical ranges (the sign of flexion depends on the side, so ranges are symmetric).
AngleLimits limitsFor(const Joint& joint) {
  using V = Eigen::Vector3d;
  if (joint.parent < 0) return {V(-180, -90, -180), V(180, 90, 180)};
  if (contains(joint.name, "knee") || contains(joint.name, "elbow") || contains(joint.name, "forearm") ||
      contains(joint.name, "tibia"))
    return {V(-150, -15, -45), V(150, 15, 45)};
  if (contains(joint.name, "spine") || contains(joint.name, "neck") || contains(joint.name, "vertebra") ||
      contains(joint.name, "head") || contains(joint.name, "skull"))
    return {V(-60, -45, -60), V(60, 45, 60)};
  if (contains(joint.name, "ankle") || contains(joint.name, "foot") || contains(joint.name, "wrist") ||
      contains(joint.name, "hand"))
    return {V(-60, -45, -45), V(60, 45, 45)};
  return {V(-150, -90, -90), V(150, 90, 90)};
}

}  // namespace

Eigen::Quaterniond quaternionFromAngles(const Eigen::Vector3d& d) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(d.z() * kDeg, Eigen::Vector3d::UnitZ()) *
                            Eigen::AngleAxisd(d.y() * kDeg, Eigen::Vector3d::UnitY()) *
                            Eigen::AngleAxisd(d.x() * kDeg, Eigen::Vector3d::UnitX()));
}

Eigen::Vector3d anglesFromQuaternion(const Eigen::Quaterniond& q) {
  const Eigen::Matrix3d R = q.normalized().toRotationMatrix();
  const double y = std::asin(std::clamp(-R(2, 0), -1.0, 1.0));
  double x, z;
  if (std::fabs(R(2, 0)) < 1 - 1e-9) {
    x = std::atan2(R(2, 1), R(2, 2));
    z = std::atan2(R(1, 0), R(0, 0));
  } else {  // gimbal lock: put everything in z
    x = 0;
    z = std::atan2(-R(0, 1), R(1, 1));
  }
  return Eigen::Vector3d(x, y, z) / kDeg;
}

bool PoseController::State::operator==(const State& o) const {
  if (rotations.size() != o.rotations.size() || translation != o.translation) return false;
  for (std::size_t i = 0; i < rotations.size(); ++i)
    if (!rotations[i].coeffs().isApprox(o.rotations[i].coeffs(), 1e-12) &&
        !rotations[i].coeffs().isApprox(-o.rotations[i].coeffs(), 1e-12))
      return false;
  return true;
}

PoseController::PoseController(QObject* parent) : QObject(parent) {}

void PoseController::setSkeleton(const Skeleton& skeleton) {
  skeleton_ = skeleton;
  limits_.clear();
  for (const Joint& j : skeleton_.joints) limits_.push_back(limitsFor(j));
  state_ = State();
  state_.rotations.assign(skeleton_.size(), Eigen::Quaterniond::Identity());
  undo_.clear();
  redo_.clear();
  editDepth_ = 0;
  emit poseChanged();
  emit historyChanged();
}

void PoseController::checkJoint(int joint) const {
  if (joint < 0 || joint >= jointCount())
    throw std::invalid_argument("no joint " + std::to_string(joint) + " (the skeleton has " +
                                std::to_string(jointCount()) + ")");
}

Eigen::Vector3d PoseController::angles(int joint) const {
  checkJoint(joint);
  return anglesFromQuaternion(state_.rotations[std::size_t(joint)]);
}

AngleLimits PoseController::limits(int joint) const {
  checkJoint(joint);
  return limits_[std::size_t(joint)];
}

Pose PoseController::pose() const {
  Pose p;
  p.translation = state_.translation;
  for (std::size_t j = 0; j < state_.rotations.size(); ++j)
    if (!state_.rotations[j].isApprox(Eigen::Quaterniond::Identity(), 1e-12))
      p.rotations[skeleton_.joints[j].name] = state_.rotations[j];
  return p;
}

std::vector<Eigen::Isometry3d> PoseController::globalTransforms() const { return forwardKinematics(skeleton_, pose()); }

void PoseController::apply(const State& next, bool record) {
  if (next == state_) return;
  if (editDepth_ == 0 && record) {
    undo_.push_back(state_);
    redo_.clear();
  }
  state_ = next;
  emit poseChanged();
  if (editDepth_ == 0 && record) emit historyChanged();
}

void PoseController::setAngles(int joint, const Eigen::Vector3d& degrees) {
  checkJoint(joint);
  const AngleLimits& l = limits_[std::size_t(joint)];
  const Eigen::Vector3d clamped = degrees.cwiseMax(l.lower).cwiseMin(l.upper);
  State next = state_;
  next.rotations[std::size_t(joint)] = quaternionFromAngles(clamped);
  apply(next);
}

void PoseController::rotateInWorld(int joint, const Eigen::Quaterniond& worldDelta) {
  checkJoint(joint);
  // G_j = G_p T(c) R_j T(-c): rotating the posed bone by D gives R_j' = rot(G_p)^-1 D rot(G_p) R_j.
  Eigen::Quaterniond parent = Eigen::Quaterniond::Identity();
  const int p = skeleton_.joints[std::size_t(joint)].parent;
  if (p >= 0) parent = Eigen::Quaterniond(globalTransforms()[std::size_t(p)].rotation());
  const Eigen::Quaterniond local = parent.inverse() * worldDelta * parent * state_.rotations[std::size_t(joint)];
  setAngles(joint, anglesFromQuaternion(local));
}

void PoseController::resetJoint(int joint) {
  checkJoint(joint);
  State next = state_;
  next.rotations[std::size_t(joint)] = Eigen::Quaterniond::Identity();
  if (skeleton_.joints[std::size_t(joint)].parent < 0) next.translation.setZero();
  apply(next);
}

void PoseController::resetAll() {
  State next = state_;
  next.rotations.assign(skeleton_.size(), Eigen::Quaterniond::Identity());
  next.translation.setZero();
  apply(next);
}

void PoseController::setPose(const Pose& pose, bool recordHistory) {
  validatePose(pose, skeleton_);
  State next;
  next.rotations.assign(skeleton_.size(), Eigen::Quaterniond::Identity());
  next.translation = pose.translation;
  for (const auto& [name, q] : pose.rotations) next.rotations[std::size_t(skeleton_.find(name))] = q.normalized();
  apply(next, recordHistory);
}

void PoseController::beginEdit() {
  if (editDepth_++ == 0) editStart_ = state_;
}

void PoseController::endEdit() {
  if (editDepth_ == 0) return;
  if (--editDepth_ > 0) return;
  if (!(editStart_ == state_)) {
    undo_.push_back(editStart_);
    redo_.clear();
    emit historyChanged();
  }
  emit editFinished();
}

void PoseController::undo() {
  if (undo_.empty() || editDepth_ > 0) return;
  redo_.push_back(state_);
  state_ = undo_.back();
  undo_.pop_back();
  emit poseChanged();
  emit historyChanged();
}

void PoseController::redo() {
  if (redo_.empty() || editDepth_ > 0) return;
  undo_.push_back(state_);
  state_ = redo_.back();
  redo_.pop_back();
  emit poseChanged();
  emit historyChanged();
}

}  // namespace repose
