#pragma once
// The pose being edited: one rotation per joint (about its rest centre, rest-frame axes, as in
// pose.json), the root translation, joint limits and an undo/redo stack. No widgets: the joint
// panel, the 3D view's drag and the animation timeline all edit the pose through this class.
// Angles are anatomical (anatomical_angles.h: flexion, abduction, rotation with clinical signs) and
// clamped to the joint's range (joint_limits.h) on interactive edits.
#include <vector>

#include <Eigen/Geometry>
#include <QObject>

#include "anatomical_angles.h"
#include "joint_limits.h"
#include "pose.h"
#include "skeleton.h"

namespace repose {

class PoseController : public QObject {
  Q_OBJECT
public:
  explicit PoseController(QObject* parent = nullptr);

  /// Starts over at the rest pose with an empty history. Emits skeletonChanged() first (views that
  /// hold joint indices rebuild), then poseChanged().
  void setSkeleton(const Skeleton& skeleton);
  const Skeleton& skeleton() const { return skeleton_; }
  int jointCount() const { return int(skeleton_.size()); }

  /// Anatomical angles of a joint, degrees (flexion, abduction, rotation; see anatomical_angles.h).
  Eigen::Vector3d angles(int joint) const;
  JointLimits limits(int joint) const;
  const JointClass& jointClass(int joint) const;
  Eigen::Quaterniond rotation(int joint) const { return state_.rotations.at(std::size_t(joint)); }
  /// The pose as pose.json holds it (only joints away from rest are named).
  Pose pose() const;
  /// Global rest -> posed transform of every joint (forward kinematics).
  std::vector<Eigen::Isometry3d> globalTransforms() const;
  bool atRest() const;

  // --- edits (each one undo step unless inside beginEdit/endEdit) ------------------------------
  /// Sets a joint's anatomical angles, clamped to its limits.
  void setAngles(int joint, const Eigen::Vector3d& degrees);
  /// Rotates a posed bone by `worldDelta` (posed frame) about its joint: what a drag does. The
  /// result is clamped to the joint's limits.
  void rotateInWorld(int joint, const Eigen::Quaterniond& worldDelta);
  void resetJoint(int joint);
  void resetAll();
  /// Replaces the whole pose (loaded pose.json, an animation frame); throws std::invalid_argument
  /// on a joint the skeleton lacks. Animation frames pass recordHistory = false: they are no undo
  /// steps, except the first one over a hand pose (undo then brings the hand pose back).
  void setPose(const Pose& pose, bool recordHistory = true);
  /// Groups every edit until endEdit() into one undo step (a slider or mouse drag).
  void beginEdit();
  void endEdit();
  bool editing() const { return editDepth_ > 0; }

  bool canUndo() const { return !undo_.empty(); }
  bool canRedo() const { return !redo_.empty(); }
  void undo();
  void redo();

  /// True when the pose was made by hand (edits, undo, a loaded file) and differs from the last
  /// saved one; a pose shown from a motion clip is not the user's work. setSkeleton() and
  /// markSaved() start clean.
  bool hasUnsavedPose() const;
  /// True when the pose is the user's, not the rest pose and not a clip frame (a clip would replace it).
  bool isHandPose() const;
  void markSaved();

signals:
  void skeletonChanged();
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
  void restore(std::vector<State>& from, std::vector<State>& to);  // undo / redo

  Skeleton skeleton_;
  std::vector<JointClass> classes_;
  std::vector<JointLimits> limits_;
  State state_, editStart_, saved_;
  bool fromClip_ = false;  // the state was set by setPose(..., false)
  int editDepth_ = 0;
  std::vector<State> undo_, redo_;
};

}  // namespace repose
