#include "main_window.h"

#include <chrono>
#include <cmath>

#include <QAction>
#include <QApplication>
#include <QCheckBox>
#include <QCloseEvent>
#include <QComboBox>
#include <QDockWidget>
#include <QFileDialog>
#include <QFileInfo>
#include <QFormLayout>
#include <QGroupBox>
#include <QKeyEvent>
#include <QLabel>
#include <QMenuBar>
#include <QMessageBox>
#include <QPushButton>
#include <QSlider>
#include <QSplitter>
#include <QStackedWidget>
#include <QStatusBar>
#include <QTimer>
#include <QVBoxLayout>
#include <QtConcurrent/QtConcurrentRun>
#include <vtkAlgorithm.h>
#include <vtkCommand.h>
#include <vtkDataArray.h>
#include <vtkImageData.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkRenderWindow.h>
#include <vtkUnstructuredGrid.h>
#include <vtkVersion.h>

#include "animation_panel.h"
#include "joint_panel.h"
#include "label_legend.h"
#include "lps_image.h"
#include "open_scan_dialog.h"
#include "repose_pipeline.h"
#include "repose_version.h"
#include "scene_view.h"
#include "series_export_dialog.h"
#include "slice_views.h"
#include "start_page.h"
#include "vtkReposeCorotationalRelax.h"
#include "posed_volume_sampler.h"

namespace repose {
namespace {

const char* const kRelaxText = "Relax soft tissue (FEM)";

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

const char* kImageFilter = "NIfTI (*.nii.gz *.nii);;NRRD (*.nrrd);;MetaImage (*.mha)";

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

void MainWindow::buildWorkspace() {
  auto* workspace = new QSplitter(Qt::Vertical, stack_);
  scene_ = new SceneView(workspace);
  scene_->setMinimumSize(400, 300);
  slices_ = new SliceViews(workspace);
  workspace->addWidget(scene_);
  workspace->addWidget(slices_);
  workspace->setStretchFactor(0, 3);
  workspace->setStretchFactor(1, 1);
  stack_->addWidget(workspace);

  auto dock = [this](const QString& title, const QString& name, QWidget* widget, Qt::DockWidgetArea area) {
    auto* d = new QDockWidget(title, this);
    d->setObjectName(name);
    d->setWidget(widget);
    d->setFeatures(QDockWidget::DockWidgetMovable | QDockWidget::DockWidgetFloatable);
    addDockWidget(area, d);
    return d;
  };
  joints_ = new JointPanel(&controller_, this);
  joints_->setMinimumWidth(270);  // joint names and their angles side by side
  QDockWidget* jointDock = dock("Skeleton and pose", "jointDock", joints_, Qt::LeftDockWidgetArea);

  auto* panel = new QWidget(this);
  auto* layout = new QVBoxLayout(panel);
  auto* display = new QGroupBox("Display", panel);
  auto* displayForm = new QFormLayout(display);
  skinOpacity_ = new QSlider(Qt::Horizontal, display);
  skinOpacity_->setRange(0, 100);
  skinOpacity_->setValue(30);
  displayForm->addRow("Skin opacity:", skinOpacity_);
  auto* showSkeleton = new QCheckBox("Show skeleton", display);
  showSkeleton->setChecked(true);
  displayForm->addRow(showSkeleton);
  auto* overlay = new QSlider(Qt::Horizontal, display);
  overlay->setRange(0, 100);
  overlay->setValue(50);
  displayForm->addRow("Label overlay:", overlay);
  layout->addWidget(display);
  auto* deformation = new QGroupBox("Deformation", panel);
  auto* form = new QFormLayout(deformation);
  skinning_ = new QComboBox(deformation);
  skinning_->addItem("Dual quaternion (DQS)", "dqs");
  skinning_->addItem("Linear blend (LBS)", "lbs");
  skinning_->setToolTip("DQS keeps volume at bent joints; LBS is the classic blend (collapses at large angles)");
  form->addRow("Skinning:", skinning_);
  relax_ = new QPushButton(kRelaxText, deformation);
  relax_->setToolTip("Corotational FEM relaxation of the current pose, bones rigid (Ctrl+F). Runs in the background; "
                     "click again to cancel it.");
  form->addRow(relax_);
  relaxWarmStart_ = new QCheckBox("Start from the last relaxation", deformation);
  relaxWarmStart_->setObjectName("relaxWarmStart");
  relaxWarmStart_->setToolTip(
      "Solve the new pose from the last relaxed one's correction (relaxed minus skinned): after a small pose change "
      "a few Newton steps instead of a whole solve (medium phantom: about 20 s instead of 55 s). Where no fold-free "
      "pose exists (bones pressing together) the result can then depend on the poses relaxed before; off, every "
      "pose is solved from its skinning alone and the same pose always gives the same result.");
  form->addRow(relaxWarmStart_);
  showBefore_ = new QCheckBox("Show before relaxation (wireframe)", deformation);
  showBefore_->setChecked(true);
  form->addRow(showBefore_);
  relaxLabel_ = new QLabel("Skinning only.", deformation);
  relaxLabel_->setWordWrap(true);
  form->addRow(relaxLabel_);
  layout->addWidget(deformation);
  layout->addStretch(1);
  QDockWidget* rightDock = dock("View and deformation", "rightDock", panel, Qt::RightDockWidgetArea);
  legend_ = new LabelLegend(this);
  QDockWidget* legendDock = dock("Legend", "legendDock", legend_, Qt::RightDockWidgetArea);
  animation_ = new AnimationPanel(this);
  QDockWidget* animDock = dock("Motion", "motionDock", animation_, Qt::BottomDockWidgetArea);
  for (QDockWidget* dock : {jointDock, rightDock, legendDock, animDock}) dock->setVisible(false);

  frameLabel_ = new QLabel(this);
  sliceLabel_ = new QLabel(this);
  statusBar()->addPermanentWidget(sliceLabel_);
  statusBar()->addPermanentWidget(frameLabel_);

  connect(skinOpacity_, &QSlider::valueChanged, this, [this](int v) {
    scene_->setSkinOpacity(v / 100.0);
    scene_->render();
  });
  connect(showSkeleton, &QCheckBox::toggled, this, [this](bool on) {
    scene_->setSkeletonVisible(on);
    scene_->render();
  });
  connect(overlay, &QSlider::valueChanged, this, [this](int v) { slices_->setOverlayOpacity(v / 100.0); });
  connect(skinning_, qOverload<int>(&QComboBox::currentIndexChanged), this,
          [this] { setSkinning(skinning_->currentData().toString()); });
  connect(relax_, &QPushButton::clicked, this, [this] {
    if (isRelaxing())
      cancelRelaxation();
    else
      relaxCurrentPose();
  });
  connect(showBefore_, &QCheckBox::toggled, this, [this](bool on) {
    scene_->setGhost(on && relaxed_ ? beforeSurfaces_.Get() : nullptr);
    scene_->render();
  });
  connect(scene_, &SceneView::jointPicked, joints_, &JointPanel::setSelectedJoint);
  connect(legend_, &LabelLegend::jointActivated, joints_, &JointPanel::setSelectedJoint);
  connect(animation_, &AnimationPanel::cameraFollowChanged, this, [this](bool on) { scene_->setCameraFollow(on); });
  connect(joints_, &JointPanel::jointSelected, scene_, &SceneView::setSelectedJoint);
  connect(scene_, &SceneView::dragStarted, &controller_, [this] { controller_.beginEdit(); });
  connect(scene_, &SceneView::dragEnded, &controller_, [this] { controller_.endEdit(); });
  scene_->onDragRotate = [this](int joint, const Eigen::Quaterniond& delta) {
    if (joint >= 0 && !isRelaxing()) controller_.rotateInWorld(joint, delta);
  };
  connect(animation_, &AnimationPanel::frameChanged, this, &MainWindow::showAnimationFrame);
  connect(animation_, &AnimationPanel::loadRequested, this, [this] {
    const QString bvh = QFileDialog::getOpenFileName(this, "Load a motion clip", QString(), "BVH motion (*.bvh);;All files (*)");
    if (bvh.isEmpty()) return;
    const auto answer = QMessageBox::question(
        this, "Joint map", "Use a joint map file (BVH joint -> skeleton joint)?\nNo = the built-in CMU map.",
        QMessageBox::Yes | QMessageBox::No | QMessageBox::Cancel, QMessageBox::No);
    if (answer == QMessageBox::Cancel) return;
    QString map;
    if (answer == QMessageBox::Yes) {
      map = QFileDialog::getOpenFileName(this, "Joint map", QString(), "Joint map (*.json);;All files (*)");
      if (map.isEmpty()) return;
    }
    loadClip(bvh, map);
  });
  connect(animation_, &AnimationPanel::exportRequested, this, [this] { export_[4]->trigger(); });
}

void MainWindow::buildMenus() {
  auto add = [this](QMenu* menu, const QString& text, const QKeySequence& key, std::function<void()> fn) {
    QAction* a = menu->addAction(text);
    if (!key.isEmpty()) a->setShortcut(key);
    connect(a, &QAction::triggered, this, [fn] { fn(); });
    return a;
  };
  QMenu* file = menuBar()->addMenu("&File");
  add(file, "Open built-in &phantom", QKeySequence("Ctrl+Shift+P"), [this] { openPhantom(start_->phantomSize()); });
  add(file, "&Open prepared case…", QKeySequence::Open, [this] {
    const QString dir = QFileDialog::getExistingDirectory(this, "Open a prepared case");
    if (!dir.isEmpty()) openCase(dir);
  });
  add(file, "Open &scan…", QKeySequence("Ctrl+Shift+O"), [this] {
    OpenScanDialog dialog(this);
    if (dialog.exec() == QDialog::Accepted) openScan(dialog.request());
  });
  loadCt_ = add(file, "Load &CT for this case…", QKeySequence(), [this] {
    const QString p = QFileDialog::getOpenFileName(this, "CT on the label grid", QString(),
                                                   "Images (*.nii *.nii.gz *.nrrd *.nhdr *.mha *.mhd)");
    if (!p.isEmpty()) loadRestImage(p);
  });
  loadCtSeries_ = add(file, "Load CT from a &DICOM series…", QKeySequence(), [this] {
    const QString dir = QFileDialog::getExistingDirectory(this, "DICOM CT series on the label grid");
    if (!dir.isEmpty()) loadRestImage(dir);
  });
  file->addSeparator();
  loadPose_ = add(file, "&Load pose…", QKeySequence("Ctrl+L"), [this] {
    const QString p = QFileDialog::getOpenFileName(this, "Load pose", QString(), "Pose (*.json)");
    if (!p.isEmpty()) loadPose(p);
  });
  savePose_ = add(file, "&Save pose…", QKeySequence::Save, [this] {
    const QString p = askSavePath("Save pose", "pose.json", "Pose (*.json)");
    if (!p.isEmpty()) savePose(p);
  });
  file->addSeparator();
  QMenu* exportMenu = file->addMenu("&Export");
  export_[0] = add(exportMenu, "Posed &label volume…", QKeySequence("Ctrl+E"), [this] {
    const QString p = askSavePath("Export posed label volume", "posed_labels.nii.gz", kImageFilter);
    if (!p.isEmpty()) exportPosedLabels(p);
  });
  export_[1] = add(exportMenu, "Posed &CT…", QKeySequence("Ctrl+Shift+E"), [this] {
    if (!restImage_) return showError("no CT for this case (File > Load CT for this case)");
    const QString p = askSavePath("Export posed CT", "posed_image.nii.gz", kImageFilter);
    if (!p.isEmpty()) exportPosedImage(p);
  });
  export_[2] = add(exportMenu, "Posed tet &mesh (.vtu)…", QKeySequence(), [this] {
    const QString p = askSavePath("Export posed mesh", "posed_mesh.vtu", "VTK mesh (*.vtu)");
    if (!p.isEmpty()) exportPosedMesh(p);
  });
  export_[3] = add(exportMenu, "Posed &surfaces (.vtp)…", QKeySequence(), [this] {
    const QString p = askSavePath("Export posed surfaces", "posed_surfaces.vtp", "VTK surfaces (*.vtp)");
    if (!p.isEmpty()) exportPosedSurfaces(p);
  });
  export_[4] = add(exportMenu, "&Animation series (.pvd)…", QKeySequence(), [this] {
    if (!pipeline_ || !animation_->hasClip()) return showError("no motion loaded (Motion > Load motion)");
    // Size per frame: the posed mesh and surfaces written as they are held (about what the files take).
    const double mb = (pipeline_->restMesh()->GetActualMemorySize() + pipeline_->restSurfaces()->GetActualMemorySize()) / 1024.0;
    SeriesExportDialog dialog(animation_->frameCount(), animation_->frameTime(), mb, this);
    if (dialog.exec() != QDialog::Accepted) return;
    const SeriesExportSettings s = dialog.settings();
    exportAnimation(s.dir, s.stride, s.first, s.last);
  });
  export_[5] = add(file, "Screens&hot of the 3D view…", QKeySequence("F12"), [this] {
    const QString p = askSavePath("Screenshot", "repose.png", "PNG image (*.png)");
    if (!p.isEmpty()) exportScreenshot(p);
  });
  file->addSeparator();
  closeCase_ = add(file, "&Close case", QKeySequence::Close, [this] { closeCase(); });
  closeCase_->setObjectName("closeCase");
  export_[0]->setObjectName("exportPosedLabels");
  export_[1]->setObjectName("exportPosedCt");
  export_[4]->setObjectName("exportSeries");
  add(file, "&Quit", QKeySequence::Quit, [this] { close(); });

  QMenu* edit = menuBar()->addMenu("&Edit");
  undo_ = add(edit, "&Undo pose change", QKeySequence::Undo, [this] { controller_.undo(); });
  redo_ = add(edit, "&Redo pose change", QKeySequence("Ctrl+Shift+Z"), [this] { controller_.redo(); });
  redo_->setShortcuts({QKeySequence("Ctrl+Shift+Z"), QKeySequence("Ctrl+Y")});
  add(edit, "Reset &joint", QKeySequence("Ctrl+R"), [this] {
    if (joints_->selectedJoint() >= 0) controller_.resetJoint(joints_->selectedJoint());
  });
  add(edit, "Reset &all joints", QKeySequence("Ctrl+Shift+R"), [this] { controller_.resetAll(); });
  add(edit, "Relax soft tissue (&FEM)", QKeySequence("Ctrl+F"), [this] { relaxCurrentPose(); });

  QMenu* view = menuBar()->addMenu("&View");
  add(view, "&Reset camera", QKeySequence("Ctrl+0"), [this] {
    scene_->resetCamera();
    scene_->render();
  })->setObjectName("resetCamera");
  add(view, "&Centre slices on the selected joint", QKeySequence("Ctrl+Shift+C"), [this] { centreSlicesOnSelection(); });

  QMenu* motion = menuBar()->addMenu("&Motion");
  add(motion, "&Load motion (BVH)…", QKeySequence("Ctrl+B"), [this] { emit animation_->loadRequested(); });
  add(motion, "&Play / pause", QKeySequence(Qt::Key_Space), [this] { animation_->togglePlay(); })->setObjectName("playPause");
  add(motion, "&Next frame", QKeySequence("Ctrl+Right"), [this] { animation_->stepFrames(1); });
  add(motion, "P&revious frame", QKeySequence("Ctrl+Left"), [this] { animation_->stepFrames(-1); });

  QMenu* help = menuBar()->addMenu("&Help");
  add(help, "&Controls", QKeySequence::HelpContents, [this] {
    QMessageBox::information(
        this, "Controls",
        "3D view: left-drag on a bone rotates its joint; left-drag elsewhere turns the camera; right-drag "
        "zooms; middle-drag pans.\nSlice views: click moves the linked cursor; left-drag sets window/level; "
        "sliders choose the slices; hover names the structure.\nSlices are shown as in 3D Slicer: axial from the "
        "feet and coronal from the front (the patient's left on screen right), sagittal from the patient's left "
        "(anterior on screen left); View > Centre slices on the selected joint (Ctrl+Shift+C).\nThe slice views "
        "show the posed volume when a drag ends.\nJoint angles: flexion, abduction and internal rotation positive "
        "on either side (spine: bending forwards, to the right, turning to the left).");
  });
  add(help, "&About Repose", QKeySequence(), [this] { QMessageBox::about(this, "About Repose", aboutText()); });
  for (QAction* a : findChildren<QAction*>())
    if (!a->shortcuts().isEmpty()) shortcutActions_.push_back(a);
}

QString MainWindow::aboutText() const {
  return QString("<b>Repose %1</b><p>Reposes segmented CT/MRI scans: label volume and skeleton in, the same "
                 "anatomy in a new pose out (posed labels and CT, tet mesh, surfaces).</p>"
                 "<p>Qt %2, VTK %3. The body is meshed by TetGen (AGPL).</p>")
      .arg(REPOSE_VERSION, qVersion(), vtkVersion::GetVTKVersion());
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
  relax_->setText(kRelaxText);
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
