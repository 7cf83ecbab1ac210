#include "joint_panel.h"

#include <cmath>

#include <QDoubleSpinBox>
#include <QGridLayout>
#include <QGroupBox>
#include <QHBoxLayout>
#include <QHeaderView>
#include <QLabel>
#include <QPushButton>
#include <QSlider>
#include <QTreeWidget>
#include <QVBoxLayout>

#include "pose_controller.h"

namespace repose {
namespace {
const char* kConventionTip =
    "Angles from the scan's rest pose, with the signs of the anatomical position: flexion, abduction and "
    "internal rotation (elbow: pronation) positive on either side; spine, neck and pelvis: bending forwards, "
    "bending to the patient's right and turning to the patient's left positive. Order: flexion about the "
    "left-right axis, then abduction about the front-back axis, then rotation about the bone's long axis.";

QString degrees(double v) { return QString::number(v, 'f', 0) + "°"; }
}  // namespace

JointPanel::JointPanel(PoseController* controller, QWidget* parent) : QWidget(parent), controller_(controller) {
  auto* layout = new QVBoxLayout(this);
  layout->setContentsMargins(4, 4, 4, 4);
  tree_ = new QTreeWidget(this);
  tree_->setColumnCount(2);
  tree_->setHeaderLabels({"Joint", "Angles (°)"});
  tree_->headerItem()->setToolTip(1, "Flexion, abduction, rotation");
  tree_->setIndentation(8);  // the vertebra chain is deep: keep the angle column in view
  tree_->header()->setStretchLastSection(false);
  tree_->header()->setSectionResizeMode(0, QHeaderView::Stretch);
  tree_->header()->setSectionResizeMode(1, QHeaderView::ResizeToContents);
  tree_->setTextElideMode(Qt::ElideMiddle);
  tree_->setToolTip("Joints of the skeleton and their flexion, abduction and rotation; click a bone in the 3D view "
                    "to select its joint.\n" + QString(kConventionTip));
  layout->addWidget(tree_, 1);

  group_ = new QGroupBox("Rotation", this);
  group_->setToolTip(kConventionTip);
  auto* grid = new QGridLayout(group_);
  grid->setColumnStretch(1, 1);
  for (int a = 0; a < 3; ++a) {
    captions_[a] = new QLabel(group_);
    sliders_[a] = new QSlider(Qt::Horizontal, group_);
    spins_[a] = new QDoubleSpinBox(group_);
    spins_[a]->setDecimals(1);
    spins_[a]->setSuffix("°");
    spins_[a]->setKeyboardTracking(false);
    lower_[a] = new QLabel(group_);
    upper_[a] = new QLabel(group_);
    for (QLabel* l : {lower_[a], upper_[a]}) l->setStyleSheet("color: gray");
    // Caption on its own row; the limits at the ends of the slider they bound.
    grid->addWidget(captions_[a], 2 * a, 0, 1, 4);
    grid->addWidget(lower_[a], 2 * a + 1, 0, Qt::AlignRight);
    grid->addWidget(sliders_[a], 2 * a + 1, 1);
    grid->addWidget(upper_[a], 2 * a + 1, 2);
    grid->addWidget(spins_[a], 2 * a + 1, 3);
    connect(sliders_[a], &QSlider::sliderPressed, controller_, &PoseController::beginEdit);
    connect(sliders_[a], &QSlider::sliderReleased, controller_, &PoseController::endEdit);
    auto setAngle = [this, a](double value) {
      if (selected_ < 0) return;
      Eigen::Vector3d angles = controller_->angles(selected_);
      angles[a] = value;
      controller_->setAngles(selected_, angles);
    };
    connect(sliders_[a], &QSlider::valueChanged, this, setAngle);
    connect(spins_[a], qOverload<double>(&QDoubleSpinBox::valueChanged), this, setAngle);
  }
  auto* buttons = new QHBoxLayout;
  auto* resetJoint = new QPushButton("Reset joint", group_);
  auto* resetAll = new QPushButton("Reset all", group_);
  buttons->addWidget(resetJoint);
  buttons->addWidget(resetAll);
  grid->addLayout(buttons, 6, 0, 1, 4);
  layout->addWidget(group_);
  connect(resetJoint, &QPushButton::clicked, this, [this] {
    if (selected_ >= 0) controller_->resetJoint(selected_);
  });
  connect(resetAll, &QPushButton::clicked, controller_, &PoseController::resetAll);
  connect(tree_, &QTreeWidget::currentItemChanged, this, [this](QTreeWidgetItem* item) {
    const int joint = item ? item->data(0, Qt::UserRole).toInt() : -1;
    if (joint == selected_) return;
    selected_ = joint;
    refresh();
    emit jointSelected(joint);
  });
  // The tree holds joint indices: it is rebuilt before the new skeleton's first pose arrives.
  connect(controller_, &PoseController::skeletonChanged, this, &JointPanel::rebuild);
  connect(controller_, &PoseController::poseChanged, this, &JointPanel::refresh);
  rebuild();
}

QString JointPanel::axisCaption(int axis) const { return captions_[axis]->text(); }

void JointPanel::rebuild() {
  QSignalBlocker block(tree_);
  tree_->clear();
  items_.clear();
  const Skeleton& s = controller_->skeleton();
  for (std::size_t j = 0; j < s.size(); ++j) {
    const int p = s.joints[j].parent;
    auto* item = p < 0 ? new QTreeWidgetItem(tree_) : new QTreeWidgetItem(items_[std::size_t(p)]);
    item->setText(0, QString::fromStdString(s.joints[j].name));
    item->setToolTip(0, QString::fromStdString(s.joints[j].name));
    item->setData(0, Qt::UserRole, int(j));
    items_.push_back(item);
  }
  tree_->expandAll();
  const bool hadSelection = selected_ >= 0;
  selected_ = -1;
  refresh();
  if (hadSelection) emit jointSelected(-1);
}

void JointPanel::setSelectedJoint(int joint) {
  if (joint < 0 || std::size_t(joint) >= items_.size()) return;
  tree_->setCurrentItem(items_[std::size_t(joint)]);  // emits jointSelected through currentItemChanged
}

void JointPanel::refresh() {
  for (std::size_t j = 0; j < items_.size(); ++j) {
    const Eigen::Vector3d a = controller_->angles(int(j));
    items_[j]->setText(1, a.isZero(0.05) ? QString()
                                         : QString("%1, %2, %3").arg(a.x(), 0, 'f', 0).arg(a.y(), 0, 'f', 0).arg(a.z(), 0, 'f', 0));
  }
  group_->setEnabled(selected_ >= 0);
  group_->setTitle(selected_ >= 0 ? "Rotation of " + QString::fromStdString(controller_->skeleton().joints[std::size_t(selected_)].name)
                                  : "Rotation (select a joint)");
  const JointClass joint = selected_ >= 0 ? controller_->jointClass(selected_) : JointClass();
  const std::array<std::string, 3> names = anatomicalAngleNames(joint);
  for (int a = 0; a < 3; ++a) captions_[a]->setText(QString::fromStdString(names[std::size_t(a)]));
  if (selected_ < 0) return;
  const Eigen::Vector3d angles = controller_->angles(selected_);
  const JointLimits limits = controller_->limits(selected_);
  for (int a = 0; a < 3; ++a) {
    QSignalBlocker b1(sliders_[a]), b2(spins_[a]);
    sliders_[a]->setRange(int(limits.lower[a]), int(limits.upper[a]));
    spins_[a]->setRange(limits.lower[a], limits.upper[a]);
    if (!sliders_[a]->isSliderDown()) sliders_[a]->setValue(int(std::lround(angles[a])));
    spins_[a]->setValue(angles[a]);
    lower_[a]->setText(degrees(limits.lower[a]));
    upper_[a]->setText(degrees(limits.upper[a]));
  }
}

}  // namespace repose
