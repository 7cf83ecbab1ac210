#pragma once
// The joint tree and the selected joint's three rotation angles (sliders and spin boxes, limits
// shown), with Reset joint / Reset all. Edits go through the PoseController.
#include <QWidget>

class QDoubleSpinBox;
class QGroupBox;
class QLabel;
class QSlider;
class QTreeWidget;
class QTreeWidgetItem;

namespace repose {

class PoseController;

class JointPanel : public QWidget {
  Q_OBJECT
public:
  explicit JointPanel(PoseController* controller, QWidget* parent = nullptr);
  /// Rebuilds the tree from the controller's skeleton.
  void rebuild();
  void setSelectedJoint(int joint);
  int selectedJoint() const { return selected_; }
  /// The angle slider of axis 0..2 (tests drive it like a user).
  QSlider* slider(int axis) const { return sliders_[axis]; }
  QDoubleSpinBox* spinBox(int axis) const { return spins_[axis]; }

signals:
  void jointSelected(int joint);

private:
  void refresh();
  PoseController* controller_;
  QTreeWidget* tree_;
  QGroupBox* group_;
  QSlider* sliders_[3];
  QDoubleSpinBox* spins_[3];
  QLabel* limits_[3];
  std::vector<QTreeWidgetItem*> items_;
  int selected_ = -1;
};

}  // namespace repose
