#include "label_legend.h"

#include <algorithm>
#include <set>
#include <vector>

#include <QHeaderView>
#include <QPixmap>
#include <QTreeWidget>
#include <QVBoxLayout>
#include <vtkCellData.h>
#include <vtkDataArray.h>
#include <vtkPolyData.h>

#include "label_colors.h"
#include "array_names.h"

namespace repose {

LabelLegend::LabelLegend(QWidget* parent) : QWidget(parent) {
  auto* layout = new QVBoxLayout(this);
  layout->setContentsMargins(4, 4, 4, 4);
  list_ = new QTreeWidget(this);
  list_->setColumnCount(3);
  list_->setHeaderLabels({"Structure", "Label", "Joint"});
  list_->setRootIsDecorated(false);
  list_->header()->setStretchLastSection(false);
  list_->header()->setSectionResizeMode(0, QHeaderView::Stretch);
  list_->header()->setSectionResizeMode(1, QHeaderView::ResizeToContents);
  list_->header()->setSectionResizeMode(2, QHeaderView::ResizeToContents);
  list_->setToolTip("The structures of the 3D view in their colours; double-click a bone to select its joint");
  layout->addWidget(list_);
  connect(list_, &QTreeWidget::itemActivated, this, [this](QTreeWidgetItem* item) {
    const int joint = item->data(0, Qt::UserRole).toInt();
    if (joint >= 0) emit jointActivated(joint);
  });
}

void LabelLegend::clear() { list_->clear(); }

void LabelLegend::setCase(vtkPolyData* surfaces, const LabelTable& table, const Skeleton& skeleton) {
  list_->clear();
  vtkDataArray* labels = surfaces ? surfaces->GetCellData()->GetArray(repose::arrays::kLabel) : nullptr;
  if (!labels) return;
  std::set<int> values;
  for (vtkIdType c = 0; c < labels->GetNumberOfTuples(); ++c) values.insert(int(labels->GetTuple1(c)));
  if (values.empty()) return;
  const std::vector<int> jointOfLabel = boneOfLabel(skeleton, std::max(0, *values.rbegin()));
  for (int v : values) {
    const int joint = v >= 0 ? jointOfLabel[std::size_t(v)] : -1;
    double rgb[3];
    labelColor(v, table, joint >= 0, rgb);
    QPixmap swatch(14, 14);
    swatch.fill(QColor::fromRgbF(rgb[0], rgb[1], rgb[2]));
    const LabelInfo* info = table.find(v);
    const QString name = v < 0 ? QString("skin (body surface)")
                               : info ? QString::fromStdString(info->name) : QString("label %1").arg(v);
    auto* item = new QTreeWidgetItem(list_);
    item->setIcon(0, QIcon(swatch));
    item->setText(0, name);
    item->setToolTip(0, name);
    item->setText(1, v < 0 ? QString() : QString::number(v));
    item->setText(2, joint >= 0 ? QString::fromStdString(skeleton.joints[std::size_t(joint)].name) : QString());
    item->setData(0, Qt::UserRole, joint);
  }
}

QStringList LabelLegend::entries() const {
  QStringList out;
  for (int i = 0; i < list_->topLevelItemCount(); ++i)
    out << list_->topLevelItem(i)->text(1) + "\t" + list_->topLevelItem(i)->text(0);
  return out;
}

}  // namespace repose
