#include "open_scan_dialog.h"

#include <QCheckBox>
#include <QDialogButtonBox>
#include <QDoubleSpinBox>
#include <QFileDialog>
#include <QFormLayout>
#include <QHBoxLayout>
#include <QLineEdit>
#include <QMessageBox>
#include <QPushButton>

namespace repose {
namespace {
const char* kImages = "Images (*.nii *.nii.gz *.nrrd *.nhdr *.mha *.mhd);;All files (*)";
}

OpenScanDialog::OpenScanDialog(QWidget* parent) : QDialog(parent) {
  setWindowTitle("Open a scan");
  auto* form = new QFormLayout(this);
  auto row = [this, form](const QString& label, QLineEdit*& edit, bool directory, const char* filter) {
    edit = new QLineEdit(this);
    auto* browse = new QPushButton("Browse…", this);
    auto* box = new QHBoxLayout;
    box->addWidget(edit, 1);
    box->addWidget(browse);
    form->addRow(label, box);
    connect(browse, &QPushButton::clicked, this, [this, edit, directory, filter] {
      const QString path = directory ? QFileDialog::getExistingDirectory(this, "Choose a folder")
                                     : QFileDialog::getOpenFileName(this, "Choose a file", QString(), filter);
      if (!path.isEmpty()) edit->setText(path);
    });
  };
  row("Label volume (segmentation):", labels_, false, kImages);
  row("CT on the same grid (optional):", image_, false, kImages);
  {
    // A CT often comes as a DICOM series: a folder of slices, read as one volume.
    auto* series = new QPushButton("DICOM series folder…", this);
    series->setToolTip("Choose a folder holding one DICOM CT series (oblique series are read with their "
                       "direction; gantry-tilted ones are refused)");
    form->addRow("", series);
    connect(series, &QPushButton::clicked, this, [this] {
      const QString dir = QFileDialog::getExistingDirectory(this, "Choose the DICOM series folder");
      if (!dir.isEmpty()) image_->setText(dir);
    });
  }
  row("Label table .tsv (optional):", table_, false, "Label tables (*.tsv *.txt);;All files (*)");
  auto_ = new QCheckBox("Find the skeleton automatically from the bone labels", this);
  form->addRow("", auto_);
  row("Skeleton (skeleton.json):", skeleton_, false, "Skeleton (*.json);;All files (*)");
  connect(auto_, &QCheckBox::toggled, skeleton_, &QLineEdit::setDisabled);
  spacing_ = new QDoubleSpinBox(this);
  spacing_->setRange(0, 20);
  spacing_->setDecimals(1);
  spacing_->setSuffix(" mm");
  spacing_->setSpecialValueText("label voxel size");
  spacing_->setToolTip("Mesh the body on this voxel size; coarser is faster to prepare and to pose");
  form->addRow("Mesh spacing:", spacing_);
  row("Save the prepared case to (optional):", save_, true, nullptr);
  auto* buttons = new QDialogButtonBox(QDialogButtonBox::Ok | QDialogButtonBox::Cancel, this);
  buttons->button(QDialogButtonBox::Ok)->setText("Prepare");
  form->addRow(buttons);
  connect(buttons, &QDialogButtonBox::accepted, this, [this] {
    if (labels_->text().isEmpty())
      return void(QMessageBox::warning(this, "Open a scan", "Choose the label volume."));
    if (!auto_->isChecked() && skeleton_->text().isEmpty())
      return void(QMessageBox::warning(this, "Open a scan", "Choose a skeleton.json or the automatic skeleton."));
    accept();
  });
  connect(buttons, &QDialogButtonBox::rejected, this, &QDialog::reject);
  resize(640, height());
}

OpenRequest OpenScanDialog::request() const {
  OpenRequest r;
  r.kind = OpenRequest::Scan;
  r.labelsPath = labels_->text();
  r.imagePath = image_->text();
  r.labelTablePath = table_->text();
  r.autoSkeleton = auto_->isChecked();
  r.skeletonPath = skeleton_->text();
  r.saveCaseDir = save_->text();
  r.settings.meshSpacing = spacing_->value();
  return r;
}

}  // namespace repose
