#pragma once
// The pose being edited: one rotation per joint (about its rest centre, rest-frame axes, as in
// pose.json), the root translation, joint limits and an undo/redo stack. No widgets: the joint
// panel, the 3D view's drag and the animation timeline all edit the pose through this class.
#include <vector>

#include <Eigen/Geometry>
#include <QObject>

#include "pose.h"
#include "skeleton.h"

namespace repose {

/// Angles in degrees about the rest frame's axes (LPS: x left-right, y front-back, z foot-head),
/// applied x first: R = Rz(z) Ry(y) Rx(x).
Eigen::Quaterniond quaternionFromAngles(const Eigen::Vector3d& degrees);
/// Inverse of quaternionFromAngles with y in [-90, 90].
Eigen::Vector3d anglesFromQuaternion(const Eigen::Quaterniond& q);

struct AngleLimits {
  Eigen::Vector3d lower, upper;  ///< degrees per axis
};

class PoseController : public QObject {
  Q_OBJECT
public:
  explicit PoseController(QObject* parent = nullptr);

  /// Starts over at the rest pose with an empty history.
  void setSkeleton(const Skeleton& skeleton);
  const Skeleton& skeleton() const { return skeleton_; }
  int jointCount() const { return int(skeleton_.size()); }

  Eigen::Vector3d angles(int joint) const;
  AngleLimits limits(int joint) const;
  Eigen::Quaterniond rotation(int joint) const { return state_.rotations.at(std::size_t(joint)); }
  /// The pose as pose.json holds it (only joints away from rest are named).
  Pose pose() const;
  /// Global rest -> posed transform of every joint (forward kinematics).
  std::vector<Eigen::Isometry3d> globalTransforms() const;

  // --- edits (each one undo step unless inside beginEdit/endEdit) ------------------------------
  /// Sets a joint's angles, clamped to its limits.
  void setAngles(int joint, const Eigen::Vector3d& degrees);
  /// Rotates a posed bone by `worldDelta` (posed frame) about its joint: what a drag does. The
  /// result is clamped to the joint's limits.
  void rotateInWorld(int joint, const Eigen::Quaterniond& worldDelta);
  void resetJoint(int joint);
  void resetAll();
  /// Replaces the whole pose (loaded pose.json, an animation frame); throws std::invalid_argument
  /// on a joint the skeleton lacks. Animation frames pass recordHistory = false.
  void setPose(const Pose& pose, bool recordHistory = true);
  /// Groups every edit until endEdit() into one undo step (a slider or mouse drag).
  void beginEdit();
  void endEdit();
  bool editing() const { return editDepth_ > 0; }

  bool canUndo() const { return !undo_.empty(); }
  bool canRedo() const { return !redo_.empty(); }
  void undo();
  void redo();

signals:
  void poseChanged();
  void historyChanged();
  /// The outermost endEdit() ran (a drag ended), whether or not it changed the pose.
  void editFinished();

private:
  struct State {
    std::vector<Eigen::Quaterniond> rotations;
    Eigen::Vector3d translation = Eigen::Vector3d::Zero();
    bool operator==(const State& o) const;
  };
  void checkJoint(int joint) const;
  void apply(const State& next, bool record = true);  // records history and notifies

  Skeleton skeleton_;
  std::vector<AngleLimits> limits_;
  State state_, editStart_;
  int editDepth_ = 0;
  std::vector<State> undo_, redo_;
};

}  // namespace repose
