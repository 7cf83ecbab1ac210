#include "main_window.h"

#include <chrono>


#include <QApplication>
#include <QComboBox>
#include <QDockWidget>
#include <QFileDialog>
#include <QKeyEvent>
#include <QLabel>
#include <QMenuBar>
#include <QStackedWidget>
#include <QStatusBar>
#include <QTimer>
#include <QtConcurrent/QtConcurrentRun>
#include <vtkPointData.h>
#include <vtkRenderWindow.h>

#include "animation_panel.h"
#include "joint_panel.h"
#include "label_legend.h"
#include "lps_image.h"
#include "open_scan_dialog.h"
#include "scene_view.h"
#include "slice_views.h"
#include "start_page.h"
#include "posed_volume_sampler.h"

namespace repose {
namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

}  // namespace

MainWindow::MainWindow(QWidget* parent) : QMainWindow(parent) {
  setWindowTitle("Repose");
  stack_ = new QStackedWidget(this);
  start_ = new StartPage(stack_);
  stack_->addWidget(start_);
  setCentralWidget(stack_);
  buildWorkspace();
  buildMenus();
  connect(start_, &StartPage::openPhantomRequested, this, [this](const QString& size) { openPhantom(size); });
  connect(start_, &StartPage::openCaseRequested, this, [this] {
    const QString dir = QFileDialog::getExistingDirectory(this, "Open a prepared case");
    if (!dir.isEmpty()) openCase(dir);
  });
  connect(start_, &StartPage::openScanRequested, this, [this] {
    OpenScanDialog dialog(this);
    if (dialog.exec() == QDialog::Accepted) openScan(dialog.request());
  });
  connect(start_, &StartPage::cancelRequested, this, &MainWindow::cancelOpening);
  connect(&controller_, &PoseController::poseChanged, this, &MainWindow::poseChanged);
  connect(&controller_, &PoseController::historyChanged, this, [this] {
    updateActions();
    if (!controller_.editing()) requestSliceUpdate();
  });
  // Full detail and the posed volume once an interaction is over.
  auto interactionOver = [this] {
    if (controller_.editing() || animation_->playing()) return;
    scene_->setInteractive(false);
    scene_->render();
    requestSliceUpdate();
  };
  connect(&controller_, &PoseController::editFinished, this, interactionOver);
  connect(animation_, &AnimationPanel::playingChanged, this, interactionOver);
  connect(&sliceWatcher_, &QFutureWatcher<SliceResult>::finished, this, &MainWindow::sliceUpdateFinished);
  connect(&relaxWatcher_, &QFutureWatcher<QString>::finished, this, &MainWindow::relaxDone);
  qApp->installEventFilter(this);
  updateActions();
  resize(1500, 950);
}

MainWindow::~MainWindow() {
  for (PreprocessWorker* w : findChildren<PreprocessWorker*>()) {
    w->cancel();
    w->wait();
  }
  sliceWatcher_.waitForFinished();
  stopRelaxation();
}

void MainWindow::closeEvent(QCloseEvent* event) {
  if (deferWhileExporting([this] { close(); }) || !confirmDiscardPose("quitting")) {
    event->ignore();
    return;
  }
  if (worker_) statusBar()->showMessage("Waiting for the running preprocessing stage to stop…");
  QMainWindow::closeEvent(event);
}

bool MainWindow::eventFilter(QObject* watched, QEvent* event) {
  if (event->type() == QEvent::ShortcutOverride) {
    auto* widget = qobject_cast<QWidget*>(watched);
    if (widget && widget->window() == this) {  // not in dialogs, whose fields need their keys
      auto* key = static_cast<QKeyEvent*>(event);
      const Qt::KeyboardModifiers mods =
          key->modifiers() & (Qt::ShiftModifier | Qt::ControlModifier | Qt::AltModifier | Qt::MetaModifier);
      const QKeySequence pressed(int(mods) | key->key());
      for (QAction* a : shortcutActions_)
        if (a->isEnabled() && a->shortcuts().contains(pressed)) {
          event->ignore();  // not overridden: the shortcut map triggers the action
          return true;
        }
    }
  }
  return QMainWindow::eventFilter(watched, event);
}

QMessageBox::StandardButton MainWindow::ask(const QString& question, QMessageBox::StandardButtons buttons,
                                            QMessageBox::StandardButton fallback) {
  if (questionHandler_) return questionHandler_(question, buttons);
  return QMessageBox::question(this, "Repose", question, buttons, fallback);
}

bool MainWindow::confirmDiscardPose(const QString& before) {
  if (!hasCase() || !controller_.hasUnsavedPose()) return true;
  const auto answer = ask("The pose has changes that are not saved. Save the pose before " + before + "?",
                          QMessageBox::Save | QMessageBox::Discard | QMessageBox::Cancel, QMessageBox::Save);
  if (answer == QMessageBox::Discard) return true;
  if (answer != QMessageBox::Save) return false;
  const QString path = askSavePath("Save pose", "pose.json", "Pose (*.json)");
  return !path.isEmpty() && savePose(path);
}

bool MainWindow::deferWhileExporting(const std::function<void()>& again) {
  if (!exporting_) return false;
  abortExport_ = true;
  QTimer::singleShot(20, this, again);
  return true;
}

QString MainWindow::askSavePath(const QString& title, const QString& name, const QString& filter) {
  if (savePathHandler_) return savePathHandler_(title, name);
  return QFileDialog::getSaveFileName(this, title, name, filter);
}

void MainWindow::showError(const QString& message) {
  QString line = message;
  line.replace('\n', ' ');
  statusBar()->showMessage(line, 10000);
  if (errorHandler_)
    errorHandler_(line);
  else
    QMessageBox::critical(this, "Repose", line);
}

bool MainWindow::guarded(const std::function<void()>& action) {
  try {
    action();
    return true;
  } catch (const std::exception& e) {
    QApplication::restoreOverrideCursor();
    showError(e.what());
  } catch (...) {
    QApplication::restoreOverrideCursor();
    showError("unexpected error");
  }
  return false;
}

void MainWindow::updateActions() {
  const bool ready = hasCase() && !isRelaxing();
  undo_->setEnabled(ready && controller_.canUndo());
  redo_->setEnabled(ready && controller_.canRedo());
  for (QAction* a : {savePose_, loadPose_, closeCase_, loadCt_, loadCtSeries_}) a->setEnabled(ready);
  for (QAction* a : export_) a->setEnabled(ready);
  export_[1]->setEnabled(ready && restImage_);  // no save dialog for a CT the case does not have
  export_[4]->setEnabled(ready && animation_->hasClip());
}

// --- opening ---------------------------------------------------------------------------------

void MainWindow::openPhantom(const QString& size, const PrepareSettings& settings) {
  OpenRequest r;
  r.kind = OpenRequest::Phantom;
  r.phantomSize = size;
  r.settings = settings;
  startWorker(r);
}

void MainWindow::openCase(const QString& caseDir) {
  OpenRequest r;
  r.kind = OpenRequest::Case;
  r.caseDir = caseDir;
  startWorker(r);
}

void MainWindow::openScan(const OpenRequest& request) { startWorker(request); }

void MainWindow::startWorker(const OpenRequest& request) {
  if (worker_) return showError("a case is already being opened; cancel it first");
  if (!confirmDiscardPose("opening another case")) return;
  worker_ = new PreprocessWorker(request, this);
  connect(worker_, &PreprocessWorker::progress, start_, &StartPage::setProgress);
  connect(worker_, &QThread::finished, this, &MainWindow::workerFinished);
  stack_->setCurrentWidget(start_);
  for (QDockWidget* dock : findChildren<QDockWidget*>()) dock->setVisible(false);
  start_->setBusy(true);
  worker_->start();
}

void MainWindow::cancelOpening() {
  if (!worker_) return;
  // The running stage (TetGen) cannot be interrupted: the worker stops at the next stage and
  // deletes itself; the window is free at once.
  PreprocessWorker* w = worker_;
  worker_ = nullptr;
  w->cancel();
  disconnect(w, nullptr, this, nullptr);
  disconnect(w, nullptr, start_, nullptr);
  connect(w, &QThread::finished, w, &QObject::deleteLater);
  start_->setBusy(false);
  statusBar()->showMessage("Opening cancelled", 5000);
  if (hasCase()) {
    stack_->setCurrentIndex(1);
    for (QDockWidget* dock : findChildren<QDockWidget*>()) dock->setVisible(true);
  }
}

void MainWindow::workerFinished() {
  // The new case replaces the pipeline an export is writing from: once the export has stopped.
  if (deferWhileExporting([this] { workerFinished(); })) return;
  PreprocessWorker* w = worker_;
  worker_ = nullptr;
  if (!w) return;
  w->deleteLater();
  start_->setBusy(false);
  if (w->cancelled()) return;
  if (!w->error().isEmpty() || !w->result().pipeline) {
    const QString message = w->error().isEmpty() ? "opening failed" : w->error();
    showError(message);
    emit openFailed(message);
    if (hasCase()) {
      stack_->setCurrentIndex(1);
      for (QDockWidget* dock : findChildren<QDockWidget*>()) dock->setVisible(true);
    }
    return;
  }
  if (!guarded([&] { installCase(w->result()); })) {
    dropCase();
    emit openFailed("cannot show the case");
    return;
  }
  emit caseOpened();
}

void MainWindow::installCase(const OpenResult& result) {
  sliceWatcher_.waitForFinished();
  stopRelaxation();
  animation_->pause();
  ++caseGeneration_;
  sliceSampler_.reset();
  pipeline_ = result.pipeline;
  table_ = result.table;
  restImage_ = result.image;
  title_ = result.title;
  relaxed_ = false;
  beforeSurfaces_ = nullptr;
  const Skeleton skeleton = parseSkeletonJson(pipeline_->skeletonJson());
  boneLabels_.clear();
  for (const Joint& j : skeleton.joints) boneLabels_.insert(boneLabels_.end(), j.labels.begin(), j.labels.end());
  pipeline_->setSkinningMethod(skinning_->currentData().toString().toStdString());
  relaxLabel_->setText("Skinning only.");
  stack_->setCurrentIndex(1);
  for (QDockWidget* dock : findChildren<QDockWidget*>()) dock->setVisible(true);
  scene_->setCase(pipeline_->restSurfaces(), skeleton, table_);
  scene_->setSkinOpacity(skinOpacity_->value() / 100.0);
  scene_->setCameraFollow(animation_->cameraFollows());
  animation_->setSkeleton(skeleton);
  // The joint panel rebuilds on skeletonChanged, before this poses (rest) and renders.
  controller_.setSkeleton(skeleton);
  legend_->setCase(pipeline_->restSurfaces(), table_, skeleton);
  slices_->clear();  // a new case: the views fit its grid and centre the cursor
  slices_->setVolumes(pipeline_->restLabels(), restImage_, table_, boneLabels_);
  newSliceSampler();
  slicesRoot_ = rootCentre();
  slicesDirty_ = false;
  setWindowTitle("Repose — " + title_);
  statusBar()->showMessage(QString("Opened %1: %2 nodes, %3 tets, %4 surface triangles")
                               .arg(title_)
                               .arg(pipeline_->restMesh()->GetNumberOfPoints())
                               .arg(pipeline_->restMesh()->GetNumberOfCells())
                               .arg(pipeline_->restSurfaces()->GetNumberOfCells()),
                           10000);
  updateActions();
  scene_->render();
}

void MainWindow::closeCase() {
  if (deferWhileExporting([this] { closeCase(); })) return;
  if (worker_) cancelOpening();
  if (!confirmDiscardPose("closing the case")) return;
  dropCase();
}

void MainWindow::dropCase() {
  sliceWatcher_.waitForFinished();
  stopRelaxation();
  ++caseGeneration_;
  sliceSampler_.reset();
  pipeline_.reset();
  restImage_ = nullptr;
  scene_->clearCase();
  slices_->clear();
  legend_->clear();
  animation_->setSkeleton(Skeleton());
  controller_.setSkeleton(Skeleton());
  stack_->setCurrentWidget(start_);
  for (QDockWidget* dock : findChildren<QDockWidget*>()) dock->setVisible(false);
  setWindowTitle("Repose");
  frameLabel_->clear();
  sliceLabel_->clear();
  updateActions();
}

// --- posing ----------------------------------------------------------------------------------

void MainWindow::poseChanged() {
  if (isRelaxing()) posedWhileRelaxing_ = true;
  if (!pipeline_ || isRelaxing() || controller_.jointCount() == 0) return;
  if (relaxed_) dropRelaxation();
  guarded([&] {
    const auto t0 = Clock::now();
    pipeline_->setPose(controller_.pose());
    pipeline_->posedMesh();
    const auto t1 = Clock::now();
    vtkPolyData* posed = pipeline_->posedSurfaces();
    const auto t2 = Clock::now();
    scene_->setInteractive(controller_.editing() || animation_->playing());
    scene_->updatePose(posed, pipeline_->boneTransforms());
    scene_->render();
    timing_.skinning = std::chrono::duration<double>(t1 - t0).count();
    timing_.surfaces = std::chrono::duration<double>(t2 - t1).count();
    timing_.render = since(t2);
    timing_.total = since(t0);
    frameLabel_->setText(QString("Pose update %1 ms (%2 fps): skinning %3, surfaces %4, render %5 ms")
                             .arg(timing_.total * 1e3, 0, 'f', 1)
                             .arg(1.0 / std::max(timing_.total, 1e-6), 0, 'f', 0)
                             .arg(timing_.skinning * 1e3, 0, 'f', 1)
                             .arg(timing_.surfaces * 1e3, 0, 'f', 1)
                             .arg(timing_.render * 1e3, 0, 'f', 1) +
                         (scene_->interactive() && scene_->interactiveTriangles() > 0
                              ? QString(" (drag view: %1 k triangles)").arg(scene_->interactiveTriangles() / 1000)
                              : QString()));
  });
  slicesDirty_ = true;
  if (!controller_.editing() && !animation_->playing()) requestSliceUpdate();
}

double MainWindow::simulateDrag(double dx, double dy) {
  const int joint = scene_->selectedJoint();
  if (joint < 0 || !scene_->onDragRotate) return 0;
  const auto t0 = Clock::now();
  scene_->onDragRotate(joint, scene_->dragRotation(dx, dy));
  scene_->renderWindow()->WaitForCompletion();
  return since(t0);
}

void MainWindow::showAnimationFrame(int frame) {
  if (!pipeline_ || !animation_->hasClip()) return;
  guarded([&] { controller_.setPose(animation_->pose(frame), false); });
}

bool MainWindow::setSkinning(const QString& method) {
  return guarded([&] {
    if (!pipeline_) return;
    if (isRelaxing()) throw std::runtime_error("wait for the FEM relaxation to finish");
    pipeline_->setSkinningMethod(method.toStdString());
    const int index = skinning_->findData(method);
    if (index >= 0 && index != skinning_->currentIndex()) {
      QSignalBlocker block(skinning_);
      skinning_->setCurrentIndex(index);
    }
    if (relaxed_) dropRelaxation();
    // Re-pose with the new method (the pose itself is unchanged).
    poseChanged();
  });
}

Eigen::Vector3d MainWindow::jointCentre(int joint) const {
  if (joint < 0 || joint >= controller_.jointCount()) return Eigen::Vector3d::Zero();
  return controller_.globalTransforms()[std::size_t(joint)] * controller_.skeleton().joints[std::size_t(joint)].center;
}

Eigen::Vector3d MainWindow::rootCentre() const {
  for (int j = 0; j < controller_.jointCount(); ++j)
    if (controller_.skeleton().joints[std::size_t(j)].parent < 0) return jointCentre(j);
  return Eigen::Vector3d::Zero();
}

void MainWindow::centreSlicesOnSelection() {
  if (!pipeline_ || !slices_->hasVolumes() || controller_.jointCount() == 0) return;
  const int joint = joints_->selectedJoint();
  slices_->centreOn(joint >= 0 ? jointCentre(joint) : rootCentre());
}

// --- posed volumes in the background ---------------------------------------------------------

void MainWindow::newSliceSampler() {
  sliceSampler_ = std::make_shared<PosedVolumeSampler>(pipeline_->restLabels(), restImage_, pipeline_->restMesh());
  // The rest-side work in the background now, not on the first pose's slice update (Visible Human
  // female, 18.7 M voxels: 2.7 s there, 0.6 s for every later pose).
  std::shared_ptr<PosedVolumeSampler> sampler = sliceSampler_;
  static_cast<void>(QtConcurrent::run([sampler] {
    try {
      sampler->warmUp();
    } catch (const std::exception&) {
      // The slice update that follows reports the same error.
    }
  }));
}

void MainWindow::requestSliceUpdate() {
  if (!pipeline_) return;
  slicesDirty_ = true;
  // The FEM thread owns the pipeline while it runs; relaxDone() asks again.
  if (!sliceWatcher_.isRunning() && !isRelaxing()) startSliceUpdate();
}

void MainWindow::startSliceUpdate() {
  slicesDirty_ = false;
  const Pose pose = controller_.pose();
  const bool rest = pose.rotations.empty() && pose.translation.isZero() && !relaxed_;
  // The pipeline's posed nodes change with the next pose: the worker gets its own copy.
  vtkSmartPointer<vtkPoints> posedNodes;
  std::shared_ptr<PosedVolumeSampler> sampler;
  try {
    if (!rest) {
      posedNodes = vtkSmartPointer<vtkPoints>::New();
      posedNodes->DeepCopy(pipeline_->posedMesh()->GetPoints());
    }
    if (!sliceSampler_) newSliceSampler();
    sampler = sliceSampler_;
  } catch (const std::exception&) {
    return;
  }
  const int generation = caseGeneration_;
  const Eigen::Vector3d root = rootCentre();
  double background = 0;
  if (restImage_) background = restImage_->GetPointData()->GetScalars()->GetRange()[0];
  sliceLabel_->setText("Updating the slice views…");
  sliceWatcher_.setFuture(QtConcurrent::run([=]() -> SliceResult {
    SliceResult r;
    r.generation = generation;
    r.root = root;
    const auto t0 = Clock::now();
    try {
      const PosedVolumeSampler::Volumes v = sampler->sample(posedNodes);
      // In patient coordinates for the slice views (off the UI thread: it may reorder every voxel).
      r.labels = lpsAlignedImage(v.labels, true);
      r.image = lpsAlignedImage(v.image, false, background);
    } catch (const std::exception& e) {
      r.error = e.what();
    }
    r.seconds = since(t0);
    return r;
  }));
}

void MainWindow::sliceUpdateFinished() {
  const SliceResult r = sliceWatcher_.result();
  if (r.generation != caseGeneration_ || !pipeline_) return;
  if (!r.error.isEmpty()) {
    sliceLabel_->setText("Slice views not updated");
    showError(r.error);
    return;
  }
  // The cursor travels with the body (a clip's root motion), and the views pan along.
  const Eigen::Vector3d moved = r.root - slicesRoot_;
  const Eigen::Vector3d cursor = slices_->cursorPosition() + moved;
  slices_->setVolumes(r.labels, r.image, table_, boneLabels_);
  if (moved.norm() > 1.0) slices_->centreOn(cursor);
  slicesRoot_ = r.root;
  sliceLabel_->setText(r.seconds > 0 ? QString("Posed volume %1 s").arg(r.seconds, 0, 'f', 2) : QString());
  if (slicesDirty_ && !controller_.editing() && !animation_->playing() && !isRelaxing()) startSliceUpdate();
}

}  // namespace repose
