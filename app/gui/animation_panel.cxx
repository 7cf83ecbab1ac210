#include "animation_panel.h"

#include <QCheckBox>
#include <QFileInfo>
#include <QHBoxLayout>
#include <QLabel>
#include <QPushButton>
#include <QSlider>
#include <QStyle>
#include <QTimer>
#include <QToolButton>

#include "bvh.h"

namespace repose {

AnimationPanel::AnimationPanel(QWidget* parent) : QWidget(parent) {
  auto* layout = new QHBoxLayout(this);
  layout->setContentsMargins(4, 2, 4, 2);
  load_ = new QPushButton("Load motion (BVH)…", this);
  back_ = new QToolButton(this);
  back_->setIcon(style()->standardIcon(QStyle::SP_MediaSeekBackward));
  back_->setToolTip("Previous frame (Ctrl+Left)");
  play_ = new QToolButton(this);
  play_->setIcon(style()->standardIcon(QStyle::SP_MediaPlay));
  play_->setToolTip("Play / pause (Space)");
  forward_ = new QToolButton(this);
  forward_->setIcon(style()->standardIcon(QStyle::SP_MediaSeekForward));
  forward_->setToolTip("Next frame (Ctrl+Right)");
  slider_ = new QSlider(Qt::Horizontal, this);
  label_ = new QLabel("no motion loaded", this);
  label_->setMinimumWidth(220);
  export_ = new QPushButton("Export series (.pvd)…", this);
  keepRoot_ = new QCheckBox("Keep root in place", this);
  keepRoot_->setChecked(true);
  keepRoot_->setToolTip("Drop the clip's root translation: the body moves its joints where it stands (a walk "
                        "stays in view). Off, the root travels as in the clip (the command line's default; "
                        "`repose animate --no-root-motion` is this switch).");
  follow_ = new QCheckBox("Camera follows", this);
  follow_->setChecked(true);
  follow_->setToolTip("The 3D view moves with the body when its root travels");
  layout->addWidget(load_);
  layout->addWidget(back_);
  layout->addWidget(play_);
  layout->addWidget(forward_);
  layout->addWidget(slider_, 1);
  layout->addWidget(label_);
  layout->addWidget(keepRoot_);
  layout->addWidget(follow_);
  layout->addWidget(export_);
  timer_ = new QTimer(this);
  connect(timer_, &QTimer::timeout, this, &AnimationPanel::tick);
  connect(load_, &QPushButton::clicked, this, &AnimationPanel::loadRequested);
  connect(export_, &QPushButton::clicked, this, &AnimationPanel::exportRequested);
  connect(play_, &QToolButton::clicked, this, &AnimationPanel::togglePlay);
  connect(back_, &QToolButton::clicked, this, [this] { stepFrames(-1); });
  connect(forward_, &QToolButton::clicked, this, [this] { stepFrames(1); });
  connect(keepRoot_, &QCheckBox::toggled, this, [this] {
    if (retargeter_) emit frameChanged(frame());  // show the frame again, with or without travel
  });
  connect(follow_, &QCheckBox::toggled, this, &AnimationPanel::cameraFollowChanged);
  connect(slider_, &QSlider::valueChanged, this, [this](int f) {
    updateLabel();
    emit frameChanged(f);
  });
  setSkeleton(Skeleton());
}

AnimationPanel::~AnimationPanel() = default;

void AnimationPanel::setSkeleton(const Skeleton& skeleton) {
  pause();
  skeleton_ = skeleton;
  retargeter_.reset();
  clipName_.clear();
  QSignalBlocker block(slider_);
  slider_->setRange(0, 0);
  for (QWidget* w : std::initializer_list<QWidget*>{slider_, play_, back_, forward_, export_}) w->setEnabled(false);
  load_->setEnabled(skeleton.size() > 0);
  updateLabel();
}

void AnimationPanel::loadClip(const QString& bvhPath, const QString& mapPath) {
  const std::string bvh = bvhPath.toStdString();
  BvhMotion motion;
  try {
    motion = readBvhFile(bvh);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(e.what());
  }
  BvhJointMap map;
  try {
    map = mapPath.isEmpty() ? defaultCmuJointMap(motion, skeleton_) : readJointMapFile(mapPath.toStdString());
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error((mapPath.isEmpty() ? bvh : mapPath.toStdString()) + ": " + e.what());
  }
  std::unique_ptr<BvhRetargeter> retargeter;
  try {
    retargeter = std::make_unique<BvhRetargeter>(motion, skeleton_, map);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(bvh + ": " + e.what());
  }
  if (motion.frameCount < 1) throw std::runtime_error(bvh + ": the clip has no frames");
  pause();
  retargeter_ = std::move(retargeter);
  frameTime_ = motion.frameTime > 0 ? motion.frameTime : 1.0 / 30;
  clipName_ = QFileInfo(bvhPath).fileName();
  for (QWidget* w : std::initializer_list<QWidget*>{slider_, play_, back_, forward_, export_}) w->setEnabled(true);
  {
    QSignalBlocker block(slider_);
    slider_->setRange(0, motion.frameCount - 1);
    slider_->setValue(0);
  }
  updateLabel();
  emit frameChanged(0);
}

int AnimationPanel::frameCount() const { return retargeter_ ? retargeter_->frameCount() : 0; }
int AnimationPanel::frame() const { return slider_->value(); }
double AnimationPanel::frameTime() const { return frameTime_; }

Pose AnimationPanel::pose(int frame) const {
  if (!retargeter_) throw std::runtime_error("no motion loaded");
  Pose p = retargeter_->pose(std::clamp(frame, 0, frameCount() - 1));
  if (keepRootInPlace()) p.translation.setZero();
  return p;
}

bool AnimationPanel::keepRootInPlace() const { return keepRoot_->isChecked(); }
void AnimationPanel::setKeepRootInPlace(bool keep) { keepRoot_->setChecked(keep); }
bool AnimationPanel::cameraFollows() const { return follow_->isChecked(); }
void AnimationPanel::setCameraFollows(bool follow) { follow_->setChecked(follow); }

void AnimationPanel::setFrame(int frame) {
  if (retargeter_) slider_->setValue(std::clamp(frame, 0, frameCount() - 1));
}

void AnimationPanel::stepFrames(int delta) {
  pause();
  setFrame(frame() + delta);
}

void AnimationPanel::play() {
  if (!retargeter_ || timer_->isActive()) return;
  if (frame() >= frameCount() - 1) setFrame(0);
  playStartFrame_ = frame();
  clock_.start();
  timer_->start(std::max(10, int(frameTime_ * 1000)));
  play_->setIcon(style()->standardIcon(QStyle::SP_MediaPause));
  emit playingChanged(true);
}

void AnimationPanel::pause() {
  if (!timer_->isActive()) return;
  timer_->stop();
  play_->setIcon(style()->standardIcon(QStyle::SP_MediaPlay));
  emit playingChanged(false);
}

bool AnimationPanel::playing() const { return timer_->isActive(); }

void AnimationPanel::togglePlay() { playing() ? pause() : play(); }

void AnimationPanel::tick() {
  // Real time: the frame is the one due now, whatever the posing cost of the previous ones.
  const int due = playStartFrame_ + int(clock_.elapsed() / 1000.0 / frameTime_);
  if (due >= frameCount()) {
    setFrame(frameCount() - 1);
    pause();
    return;
  }
  if (due != frame()) setFrame(due);
}

void AnimationPanel::updateLabel() {
  if (!retargeter_) {
    label_->setText(skeleton_.size() ? "no motion loaded" : "");
    return;
  }
  label_->setText(QString("%1  frame %2 / %3  (%4 s)")
                      .arg(clipName_)
                      .arg(frame() + 1)
                      .arg(frameCount())
                      .arg(frame() * frameTime_, 0, 'f', 2));
}

}  // namespace repose
