#pragma once
// The legend of the 3D view: every structure of the case's surfaces with its colour, name (from the
// case's label table, "label N" without one) and value; bones name their joint. Activating a bone's
// entry selects its joint.
#include <QStringList>
#include <QWidget>

#include "label_table.h"
#include "skeleton.h"

class QTreeWidget;
class vtkPolyData;

namespace repose {

class LabelLegend : public QWidget {
  Q_OBJECT
public:
  explicit LabelLegend(QWidget* parent = nullptr);
  /// Lists the labels of `surfaces` (cell data "Label"; -1 is the skin), with the skeleton's joint
  /// that each bone label moves with.
  void setCase(vtkPolyData* surfaces, const LabelTable& table, const Skeleton& skeleton);
  void clear();
  /// "value<TAB>name" per entry, in the order shown (tests).
  QStringList entries() const;

signals:
  void jointActivated(int joint);

private:
  QTreeWidget* list_;
};

}  // namespace repose
