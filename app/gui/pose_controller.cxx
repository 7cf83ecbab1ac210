#include "pose_controller.h"

#include <stdexcept>

namespace repose {

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
  classes_.clear();
  limits_.clear();
  for (const Joint& j : skeleton_.joints) {
    classes_.push_back(classifyJoint(j.name, j.parent < 0));
    limits_.push_back(jointLimits(classes_.back()));
  }
  state_ = State();
  state_.rotations.assign(skeleton_.size(), Eigen::Quaterniond::Identity());
  saved_ = state_;
  fromClip_ = false;
  undo_.clear();
  redo_.clear();
  editDepth_ = 0;
  // Joint indices of the old skeleton are void from here: whoever keeps them rebuilds first.
  emit skeletonChanged();
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
  return anatomicalAngles(state_.rotations[std::size_t(joint)], classes_[std::size_t(joint)]);
}

JointLimits PoseController::limits(int joint) const {
  checkJoint(joint);
  return limits_[std::size_t(joint)];
}

const JointClass& PoseController::jointClass(int joint) const {
  checkJoint(joint);
  return classes_[std::size_t(joint)];
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

bool PoseController::atRest() const {
  State rest;
  rest.rotations.assign(skeleton_.size(), Eigen::Quaterniond::Identity());
  return state_ == rest;
}

bool PoseController::hasUnsavedPose() const { return !fromClip_ && !(state_ == saved_); }

bool PoseController::isHandPose() const { return !fromClip_ && !atRest(); }

void PoseController::markSaved() {
  saved_ = state_;
  fromClip_ = false;
}

void PoseController::apply(const State& next, bool record) {
  if (next == state_) return;
  // A clip's first frame over a hand pose keeps that pose one undo away; later frames are not steps.
  const bool step = editDepth_ == 0 && (record || (!fromClip_ && !atRest()));
  if (step) {
    undo_.push_back(state_);
    redo_.clear();
  }
  state_ = next;
  fromClip_ = !record;
  emit poseChanged();
  if (step) emit historyChanged();
}

void PoseController::setAngles(int joint, const Eigen::Vector3d& degrees) {
  checkJoint(joint);
  const std::size_t j = std::size_t(joint);
  State next = state_;
  next.rotations[j] = rotationFromAnatomicalAngles(limits_[j].clamp(degrees), classes_[j]);
  apply(next);
}

void PoseController::rotateInWorld(int joint, const Eigen::Quaterniond& worldDelta) {
  checkJoint(joint);
  // G_j = G_p T(c) R_j T(-c): rotating the posed bone by D gives R_j' = rot(G_p)^-1 D rot(G_p) R_j.
  Eigen::Quaterniond parent = Eigen::Quaterniond::Identity();
  const int p = skeleton_.joints[std::size_t(joint)].parent;
  if (p >= 0) parent = Eigen::Quaterniond(globalTransforms()[std::size_t(p)].rotation());
  const Eigen::Quaterniond local = parent.inverse() * worldDelta * parent * state_.rotations[std::size_t(joint)];
  setAngles(joint, anatomicalAngles(local, classes_[std::size_t(joint)]));
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

void PoseController::restore(std::vector<State>& from, std::vector<State>& to) {
  if (from.empty() || editDepth_ > 0) return;
  to.push_back(state_);
  state_ = from.back();
  from.pop_back();
  fromClip_ = false;
  emit poseChanged();
  emit historyChanged();
}

void PoseController::undo() { restore(undo_, redo_); }

void PoseController::redo() { restore(redo_, undo_); }

}  // namespace repose
