#include "start_page.h"

#include <QComboBox>
#include <QGridLayout>
#include <QHBoxLayout>
#include <QLabel>
#include <QProgressBar>
#include <QPushButton>
#include <QVBoxLayout>

namespace repose {

StartPage::StartPage(QWidget* parent) : QWidget(parent) {
  auto* outer = new QVBoxLayout(this);
  outer->addStretch(1);
  auto* title = new QLabel("<h1>Repose</h1><p>Virtual patient positioning: choose a pose for a segmented "
                           "CT/MRI and the anatomy follows (skin, bones and the label volume).</p>",
                           this);
  title->setAlignment(Qt::AlignCenter);
  title->setWordWrap(true);
  outer->addWidget(title);

  auto* grid = new QGridLayout;
  phantom_ = new QPushButton("Open the built-in phantom", this);
  size_ = new QComboBox(this);
  size_->addItems({"tiny", "small", "medium", "large"});
  size_->setCurrentText("small");
  size_->setToolTip("Phantom size: tiny prepares in seconds, medium in about a minute");
  case_ = new QPushButton("Open a prepared case…", this);
  case_->setToolTip("A case directory written by 'repose prepare' (mesh.vtu, surfaces.vtp, skeleton.json)");
  scan_ = new QPushButton("Open a scan…", this);
  scan_->setToolTip("A label volume (segmentation), optional CT, label table and skeleton; it is prepared here");
  for (QPushButton* b : {phantom_, case_, scan_}) b->setMinimumHeight(40);
  grid->addWidget(phantom_, 0, 0);
  grid->addWidget(size_, 0, 1);
  grid->addWidget(case_, 1, 0, 1, 2);
  grid->addWidget(scan_, 2, 0, 1, 2);
  auto* center = new QHBoxLayout;
  center->addStretch(1);
  center->addLayout(grid, 2);
  center->addStretch(1);
  outer->addLayout(center);

  stage_ = new QLabel(this);
  stage_->setAlignment(Qt::AlignCenter);
  bar_ = new QProgressBar(this);
  cancel_ = new QPushButton("Cancel", this);
  auto* progress = new QHBoxLayout;
  progress->addStretch(1);
  progress->addWidget(bar_, 3);
  progress->addWidget(cancel_);
  progress->addStretch(1);
  outer->addWidget(stage_);
  outer->addLayout(progress);
  outer->addStretch(2);
  setBusy(false);

  connect(phantom_, &QPushButton::clicked, this, [this] { emit openPhantomRequested(size_->currentText()); });
  connect(case_, &QPushButton::clicked, this, &StartPage::openCaseRequested);
  connect(scan_, &QPushButton::clicked, this, &StartPage::openScanRequested);
  connect(cancel_, &QPushButton::clicked, this, &StartPage::cancelRequested);
}

QString StartPage::phantomSize() const { return size_->currentText(); }

void StartPage::setBusy(bool busy) {
  for (QWidget* w : std::initializer_list<QWidget*>{phantom_, size_, case_, scan_}) w->setEnabled(!busy);
  bar_->setVisible(busy);
  cancel_->setVisible(busy);
  stage_->setVisible(busy);
  if (busy) {
    bar_->setRange(0, 0);
    stage_->setText("Starting…");
  }
}

void StartPage::setProgress(int step, int steps, const QString& stage) {
  bar_->setRange(0, steps);
  bar_->setValue(step);
  stage_->setText(QString("Step %1 of %2: %3…").arg(step + 1).arg(steps).arg(stage));
}

}  // namespace repose
