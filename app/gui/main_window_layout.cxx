// The main window's widgets, docks, menus and actions, built once (MainWindow's constructor).
#include "main_window.h"


#include <QCheckBox>
#include <QComboBox>
#include <QDockWidget>
#include <QFileDialog>
#include <QFormLayout>
#include <QGroupBox>
#include <QLabel>
#include <QMenuBar>
#include <QPushButton>
#include <QSplitter>
#include <QStackedWidget>
#include <QStatusBar>

#include "animation_panel.h"
#include "joint_panel.h"
#include "label_legend.h"
#include "open_scan_dialog.h"
#include "repose_version.h"
#include "scene_view.h"
#include "series_export_dialog.h"
#include "slice_views.h"
#include "start_page.h"

namespace repose {
namespace {

const char* kImageFilter = "NIfTI (*.nii.gz *.nii);;NRRD (*.nrrd);;MetaImage (*.mha)";

}  // namespace

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
  relax_ = new QPushButton(kRelaxButtonText, deformation);
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

}  // namespace repose
