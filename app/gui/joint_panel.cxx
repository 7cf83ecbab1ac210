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
const char* kAxisNames[3] = {"Flexion / extension\n(about left-right)", "Abduction / adduction\n(about front-back)",
                             "Axial rotation\n(about head-foot)"};
}

JointPanel::JointPanel(PoseController* controller, QWidget* parent) : QWidget(parent), controller_(controller) {
  auto* layout = new QVBoxLayout(this);
  layout->setContentsMargins(4, 4, 4, 4);
  tree_ = new QTreeWidget(this);
  tree_->setHeaderLabels({"Joint", "Angles (°)"});
  tree_->header()->setSectionResizeMode(0, QHeaderView::ResizeToContents);
  tree_->setToolTip("Joints of the skeleton; click a bone in the 3D view to select its joint");
  layout->addWidget(tree_, 1);

  group_ = new QGroupBox("Rotation", this);
  auto* grid = new QGridLayout(group_);
  for (int a = 0; a < 3; ++a) {
    auto* name = new QLabel(kAxisNames[a], group_);
    sliders_[a] = new QSlider(Qt::Horizontal, group_);
    spins_[a] = new QDoubleSpinBox(group_);
    spins_[a]->setDecimals(1);
    spins_[a]->setSuffix("°");
    spins_[a]->setKeyboardTracking(false);
    limits_[a] = new QLabel(group_);
    limits_[a]->setStyleSheet("color: gray");
    grid->addWidget(name, 2 * a, 0, 1, 2);
    grid->addWidget(sliders_[a], 2 * a + 1, 0);
    grid->addWidget(spins_[a], 2 * a + 1, 1);
    grid->addWidget(limits_[a], 2 * a, 1, Qt::AlignRight);
    connect(sliders_[a], &QSlider::sliderPressed, controller_, &PoseController::beginEdit);
    connect(sliders_[a], &QSlider::sliderReleased, controller_, &PoseController::endEdit);
    connect(sliders_[a], &QSlider::valueChanged, this, [this, a](int value) {
      if (selected_ < 0) return;
      Eigen::Vector3d angles = controller_->angles(selected_);
      angles[a] = value;
      controller_->setAngles(selected_, angles);
    });
    connect(spins_[a], qOverload<double>(&QDoubleSpinBox::valueChanged), this, [this, a](double value) {
      if (selected_ < 0) return;
      Eigen::Vector3d angles = controller_->angles(selected_);
      angles[a] = value;
      controller_->setAngles(selected_, angles);
    });
  }
  auto* buttons = new QHBoxLayout;
  auto* resetJoint = new QPushButton("Reset joint", group_);
  auto* resetAll = new QPushButton("Reset all", group_);
  buttons->addWidget(resetJoint);
  buttons->addWidget(resetAll);
  grid->addLayout(buttons, 6, 0, 1, 2);
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
  connect(controller_, &PoseController::poseChanged, this, &JointPanel::refresh);
  rebuild();
}

void JointPanel::rebuild() {
  QSignalBlocker block(tree_);
  tree_->clear();
  items_.clear();
  const Skeleton& s = controller_->skeleton();
  for (std::size_t j = 0; j < s.size(); ++j) {
    const int p = s.joints[j].parent;
    auto* item = p < 0 ? new QTreeWidgetItem(tree_) : new QTreeWidgetItem(items_[std::size_t(p)]);
    item->setText(0, QString::fromStdString(s.joints[j].name));
    item->setData(0, Qt::UserRole, int(j));
    items_.push_back(item);
  }
  tree_->expandAll();
  selected_ = -1;
  refresh();
}

void JointPanel::setSelectedJoint(int joint) {
  if (joint < 0 || std::size_t(joint) >= items_.size()) return;
  tree_->setCurrentItem(items_[std::size_t(joint)]);  // emits jointSelected through currentItemChanged
}

void JointPanel::refresh() {
  for (std::size_t j = 0; j < items_.size(); ++j) {
    const Eigen::Vector3d a = controller_->angles(int(j));
    items_[j]->setText(1, a.isZero(1e-9) ? QString() : QString("%1, %2, %3").arg(a.x(), 0, 'f', 0).arg(a.y(), 0, 'f', 0).arg(a.z(), 0, 'f', 0));
  }
  group_->setEnabled(selected_ >= 0);
  group_->setTitle(selected_ >= 0 ? "Rotation of " + QString::fromStdString(controller_->skeleton().joints[std::size_t(selected_)].name)
                                  : "Rotation (select a joint)");
  if (selected_ < 0) return;
  const Eigen::Vector3d angles = controller_->angles(selected_);
  const AngleLimits limits = controller_->limits(selected_);
  for (int a = 0; a < 3; ++a) {
    QSignalBlocker b1(sliders_[a]), b2(spins_[a]);
    sliders_[a]->setRange(int(limits.lower[a]), int(limits.upper[a]));
    spins_[a]->setRange(limits.lower[a], limits.upper[a]);
    if (!sliders_[a]->isSliderDown()) sliders_[a]->setValue(int(std::lround(angles[a])));
    spins_[a]->setValue(angles[a]);
    limits_[a]->setText(QString("limits %1° … %2°").arg(limits.lower[a]).arg(limits.upper[a]));
  }
}

}  // namespace repose
