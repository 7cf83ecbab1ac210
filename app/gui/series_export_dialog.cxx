#include "series_export_dialog.h"

#include <QDialogButtonBox>
#include <QFileDialog>
#include <QFormLayout>
#include <QHBoxLayout>
#include <QLabel>
#include <QLineEdit>
#include <QMessageBox>
#include <QPushButton>
#include <QSpinBox>

namespace repose {

SeriesExportDialog::SeriesExportDialog(int frameCount, double frameTime, double megabytesPerFrame, QWidget* parent)
    : QDialog(parent), frameTime_(frameTime), megabytesPerFrame_(megabytesPerFrame) {
  setWindowTitle("Export the motion as a series");
  auto* form = new QFormLayout(this);
  dir_ = new QLineEdit(this);
  auto* browse = new QPushButton("Browse…", this);
  auto* row = new QHBoxLayout;
  row->addWidget(dir_, 1);
  row->addWidget(browse);
  form->addRow("Folder:", row);
  connect(browse, &QPushButton::clicked, this, [this] {
    const QString d = QFileDialog::getExistingDirectory(this, "Export the animation into a folder", dir_->text());
    if (!d.isEmpty()) dir_->setText(d);
  });
  // Frames are numbered from 1 here, as on the timeline.
  auto spin = [this](int lo, int hi, int value) {
    auto* s = new QSpinBox(this);
    s->setRange(lo, hi);
    s->setValue(value);
    return s;
  };
  first_ = spin(1, std::max(1, frameCount), 1);
  last_ = spin(1, std::max(1, frameCount), std::max(1, frameCount));
  stride_ = spin(1, std::max(1, frameCount), 1);
  stride_->setToolTip("Write every n-th frame");
  form->addRow("First frame:", first_);
  form->addRow("Last frame:", last_);
  form->addRow("Every n-th frame:", stride_);
  estimate_ = new QLabel(this);
  form->addRow(estimate_);
  for (QSpinBox* s : {first_, last_, stride_})
    connect(s, qOverload<int>(&QSpinBox::valueChanged), this, [this] { estimate_->setText(estimate()); });
  estimate_->setText(estimate());
  auto* buttons = new QDialogButtonBox(QDialogButtonBox::Ok | QDialogButtonBox::Cancel, this);
  buttons->button(QDialogButtonBox::Ok)->setText("Export");
  form->addRow(buttons);
  connect(buttons, &QDialogButtonBox::accepted, this, [this] {
    if (dir_->text().isEmpty()) return void(QMessageBox::warning(this, windowTitle(), "Choose a folder."));
    if (settings().frameCount() < 1)
      return void(QMessageBox::warning(this, windowTitle(), "The last frame comes before the first."));
    accept();
  });
  connect(buttons, &QDialogButtonBox::rejected, this, &QDialog::reject);
  resize(520, height());
}

SeriesExportSettings SeriesExportDialog::settings() const {
  SeriesExportSettings s;
  s.dir = dir_->text();
  s.first = first_->value() - 1;
  s.last = last_->value() - 1;
  s.stride = stride_->value();
  return s;
}

void SeriesExportDialog::setSettings(const SeriesExportSettings& s) {
  dir_->setText(s.dir);
  first_->setValue(s.first + 1);
  last_->setValue(s.last + 1);
  stride_->setValue(s.stride);
}

QString SeriesExportDialog::estimate() const {
  const SeriesExportSettings s = settings();
  const int n = s.frameCount();
  return QString("%1 frame%2 (%3 s apart), about %4 MB")
      .arg(n)
      .arg(n == 1 ? "" : "s")
      .arg(s.stride * frameTime_, 0, 'f', 3)
      .arg(n * megabytesPerFrame_, 0, 'f', 0);
}

}  // namespace repose
