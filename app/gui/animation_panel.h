#pragma once
// Motion capture playback: a BVH clip retargeted onto the case's skeleton (default CMU joint map or
// a map file), a timeline slider, play/pause (in real time: frames are skipped when posing is
// slower than the clip) and frame steps. Emits the pose of every shown frame. "Keep root in place"
// (on by default) drops the clip's root translation, so a walk stays in view; "Camera follows"
// asks the 3D view to move with the body when the root does travel.
#include <memory>

#include <QElapsedTimer>
#include <QWidget>

#include "pose.h"
#include "retarget.h"
#include "skeleton.h"

class QCheckBox;
class QLabel;
class QPushButton;
class QSlider;
class QTimer;
class QToolButton;

namespace repose {

class AnimationPanel : public QWidget {
  Q_OBJECT
public:
  explicit AnimationPanel(QWidget* parent = nullptr);
  ~AnimationPanel() override;

  void setSkeleton(const Skeleton& skeleton);  ///< drops the clip
  /// Loads and retargets a clip; `mapPath` empty = built-in CMU map. Throws std::runtime_error
  /// naming the file on failure.
  void loadClip(const QString& bvhPath, const QString& mapPath);
  bool hasClip() const { return bool(retargeter_); }
  int frameCount() const;
  int frame() const;
  double frameTime() const;
  /// The frame's pose; without root translation when the root is kept in place.
  Pose pose(int frame) const;
  QString clipName() const { return clipName_; }
  bool keepRootInPlace() const;
  void setKeepRootInPlace(bool keep);
  bool cameraFollows() const;
  void setCameraFollows(bool follow);

  void setFrame(int frame);
  void stepFrames(int delta);
  void play();
  void pause();
  bool playing() const;
  void togglePlay();

signals:
  void frameChanged(int frame);
  void playingChanged(bool playing);
  void loadRequested();
  void exportRequested();
  void cameraFollowChanged(bool follow);

private:
  void tick();
  void updateLabel();
  std::unique_ptr<BvhRetargeter> retargeter_;
  Skeleton skeleton_;
  double frameTime_ = 1.0 / 30;
  QString clipName_;
  QSlider* slider_;
  QToolButton *play_, *back_, *forward_;
  QPushButton *load_, *export_;
  QLabel* label_;
  QCheckBox *keepRoot_, *follow_;
  QTimer* timer_;
  QElapsedTimer clock_;
  int playStartFrame_ = 0;
};

}  // namespace repose
