#pragma once
// The joint tree with each joint's anatomical angles, and the selected joint's three angles
// (flexion, abduction, rotation with their signs named; sliders between the limits, spin boxes),
// with Reset joint / Reset all. Edits go through the PoseController; the tree is rebuilt whenever
// the controller's skeleton changes.
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
  void setSelectedJoint(int joint);
  int selectedJoint() const { return selected_; }
  /// The angle slider of axis 0..2 (tests drive it like a user).
  QSlider* slider(int axis) const { return sliders_[axis]; }
  QDoubleSpinBox* spinBox(int axis) const { return spins_[axis]; }
  QTreeWidget* tree() const { return tree_; }
  /// The caption of axis 0..2 ("Flexion (+) / extension (−)", ...).
  QString axisCaption(int axis) const;

signals:
  void jointSelected(int joint);

private:
  void rebuild();
  void refresh();
  PoseController* controller_;
  QTreeWidget* tree_;
  QGroupBox* group_;
  QLabel* captions_[3];
  QSlider* sliders_[3];
  QDoubleSpinBox* spins_[3];
  QLabel *lower_[3], *upper_[3];
  std::vector<QTreeWidgetItem*> items_;
  int selected_ = -1;
};

}  // namespace repose
