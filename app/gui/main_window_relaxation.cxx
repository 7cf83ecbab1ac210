// The FEM relaxation of the current pose, run on a worker thread with progress and cancel.
#include "main_window.h"


#include <QCheckBox>
#include <QComboBox>
#include <QLabel>
#include <QPushButton>
#include <QtConcurrent/QtConcurrentRun>

#include "animation_panel.h"
#include "joint_panel.h"
#include "scene_view.h"

namespace repose {

// --- FEM relaxation --------------------------------------------------------------------------

void MainWindow::relaxCurrentPose() {
  if (!pipeline_ || isRelaxing()) return;
  guarded([&] {
    animation_->pause();
    beforeSurfaces_ = vtkSmartPointer<vtkPolyData>::New();
    beforeSurfaces_->DeepCopy(pipeline_->posedSurfaces());
    pipeline_->setRelaxationWarmStart(relaxWarmStart_->isChecked());
    pipeline_->setRelaxation(true);
    relaxLabel_->setText("Relaxing (FEM)…");
    relaxing_ = true;
    posedWhileRelaxing_ = false;
    relaxGeneration_ = caseGeneration_;
    for (QWidget* w : std::initializer_list<QWidget*>{joints_, animation_, skinning_}) w->setEnabled(false);
    relax_->setText("Cancel relaxation");
    relaxObserver_ = pipeline_->relaxation()->AddObserver(vtkCommand::ProgressEvent, this, &MainWindow::relaxProgress);
    std::shared_ptr<Pipeline> p = pipeline_;
    relaxWatcher_.setFuture(QtConcurrent::run([p]() -> QString {
      try {
        p->posedSurfaces();
        return QString();
      } catch (const std::exception& e) {
        return QString::fromStdString(e.what());
      }
    }));
    updateActions();
  });
}

void MainWindow::finishRelaxationState() {
  relaxing_ = false;
  if (relaxObserver_ && pipeline_ && pipeline_->relaxation()) pipeline_->relaxation()->RemoveObserver(relaxObserver_);
  relaxObserver_ = 0;
  for (QWidget* w : std::initializer_list<QWidget*>{joints_, animation_, relax_, skinning_}) w->setEnabled(true);
  relax_->setText(kRelaxButtonText);
  updateActions();
}

void MainWindow::relaxDone() {
  if (!relaxing_) return;  // stopRelaxation() has already cleaned up (the case was closed)
  finishRelaxationState();
  const QString error = relaxWatcher_.result();
  if (!pipeline_ || relaxGeneration_ != caseGeneration_) return;  // the case was closed meanwhile
  if (pipeline_->relaxation() && pipeline_->relaxation()->GetCancelled()) {
    guarded([&] { pipeline_->setRelaxation(false); });
    relaxSummary_.clear();
    relaxLabel_->setText("Relaxation cancelled: skinning only.");
    emit relaxFinished();
    if (posedWhileRelaxing_) poseChanged();
    return;
  }
  if (!error.isEmpty()) {
    guarded([&] { pipeline_->setRelaxation(false); });
    relaxLabel_->setText("Skinning only.");
    showError(error);
    return;
  }
  relaxed_ = true;
  relaxSummary_ = QString::fromStdString(pipeline_->relaxationSummary());
  relaxLabel_->setText("After relaxation (solid) vs before (wireframe).\n" + relaxSummary_);
  guarded([&] {
    scene_->updatePose(pipeline_->posedSurfaces(), pipeline_->boneTransforms());
    scene_->setGhost(showBefore_->isChecked() ? beforeSurfaces_.Get() : nullptr);
    scene_->render();
  });
  requestSliceUpdate();
  emit relaxFinished();
  // A pose set while the solver ran (a loaded pose) wins over the relaxed result.
  if (posedWhileRelaxing_) poseChanged();
}

QString MainWindow::relaxationStatus() const { return relaxLabel_->text(); }

void MainWindow::relaxProgress(vtkObject* caller, unsigned long, void*) {
  const char* text = vtkAlgorithm::SafeDownCast(caller)->GetProgressText();
  if (!text || !*text) return;  // the executive's own start and end reports
  const QString line = QString("Relaxing (FEM): %1…").arg(QString::fromUtf8(text));
  QMetaObject::invokeMethod(
    this,
    [this, line] {
      if (isRelaxing() && relax_->isEnabled()) relaxLabel_->setText(line);  // not once cancelling
    },
    Qt::QueuedConnection);
}

void MainWindow::cancelRelaxation() {
  if (!isRelaxing() || !pipeline_) return;
  pipeline_->cancelRelaxation();
  relaxLabel_->setText("Cancelling the relaxation…");
  relax_->setEnabled(false);  // until relaxDone()
}

void MainWindow::stopRelaxation() {
  if (!isRelaxing()) return;
  if (pipeline_) pipeline_->cancelRelaxation();
  relaxWatcher_.waitForFinished();
  finishRelaxationState();  // the queued relaxDone() then finds nothing to do
}

void MainWindow::dropRelaxation() {
  relaxed_ = false;
  guarded([&] { pipeline_->setRelaxation(false); });
  scene_->setGhost(nullptr);
  relaxLabel_->setText("Skinning only (the pose changed since the relaxation).");
}

}  // namespace repose
