// The main window on the tiny phantom, driven like a user: open (background preprocessing), pose
// through the joint controls and by dragging in the 3D view, undo, export, motion capture, FEM,
// errors as messages, and an image baseline of the 3D view. Needs an X display (xvfb-run).
#include <functional>
#include <map>

#include <QAction>
#include <QCheckBox>
#include <QDoubleSpinBox>
#include <QHeaderView>
#include <QTreeWidget>
#include <QDir>
#include <QFileInfo>
#include <QMouseEvent>
#include <QSignalSpy>
#include <QSlider>
#include <QSurfaceFormat>
#include <QVTKOpenGLNativeWidget.h>
#include <QtTest>
#include <vtkActor.h>
#include <vtkCamera.h>
#include <vtkMapper.h>
#include <vtkDataArray.h>
#include <vtkImageData.h>
#include <vtkImageDifference.h>
#include <vtkPNGReader.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkRenderer.h>
#include <vtkCellArray.h>
#include <vtkIdList.h>
#include <vtkMath.h>
#include <QTimer>
#include <vtkRenderWindow.h>
#include <vtkWindowToImageFilter.h>
#include <vtkUnstructuredGrid.h>

#include "animation_panel.h"
#include "joint_panel.h"
#include "label_colors.h"
#include "preprocess_worker.h"
#include "vtkReposePhantomSource.h"
#include "label_legend.h"
#include "atomic_outputs.h"
#include "repose_version.h"
#include "main_window.h"
#include "repose_pipeline.h"
#include "scene_view.h"
#include "series_export_dialog.h"
#include "slice_views.h"
#include "vtkReposeCorotationalRelax.h"

using namespace repose;

namespace {
double boundsDistance(const double a[6], const double b[6]) {
  double d = 0;
  for (int i = 0; i < 6; ++i) d = std::max(d, std::fabs(a[i] - b[i]));
  return d;
}
QString outDir() { return QString(REPOSE_GUI_TEST_OUT); }

/// Centroid of a label in physical (LPS) millimetres.
Eigen::Vector3d centroid(vtkImageData* image, int label, long* voxels = nullptr) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  long count = 0;
  int e[6];
  image->GetExtent(e);
  for (int k = e[4]; k <= e[5]; ++k)
    for (int j = e[2]; j <= e[3]; ++j)
      for (int i = e[0]; i <= e[1]; ++i)
        if (int(image->GetScalarComponentAsDouble(i, j, k, 0)) == label) {
          double x[3];
          const int ijk[3] = {i, j, k};
          image->TransformIndexToPhysicalPoint(ijk, x);
          sum += Eigen::Vector3d(x[0], x[1], x[2]);
          ++count;
        }
  if (voxels) *voxels = count;
  return sum / std::max(count, 1L);
}

/// Compares a PNG with Testing/Data/Baseline/<name>.png (VTK's image difference); a missing or
/// different baseline leaves the candidate in Testing/Temporary.
void compareWithBaseline(const QString& candidate, const QString& name) {
  const QString baseline = QString(REPOSE_BASELINE_DIR) + "/" + name + ".png";
  QDir().mkpath(REPOSE_TEMPORARY_DIR);
  const QString keep = QString(REPOSE_TEMPORARY_DIR) + "/" + name + ".png";
  if (!QFileInfo::exists(baseline)) {
    QFile::remove(keep);
    QFile::copy(candidate, keep);
    QFAIL(qPrintable("no baseline " + baseline + "; candidate written to " + keep));
  }
  vtkNew<vtkPNGReader> a, b;
  a->SetFileName(candidate.toUtf8().constData());
  b->SetFileName(baseline.toUtf8().constData());
  vtkNew<vtkImageDifference> diff;
  diff->SetInputConnection(a->GetOutputPort());
  diff->SetImageConnection(b->GetOutputPort());
  diff->Update();
  const double error = diff->GetThresholdedError();
  qInfo("%s: thresholded image error %.3f (threshold 10)", qPrintable(name), error);
  if (error > 10) {
    QFile::remove(keep);
    QFile::copy(candidate, keep);
  }
  QVERIFY2(error <= 10, qPrintable(QString("image differs from the baseline; candidate in %1").arg(keep)));
}
}  // namespace

class TestMainWindow : public QObject {
  Q_OBJECT
  MainWindow* window_ = nullptr;
  QStringList errors_, questions_, savePrompts_;
  QList<QMessageBox::StandardButton> answers_;  // the next questions' answers; then Discard (or Yes)
  double restTissue_[6], restSkin_[6];

  /// The slice views' pixel at display position `at` (3 pixels off the cursor lines) shows `label`'s
  /// overlay colour, not `other`'s (the overlay is opaque).
  bool pixelIsLabel(SliceViews::View view, const Eigen::Vector2d& at, int label, int other) {
    window_->slices()->render();
    vtkNew<vtkWindowToImageFilter> grab;
    grab->SetInput(window_->slices()->renderWindow(view));
    grab->ReadFrontBufferOff();
    grab->Update();
    double rgb[3], want[3], alt[3];
    const int x = int(std::lround(at.x())) + 3, y = int(std::lround(at.y())) + 3;
    for (int c = 0; c < 3; ++c) rgb[c] = grab->GetOutput()->GetScalarComponentAsDouble(x, y, 0, c) / 255.0;
    labelColor(label, window_->labelTable(), true, want);
    labelColor(other, window_->labelTable(), true, alt);
    const double toWant = std::sqrt(vtkMath::Distance2BetweenPoints(rgb, want));
    const double toAlt = std::sqrt(vtkMath::Distance2BetweenPoints(rgb, alt));
    qInfo("pixel (%d, %d) of view %d: %.3f %.3f %.3f; label %d at %.3f, label %d at %.3f", x, y, int(view), rgb[0],
          rgb[1], rgb[2], label, toWant, other, toAlt);
    return toWant < 3.0 / 255 && toWant < toAlt;
  }

  void compareSlicesWithBaseline(SliceViews* slices, const QString& name) {
    const QSize size = slices->size();
    slices->setFixedSize(900, 320);
    QApplication::processEvents();
    slices->render();
    const QString candidate = outDir() + "/" + name + ".png";
    // RGB: VTK's image difference compares three components.
    QVERIFY(slices->grab().toImage().convertToFormat(QImage::Format_RGB888).save(candidate));
    slices->setMinimumSize(0, 0);
    slices->setMaximumSize(QWIDGETSIZE_MAX, QWIDGETSIZE_MAX);
    slices->resize(size);
    compareWithBaseline(candidate, name);
  }

  /// While dragging, skin and bones are drawn from a decimated copy whose vertices follow the posed
  /// surfaces. Clustering once merged vertices of separate parts that shared a grid cell (the inner
  /// thighs, a femoral head and its socket), whose triangles then stretched across the gap as a web
  /// when a bone moved. A coarse edge must stretch no more than the full surface does.
  void checkDragPreview(const std::function<void()>& pose) {
    auto* c = window_->controller();
    SceneView* scene = window_->scene();
    QVERIFY2(scene->interactiveTriangles() > 0, "no drag preview");
    using Lengths = std::map<std::pair<vtkIdType, vtkIdType>, double>;
    auto edges = [](vtkPolyData* surface) {
      Lengths lengths;
      auto ids = vtkSmartPointer<vtkIdList>::New();
      vtkCellArray* polys = surface->GetPolys();
      for (polys->InitTraversal(); polys->GetNextCell(ids);)
        for (vtkIdType k = 0; k < ids->GetNumberOfIds(); ++k) {
          const vtkIdType a = ids->GetId(k), b = ids->GetId((k + 1) % ids->GetNumberOfIds());
          double p[3], q[3];
          surface->GetPoint(a, p);
          surface->GetPoint(b, q);
          lengths[{std::min(a, b), std::max(a, b)}] = std::sqrt(vtkMath::Distance2BetweenPoints(p, q));
        }
      return lengths;
    };
    // Largest stretch (posed / rest length) of an edge, and the longest posed edge.
    auto stretch = [](const Lengths& rest, const Lengths& posed, double& longest) {
      double worst = 0;
      longest = 0;
      for (const auto& [edge, length] : posed) {
        worst = std::max(worst, length / std::max(rest.at(edge), 1e-3));
        longest = std::max(longest, length);
      }
      return worst;
    };
    c->beginEdit();  // as a drag does: the preview is shown and follows the pose
    const int root = 0;
    c->setAngles(root, c->angles(root) + Eigen::Vector3d(0.01, 0, 0));
    QVERIFY(scene->interactive());
    Lengths coarseRest[2], fullRest[2];
    vtkPolyData* full[2] = {vtkPolyData::SafeDownCast(scene->skinActor()->GetMapper()->GetInput()),
                            vtkPolyData::SafeDownCast(scene->tissueActor()->GetMapper()->GetInput())};
    for (int w : {0, 1}) coarseRest[w] = edges(scene->interactiveSurface(w)), fullRest[w] = edges(full[w]);
    pose();
    for (int w : {0, 1}) {
      double coarseLongest, fullLongest;
      const double coarse = stretch(coarseRest[w], edges(scene->interactiveSurface(w)), coarseLongest);
      const double fine = stretch(fullRest[w], edges(full[w]), fullLongest);
      qInfo("drag preview %s: %lld triangles; largest edge stretch %.2f (full surface %.2f), longest edge %.1f mm (full %.1f mm)",
            w ? "tissues" : "skin", (long long)scene->interactiveSurface(w)->GetNumberOfPolys(), coarse, fine,
            coarseLongest, fullLongest);
      QVERIFY2(coarse <= 1.5 * fine, "a preview triangle stretched across separate parts");
    }
    c->endEdit();
    QVERIFY(!scene->interactive());
  }

  /// Share of a slice view's pixels that are not black: the view shows anatomy.
  double nonBackgroundFraction(SliceViews::View view) {
    window_->slices()->render();
    vtkNew<vtkWindowToImageFilter> grab;
    grab->SetInput(window_->slices()->renderWindow(view));
    grab->ReadFrontBufferOff();
    grab->Update();
    vtkImageData* image = grab->GetOutput();
    const vtkIdType n = image->GetNumberOfPoints();
    vtkIdType lit = 0;
    for (vtkIdType i = 0; i < n; ++i) {
      double m = 0;
      for (int c = 0; c < 3; ++c) m = std::max(m, image->GetPointData()->GetScalars()->GetComponent(i, c));
      lit += m > 20;
    }
    return double(lit) / std::max<vtkIdType>(n, 1);
  }

private slots:
  void initTestCase() {
    QDir(outDir()).removeRecursively();
    QDir().mkpath(outDir());
    window_ = new MainWindow;
    window_->setErrorHandler([this](const QString& m) { errors_ << m; });
    window_->setQuestionHandler([this](const QString& q, QMessageBox::StandardButtons buttons) {
      questions_ << q;
      if (!answers_.isEmpty()) return answers_.takeFirst();
      return (buttons & QMessageBox::Discard) ? QMessageBox::Discard : QMessageBox::Yes;
    });
    window_->setSavePathHandler([this](const QString& title, const QString&) {
      savePrompts_ << title;
      return QString();  // cancelled
    });
    // The tiny phantom gets the decimated drag preview too (real scans have it by size).
    window_->scene()->setLodThreshold(20000);
    window_->resize(1400, 900);
    window_->show();
    QVERIFY(QTest::qWaitForWindowExposed(window_));
  }
  void cleanupTestCase() { delete window_; }

  void cancelThenOpenPhantom() {
    // Cancel returns at once; the abandoned worker stops at its next stage on its own.
    window_->openPhantom("tiny");
    QVERIFY(window_->isOpening());
    window_->cancelOpening();
    QVERIFY(!window_->isOpening());
    QVERIFY(!window_->hasCase());

    QSignalSpy opened(window_, &MainWindow::caseOpened);
    window_->openPhantom("tiny");
    QVERIFY(window_->isOpening());
    // The UI thread stays free while preparing: events are processed by qWait inside QTRY.
    QTRY_VERIFY_WITH_TIMEOUT(!window_->isOpening(), 180000);
    QVERIFY2(window_->hasCase(), qPrintable(errors_.join("; ")));
    QCOMPARE(opened.count(), 1);
    QVERIFY(window_->controller()->jointCount() >= 10);
    QVERIFY(window_->scene()->tissueActor()->GetMapper()->GetInput()->GetNumberOfCells() > 1000);
    window_->scene()->tissueActor()->GetBounds(restTissue_);
    window_->scene()->skinActor()->GetBounds(restSkin_);
    QVERIFY(restSkin_[5] - restSkin_[4] > 500);  // the whole body, head to feet
  }

  void rotateJointThroughControlsAndUndo() {
    const int hip = window_->controller()->skeleton().find("left_hip");
    QVERIFY(hip >= 0);
    window_->jointPanel()->setSelectedJoint(hip);
    QCOMPARE(window_->scene()->selectedJoint(), hip);
    QSlider* flexion = window_->jointPanel()->slider(0);
    QVERIFY(flexion->isEnabled());
    QVERIFY(window_->jointPanel()->axisCaption(0).startsWith("Flexion (+)"));
    flexion->setValue(70);  // as keyboard or a click on the slider track does: one step
    QVERIFY(std::fabs(window_->controller()->angles(hip).x() - 70) < 1e-9);
    double tissue[6], skin[6];
    window_->scene()->tissueActor()->GetBounds(tissue);
    window_->scene()->skinActor()->GetBounds(skin);
    // The femur swings forward (LPS: anterior is -y): bones and skin reach further to the front.
    QVERIFY2(tissue[2] < restTissue_[2] - 100, "bones did not move forward");
    QVERIFY2(skin[2] < restSkin_[2] - 100, "skin did not move forward");
    QVERIFY(window_->lastFrameTiming().total > 0);
    QVERIFY(window_->lastFrameTiming().skinning > 0);
    window_->controller()->undo();
    QVERIFY(window_->controller()->pose().rotations.empty());
    window_->scene()->tissueActor()->GetBounds(tissue);
    QVERIFY(boundsDistance(tissue, restTissue_) < 1e-3);
    window_->controller()->redo();
    window_->scene()->tissueActor()->GetBounds(tissue);
    QVERIFY(tissue[2] < restTissue_[2] - 100);
    window_->controller()->resetAll();
  }

  void dragBoneInTheView() {
    SceneView* scene = window_->scene();
    const int knee = window_->controller()->skeleton().find("right_knee");
    QVERIFY(knee >= 0);
    // Press on the middle of the right shin (below the knee centre) and drag sideways.
    const Eigen::Vector3d c = window_->controller()->skeleton().joints[std::size_t(knee)].center;
    const Eigen::Vector3d shin = c + Eigen::Vector3d(0, 0, -120);
    vtkRenderer* r = scene->renderer();
    r->SetWorldPoint(shin.x(), shin.y(), shin.z(), 1.0);
    r->WorldToDisplay();
    double d[3];
    r->GetDisplayPoint(d);
    const double ratio = scene->devicePixelRatioF();
    const QPoint press(int(d[0] / ratio), int(scene->height() - d[1] / ratio));
    QCOMPARE(scene->pickJoint(int(d[0]), int(d[1])), knee);
    QWidget* target = scene;
    auto send = [&](QEvent::Type type, QPoint at, Qt::MouseButton button, Qt::MouseButtons buttons) {
      QMouseEvent e(type, at, scene->mapToGlobal(at), button, buttons, Qt::NoModifier);
      QApplication::sendEvent(target, &e);
    };
    const bool couldUndo = window_->controller()->canUndo();
    send(QEvent::MouseButtonPress, press, Qt::LeftButton, Qt::LeftButton);
    QCOMPARE(scene->selectedJoint(), knee);
    QCOMPARE(window_->jointPanel()->selectedJoint(), knee);
    // Downwards (seen from the front): the shin swings back about the left-right axis, knee flexion.
    for (int i = 1; i <= 10; ++i) send(QEvent::MouseMove, press + QPoint(0, 5 * i), Qt::NoButton, Qt::LeftButton);
    send(QEvent::MouseButtonRelease, press + QPoint(0, 50), Qt::LeftButton, Qt::NoButton);
    QVERIFY2(window_->controller()->angles(knee).x() > 10, qPrintable(QString::number(window_->controller()->angles(knee).x())));
    QVERIFY(window_->scene()->pickedCaption().startsWith("tibia_right (label 27)"));
    QVERIFY(!window_->controller()->editing());
    QVERIFY(window_->controller()->canUndo());
    double tissue[6];
    scene->tissueActor()->GetBounds(tissue);
    QVERIFY(boundsDistance(tissue, restTissue_) > 10);
    // The whole drag is one undo step.
    window_->controller()->undo();
    QVERIFY(window_->controller()->angles(knee).isZero(1e-6));
    QCOMPARE(window_->controller()->canUndo(), couldUndo);
    // Slice views follow in the background once the drag is over.
    QTRY_VERIFY_WITH_TIMEOUT(!window_->slicesPending(), 60000);
  }

  void exportPosedOutputs() {
    const int hip = window_->controller()->skeleton().find("left_hip");
    const int knee = window_->controller()->skeleton().find("left_knee");
    window_->controller()->setAngles(hip, {60, 0, 0});  // flexion
    window_->controller()->setAngles(knee, {45, 0, 0});
    const QString labels = outDir() + "/posed_labels.nii.gz";
    QVERIFY(window_->exportPosedLabels(labels));
    QVERIFY(window_->exportPosedSurfaces(outDir() + "/posed_surfaces.vtp"));
    QVERIFY(window_->exportPosedMesh(outDir() + "/posed_mesh.vtu"));
    QVERIFY(window_->savePose(outDir() + "/pose.json"));
    QVERIFY(window_->exportScreenshot(outDir() + "/screenshot.png"));
    for (const char* f : {"posed_surfaces.vtp", "posed_mesh.vtu", "pose.json", "screenshot.png", "posed_labels.tsv"})
      QVERIFY2(QFileInfo(outDir() + "/" + f).size() > 100, f);
    // The names travel with the volume, and the pose file reads as axis and degrees.
    QVERIFY(readLabelTableFile((outDir() + "/posed_labels.tsv").toStdString()).nameOf(24) == "femur_left");
    const QString poseText = QString::fromStdString(readTextFile((outDir() + "/pose.json").toStdString()));
    QVERIFY2(poseText.contains("\"degrees\" : 60") && !poseText.contains("quaternion"), qPrintable(poseText));
    // The posed volume on disk: the rigid femur keeps its voxel count and moves forward with the flexed hip.
    auto posed = readLabelVolume(labels.toStdString());
    vtkImageData* rest = window_->pipeline()->restLabels();
    long femurPosed = 0, femurRest = 0;
    const Eigen::Vector3d posedCentre = centroid(posed, 24, &femurPosed);  // femur_left
    const Eigen::Vector3d restCentre = centroid(rest, 24, &femurRest);
    QVERIFY(femurRest > 0);
    QVERIFY2(std::fabs(double(femurPosed) / femurRest - 1) < 0.15, "the rigid femur changed size");
    QVERIFY2(posedCentre.y() < restCentre.y() - 50, "the femur did not move forward");
    // Reset, then the saved pose brings it back.
    window_->controller()->resetAll();
    QVERIFY(window_->loadPose(outDir() + "/pose.json"));
    QVERIFY(std::fabs(window_->controller()->angles(hip).x() - 60) < 1e-6);
    QVERIFY(std::fabs(window_->controller()->angles(knee).x() - 45) < 1e-6);
    QVERIFY(!window_->controller()->hasUnsavedPose());  // just loaded
    QVERIFY(errors_.isEmpty());
  }

  void posedViewMatchesBaseline() {
    // A known pose, a fixed view size and camera: compare with Testing/Data/Baseline.
    window_->controller()->resetAll();
    auto* c = window_->controller();
    c->setAngles(c->skeleton().find("left_hip"), {60, 0, 0});       // flexion
    c->setAngles(c->skeleton().find("left_knee"), {45, 0, 0});      // flexion
    c->setAngles(c->skeleton().find("right_shoulder"), {0, 80, 0});  // abduction
    c->setAngles(c->skeleton().find("right_elbow"), {90, 0, 0});     // flexion
    window_->scene()->setSelectedJoint(c->skeleton().find("left_knee"));
    window_->scene()->pickJoint(0, 0);  // a miss: no caption from an earlier click
    window_->scene()->setFixedSize(500, 500);
    QApplication::processEvents();
    window_->scene()->resetCamera();
    window_->scene()->renderer()->GetActiveCamera()->Azimuth(40);  // oblique: the flexions show
    window_->scene()->renderer()->ResetCamera();
    const QString candidate = outDir() + "/GuiPosedView.png";
    QVERIFY(window_->exportScreenshot(candidate));
    window_->scene()->setMinimumSize(400, 300);
    window_->scene()->setMaximumSize(QWIDGETSIZE_MAX, QWIDGETSIZE_MAX);
    compareWithBaseline(candidate, "GuiPosedView");
  }

  void motionCapture() {
    const int hip = window_->controller()->skeleton().find("left_hip");
    window_->controller()->resetAll();
    window_->controller()->setAngles(hip, {10, 0, 0});
    window_->controller()->setAngles(hip, {20, 0, 0});
    const QString mocap = QString(REPOSE_SHARED_DATA) + "/mocap";
    const QString walk = mocap + "/cmu_131_01_walk.bvh";
    if (!QFileInfo::exists(walk)) QSKIP("shared motion capture data not available");
    // Over a hand pose the clip asks first; declined, nothing changes.
    answers_ = {QMessageBox::No};
    QVERIFY(!window_->loadClip(walk));
    QCOMPARE(questions_.size(), 1);
    QVERIFY(questions_[0].contains("Undo"));
    QVERIFY(!window_->animation()->hasClip());
    QVERIFY(std::fabs(window_->controller()->angles(hip).x() - 20) < 1e-6);
    answers_ = {QMessageBox::Yes};
    QVERIFY2(window_->loadClip(walk), qPrintable(errors_.join("; ")));
    AnimationPanel* anim = window_->animation();
    QVERIFY(anim->frameCount() > 700);
    double tissue[6], previous[6];
    anim->setFrame(500);
    QCOMPARE(anim->frame(), 500);
    QVERIFY(!window_->controller()->pose().rotations.empty());
    window_->scene()->tissueActor()->GetBounds(previous);
    QVERIFY(boundsDistance(previous, restTissue_) > 5);
    anim->stepFrames(10);
    QCOMPARE(anim->frame(), 510);
    window_->scene()->tissueActor()->GetBounds(tissue);
    QVERIFY2(boundsDistance(tissue, previous) > 1, "the 3D view did not follow the frame");
    anim->stepFrames(-1);
    QCOMPARE(anim->frame(), 509);
    // Playing advances in real time.
    anim->play();
    QVERIFY(anim->playing());
    QTRY_VERIFY_WITH_TIMEOUT(anim->frame() > 520, 10000);
    anim->pause();
    QVERIFY(!anim->playing());
    // Frames do not fill the undo history: one undo brings back the hand pose the clip replaced.
    window_->controller()->undo();
    QVERIFY(std::fabs(window_->controller()->angles(hip).x() - 20) < 1e-6);
    window_->controller()->resetAll();
    // Keep root in place (default): the walk's root does not travel; off, it does, and the camera follows.
    QVERIFY(anim->keepRootInPlace());
    anim->setFrame(900);
    QVERIFY(window_->controller()->pose().translation.isZero());
    double focal[3], moved[3];
    window_->scene()->renderer()->GetActiveCamera()->GetFocalPoint(focal);
    anim->setKeepRootInPlace(false);
    const Eigen::Vector3d travel = window_->controller()->pose().translation;
    QVERIFY2(travel.norm() > 500, "the walk's root should travel without keep-in-place");
    window_->scene()->renderer()->GetActiveCamera()->GetFocalPoint(moved);
    QVERIFY((Eigen::Vector3d(moved[0], moved[1], moved[2]) - Eigen::Vector3d(focal[0], focal[1], focal[2])).norm() > 0.9 * travel.norm());
    // The slice views follow the body too: they still show anatomy at the cursor.
    QTRY_VERIFY_WITH_TIMEOUT(!window_->slicesPending(), 60000);
    QVERIFY2(window_->slices()->labelAtCursor() != 0 || nonBackgroundFraction(SliceViews::Axial) > 0.05,
             "the slice views lost the body");
    anim->setKeepRootInPlace(true);
    window_->controller()->resetAll();
    // A short clip exported as a ParaView series: every 25th frame, then a range with a stride.
    const QString shortClip = mocap + "/cmu_short_75frames.bvh";
    QVERIFY(window_->loadClip(shortClip));
    QVERIFY(window_->exportAnimation(outDir() + "/series", 25));
    QVERIFY(QFileInfo::exists(outDir() + "/series/animation.pvd"));
    QCOMPARE(QDir(outDir() + "/series/frames").entryList(QDir::Files).size(), 6);  // 3 frames x mesh+surfaces
    QVERIFY(QFileInfo::exists(outDir() + "/series/labels.tsv"));
    QVERIFY(window_->exportAnimation(outDir() + "/range", 10, 20, 40));
    const QStringList range = QDir(outDir() + "/range/frames").entryList(QDir::Files);
    QCOMPARE(range, QStringList({"mesh_00020.vtu", "mesh_00030.vtu", "mesh_00040.vtu", "surfaces_00020.vtp",
                                 "surfaces_00030.vtp", "surfaces_00040.vtp"}));
    QVERIFY(errors_.isEmpty());
  }

  void badInputIsAMessage() {
    errors_.clear();
    QVERIFY(!window_->loadPose(outDir() + "/no_such_pose.json"));
    QCOMPARE(errors_.size(), 1);
    QVERIFY(errors_[0].contains("no_such_pose.json"));
    QVERIFY(!errors_[0].contains('\n'));
    QVERIFY(!window_->loadClip(outDir() + "/pose.json"));  // not a BVH
    QCOMPARE(errors_.size(), 2);
    QVERIFY(!window_->exportPosedImage(outDir() + "/ct.nii.gz"));  // the phantom has no CT
    QCOMPARE(errors_.size(), 3);
    QVERIFY(!window_->loadRestImage(outDir() + "/screenshot.png"));  // not on the label grid
    QCOMPARE(errors_.size(), 4);
    QVERIFY(window_->hasCase());
    // A broken case directory: the window keeps the open case.
    QSignalSpy failed(window_, &MainWindow::openFailed);
    window_->openCase(outDir());
    QTRY_VERIFY_WITH_TIMEOUT(!window_->isOpening(), 30000);
    QCOMPARE(failed.count(), 1);
    QVERIFY(errors_.last().contains("manifest.json"));
    QVERIFY(window_->hasCase());
  }

  void femRelaxationBeforeAfter() {
    errors_.clear();
    window_->animation()->pause();
    auto* c = window_->controller();
    c->resetAll();
    c->setAngles(c->skeleton().find("left_hip"), {45, 0, 0});
    QSignalSpy done(window_, &MainWindow::relaxFinished);
    window_->relaxCurrentPose();
    QVERIFY(window_->isRelaxing());
    // The label follows the solver.
    QTRY_VERIFY_WITH_TIMEOUT(window_->relaxationStatus().contains("Newton step") || !window_->isRelaxing(), 60000);
    QVERIFY2(window_->isRelaxing(), "the solver's progress was not shown while it ran");
    // Posing is held while the FEM thread owns the pipeline.
    c->setAngles(c->skeleton().find("left_knee"), {30, 0, 0});
    QTRY_VERIFY_WITH_TIMEOUT(!window_->isRelaxing(), 120000);
    QVERIFY2(errors_.isEmpty(), qPrintable(errors_.join("; ")));
    QCOMPARE(done.count(), 1);
    qInfo("relaxation: %s", qPrintable(window_->relaxationSummary()));
    QVERIFY(window_->relaxationSummary().contains("CG iterations"));
    // The knee set meanwhile is shown once the solver is done (skinning again, up to date).
    QVERIFY(!window_->pipeline()->relaxationSummary().size());
    // Posing again returns to interactive skinning.
    c->setAngles(c->skeleton().find("left_hip"), {50, 0, 0});
    QVERIFY(errors_.isEmpty());
  }

  void femRelaxationCancelled() {
    errors_.clear();
    auto* c = window_->controller();
    c->setAngles(c->skeleton().find("left_hip"), {70, 0, 0});
    QSignalSpy done(window_, &MainWindow::relaxFinished);
    window_->relaxCurrentPose();
    QVERIFY(window_->isRelaxing());
    // The solver takes the cancel at its first check: no relaxed result, no error, posing again.
    window_->cancelRelaxation();
    QTRY_VERIFY_WITH_TIMEOUT(!window_->isRelaxing(), 60000);
    QVERIFY2(errors_.isEmpty(), qPrintable(errors_.join("; ")));
    QCOMPARE(done.count(), 1);
    QVERIFY(window_->relaxationSummary().isEmpty());
    QVERIFY(window_->pipeline()->relaxation() == nullptr);
    c->setAngles(c->skeleton().find("left_knee"), {20, 0, 0});
    QVERIFY(errors_.isEmpty());
    // The next relaxation runs to its end (a milder pose: a shorter solve).
    c->setAngles(c->skeleton().find("left_hip"), {20, 0, 0});
    window_->relaxCurrentPose();
    QTRY_VERIFY_WITH_TIMEOUT(!window_->isRelaxing(), 120000);
    QVERIFY2(errors_.isEmpty(), qPrintable(errors_.join("; ")));
    QCOMPARE(done.count(), 2);
    QVERIFY(window_->relaxationSummary().contains("CG iterations"));
  }

  void femRelaxationWarmStart() {
    errors_.clear();
    auto* c = window_->controller();
    auto* warm = window_->findChild<QCheckBox*>("relaxWarmStart");
    QVERIFY(warm);
    QVERIFY(!warm->isChecked());  // off by default: a pose's result does not depend on the ones before
    QSignalSpy done(window_, &MainWindow::relaxFinished);
    auto relax = [&](bool fromLast) {
      warm->setChecked(fromLast);
      window_->relaxCurrentPose();
      QTRY_VERIFY_WITH_TIMEOUT(!window_->isRelaxing(), 120000);
      QVERIFY2(errors_.isEmpty(), qPrintable(errors_.join("; ")));
    };
    c->resetAll();
    c->setAngles(c->skeleton().find("left_hip"), {15, 0, 0});
    relax(false);
    QVERIFY(!window_->relaxationSummary().contains("started from the last relaxation"));
    // A small pose change, solved from the last relaxation: fewer Newton steps than from its skinning.
    c->setAngles(c->skeleton().find("left_hip"), {17, 0, 0});
    relax(true);
    QVERIFY2(window_->relaxationSummary().contains("started from the last relaxation"),
             qPrintable(window_->relaxationSummary()));
    // Every Newton step counts, the strained region's own (from skinning only) too.
    auto newtonSteps = [&]() {
      auto* r = window_->pipeline()->relaxation();
      return r->GetNewtonIterations() + r->GetStrainedRegionNewtonIterations();
    };
    const int fromLast = newtonSteps();
    c->setAngles(c->skeleton().find("left_hip"), {18, 0, 0});  // away and back: the same pose, relaxed again
    c->setAngles(c->skeleton().find("left_hip"), {17, 0, 0});
    relax(false);
    QVERIFY(!window_->relaxationSummary().contains("started from the last relaxation"));
    const int fromSkinning = newtonSteps();
    qInfo("Newton steps: %d from the last relaxation, %d from skinning", fromLast, fromSkinning);
    QVERIFY2(fromLast < fromSkinning, qPrintable(QString("Newton steps: %1 from the last relaxation, %2 from skinning")
                                                     .arg(fromLast).arg(fromSkinning)));
    QCOMPARE(done.count(), 3);
  }

  void dragPreviewHasNoWebs() {
    auto* c = window_->controller();
    c->resetAll();
    checkDragPreview([c] {
      c->setAngles(c->skeleton().find("left_hip"), {100, 30, 0});
      c->setAngles(c->skeleton().find("right_hip"), {-25, 20, 0});
      c->setAngles(c->skeleton().find("left_knee"), {90, 0, 0});
    });
    c->resetAll();
  }

  void shortcutsIgnoreFocus() {
    // Space, Ctrl+E and Ctrl+0 act whichever widget has the keyboard focus (a spin box took Ctrl+E as
    // "end of line", a button Space).
    const QString clip = QString(REPOSE_SHARED_DATA) + "/mocap/cmu_short_75frames.bvh";
    if (!QFileInfo::exists(clip)) QSKIP("shared motion capture data not available");
    window_->controller()->resetAll();
    QVERIFY(window_->loadClip(clip));
    // Shortcuts work in the active window (Xvfb has no window manager to activate it).
    QApplication::setActiveWindow(window_);
    QTRY_VERIFY(QApplication::activeWindow() == window_);
    window_->jointPanel()->setSelectedJoint(window_->controller()->skeleton().find("left_hip"));
    QDoubleSpinBox* spin = window_->jointPanel()->spinBox(0);
    spin->setFocus();
    QTRY_VERIFY(spin->hasFocus());
    QTest::keyClick(spin, Qt::Key_Space);
    QVERIFY(window_->animation()->playing());
    QTest::keyClick(spin, Qt::Key_Space);
    QVERIFY(!window_->animation()->playing());
    savePrompts_.clear();
    QTest::keyClick(spin, Qt::Key_E, Qt::ControlModifier);
    QCOMPARE(savePrompts_, QStringList({"Export posed label volume"}));
    vtkCamera* camera = window_->scene()->renderer()->GetActiveCamera();
    window_->scene()->resetCamera();
    double reset[3], turned[3], back[3];
    camera->GetPosition(reset);
    camera->Azimuth(50);
    camera->GetPosition(turned);
    QTest::keyClick(spin, Qt::Key_0, Qt::ControlModifier);
    camera->GetPosition(back);
    QVERIFY(std::sqrt(vtkMath::Distance2BetweenPoints(reset, turned)) > 10);
    QVERIFY(std::sqrt(vtkMath::Distance2BetweenPoints(reset, back)) < 1e-6);
    // No save dialog for a CT the case does not have: the action is off.
    auto* exportCt = window_->findChild<QAction*>("exportPosedCt");
    QVERIFY(exportCt && !exportCt->isEnabled());
    QVERIFY(window_->aboutText().contains(REPOSE_VERSION));
    // Quitting with an unsaved pose asks; Cancel keeps the window.
    window_->controller()->setAngles(window_->controller()->skeleton().find("left_hip"), {15, 0, 0});
    questions_.clear();
    answers_ = {QMessageBox::Cancel};
    QVERIFY(!window_->close());
    QVERIFY(window_->isVisible());
    QCOMPARE(questions_.size(), 1);
    QVERIFY(questions_[0].contains("before quitting"));
    // The series export's range and stride, with the size it will take.
    SeriesExportDialog dialog(75, 1.0 / 120, 12.5, window_);
    dialog.setSettings({outDir(), 10, 40, 10});
    QCOMPARE(dialog.settings().frameCount(), 4);
    QVERIFY2(dialog.estimate().startsWith("4 frames") && dialog.estimate().endsWith("about 50 MB"), qPrintable(dialog.estimate()));
  }

  void totalSegmentatorCaseFlows() {
    // From the 15-joint phantom straight to the 10-joint TotalSegmentator case, with a joint selected
    // whose index the new skeleton lacks and an unsaved pose (a question, answered Discard).
    errors_.clear();
    const QString caseDir = QString(REPOSE_GUI_TOTALSEG_CASE);
    const QString data = QString(REPOSE_SHARED_DATA) + "/totalsegmentator";
    if (!QFileInfo::exists(caseDir + "/manifest.json")) QSKIP("the TotalSegmentator case was not prepared (no shared data)");
    auto* c = window_->controller();
    QCOMPARE(c->jointCount(), 15);
    window_->jointPanel()->setSelectedJoint(14);
    c->setAngles(14, {10, 0, 0});
    questions_.clear();
    window_->openCase(caseDir);
    QCOMPARE(questions_.size(), 1);
    QVERIFY(questions_[0].contains("not saved"));
    QTRY_VERIFY_WITH_TIMEOUT(!window_->isOpening(), 60000);
    QVERIFY2(window_->hasCase(), qPrintable(errors_.join("; ")));
    QVERIFY(c->jointCount() < 15);
    QCOMPARE(window_->jointPanel()->selectedJoint(), -1);
    QVERIFY(window_->loadRestImage(data + "/example_ct.nii.gz"));
    QVERIFY(window_->findChild<QAction*>("exportPosedCt")->isEnabled());
    QTRY_VERIFY_WITH_TIMEOUT(!window_->slicesPending(), 60000);

    // Label names from the table: the legend, the 3D view's pick caption, the slice tooltips.
    QVERIFY2(window_->legend()->entries().contains("75\tfemur_left"), qPrintable(window_->legend()->entries().join(", ")));
    vtkImageData* rest = window_->pipeline()->restLabels();
    const Eigen::Vector3d femurLeft = centroid(rest, 75), femurRight = centroid(rest, 76), l3 = centroid(rest, 29);
    QVERIFY(femurLeft.x() > femurRight.x());  // LPS: the patient's left is +x
    {
      vtkRenderer* r = window_->scene()->renderer();
      r->SetWorldPoint(femurLeft.x(), femurLeft.y(), femurLeft.z(), 1.0);
      r->WorldToDisplay();
      double d[3];
      r->GetDisplayPoint(d);
      window_->scene()->pickJoint(int(d[0]), int(d[1]));
      const QString caption = window_->scene()->pickedCaption();
      QVERIFY2(caption.contains("(label ") && !caption.startsWith("label "), qPrintable(caption));
    }

    // Radiological convention on the real CT, checked on the rendered pixels with the overlay opaque.
    SliceViews* slices = window_->slices();
    slices->setOverlayOpacity(1.0);
    QCOMPARE(slices->orientationLetters(SliceViews::Axial), QStringList({"R", "L", "A", "P"}));
    QCOMPARE(slices->orientationLetters(SliceViews::Coronal), QStringList({"R", "L", "S", "I"}));
    QCOMPARE(slices->orientationLetters(SliceViews::Sagittal), QStringList({"A", "P", "S", "I"}));
    for (auto v : {SliceViews::Axial, SliceViews::Coronal, SliceViews::Sagittal})
      QVERIFY2(slices->scaleBarCaption(v).endsWith(" mm"), qPrintable(slices->scaleBarCaption(v)));
    slices->centreOn(femurLeft);
    for (auto v : {SliceViews::Axial, SliceViews::Coronal}) {
      // The left femur is drawn on the screen's right half, in its own colour, where it is in space.
      const Eigen::Vector2d at = slices->displayPosition(v, femurLeft);
      QVERIFY(at.x() > slices->displayPosition(v, femurRight).x());
      QVERIFY2(pixelIsLabel(v, at, 75, 76), "the left femur is not drawn where it is");
      QVERIFY(slices->describeAt(v, int(at.x()), int(at.y())).startsWith("femur_left (label 75)"));
    }
    slices->centreOn(l3);
    QVERIFY(slices->statusLine(SliceViews::Axial).contains("vertebrae_L3"));
    window_->jointPanel()->setSelectedJoint(c->skeleton().find("left_hip"));
    QVERIFY(window_->grab().save(outDir() + "/window_totalseg.png"));  // for a person to look at
    // The spine lies behind the abdominal organs (LPS +y), and the axial view shows it at the bottom,
    // the sagittal view behind them, on the right.
    Eigen::Vector3d organs = Eigen::Vector3d::Zero();
    long organVoxels = 0;
    for (int label = 1; label <= 24; ++label) {  // spleen ... kidney cysts in TotalSegmentator's table
      long n = 0;
      const Eigen::Vector3d c = centroid(rest, label, &n);
      organs += n * c;
      organVoxels += n;
    }
    QVERIFY(organVoxels > 1000);
    organs /= organVoxels;
    QVERIFY(l3.y() > organs.y() + 30);
    Eigen::Vector3d front = l3;
    front.y() = organs.y();
    QVERIFY(slices->displayPosition(SliceViews::Axial, l3).y() < slices->displayPosition(SliceViews::Axial, front).y() - 20);
    QVERIFY(slices->displayPosition(SliceViews::Sagittal, l3).x() > slices->displayPosition(SliceViews::Sagittal, front).x() + 20);
    for (auto v : {SliceViews::Axial, SliceViews::Sagittal})
      QVERIFY2(pixelIsLabel(v, slices->displayPosition(v, l3), 29, 28), "L3 is not drawn where it is");
    for (auto v : {SliceViews::Axial, SliceViews::Coronal, SliceViews::Sagittal})
      QVERIFY2(nonBackgroundFraction(v) > 0.2, qPrintable(QString("view %1 is nearly empty").arg(int(v))));
    slices->setOverlayOpacity(0.5);
    compareSlicesWithBaseline(slices, "GuiSliceViewsTotalSeg");

    // The deep vertebra chain keeps the angle column in view.
    QTreeWidget* tree = window_->jointPanel()->tree();
    QVERIFY(tree->columnWidth(1) > 30);
    QVERIFY(tree->header()->sectionViewportPosition(1) + 20 < tree->viewport()->width());

    // The drag preview of the real case (240 k triangles: decimated by size) has no webs either.
    const int hip = c->skeleton().find("left_hip");
    QVERIFY(hip >= 0);
    checkDragPreview([c, hip] { c->setAngles(hip, {90, 20, 0}); });
    c->resetAll();
    // A large pose: the slice views still hold the anatomy, the cursor where it was in the body.
    c->setAngles(hip, {90, 0, 0});
    QTRY_VERIFY_WITH_TIMEOUT(!window_->slicesPending(), 60000);
    for (auto v : {SliceViews::Axial, SliceViews::Coronal, SliceViews::Sagittal})
      QVERIFY2(nonBackgroundFraction(v) > 0.2, qPrintable(QString("view %1 went blank after the pose").arg(int(v))));
    QCOMPARE(slices->labelAtCursor(), 29);  // L3 does not move with the hip
    QVERIFY(window_->exportPosedLabels(outDir() + "/totalseg_posed.nii.gz"));
    QCOMPARE(readLabelTableFile((outDir() + "/totalseg_posed.tsv").toStdString()).nameOf(75), std::string("femur_left"));

    // Open a scan while this case is open: the phantom's labels (15 joints, more than now).
    const QString scanDir = outDir() + "/scan";
    QDir().mkpath(scanDir);
    auto phantom = vtkSmartPointer<vtkReposePhantomSource>::New();
    phantom->SetSizeName("tiny");
    phantom->Update();
    writeImage(phantom->GetOutput(), (scanDir + "/labels.nii.gz").toStdString());
    writeTextFile((scanDir + "/skeleton.json").toStdString(), phantom->GetSkeletonJSON());
    writeTextFile((scanDir + "/labels.tsv").toStdString(), phantom->GetLabelTableTSV());
    OpenRequest scan;
    scan.kind = OpenRequest::Scan;
    scan.labelsPath = scanDir + "/labels.nii.gz";
    scan.skeletonPath = scanDir + "/skeleton.json";
    scan.labelTablePath = scanDir + "/labels.tsv";
    scan.saveCaseDir = outDir() + "/scan_case";
    window_->openScan(scan);
    QTRY_VERIFY_WITH_TIMEOUT(!window_->isOpening(), 180000);
    QVERIFY2(window_->hasCase(), qPrintable(errors_.join("; ")));
    QCOMPARE(c->jointCount(), 15);
    QVERIFY(!window_->hasRestImage());
    QVERIFY(window_->legend()->entries().contains("24\tfemur_left"));
    QVERIFY2(QFileInfo::exists(outDir() + "/scan_case/labels.tsv"), "the saved case did not keep its label table");

    // Close while the FEM relaxation runs: the solver stops, the window is free.
    c->setAngles(c->skeleton().find("left_hip"), {50, 0, 0});
    window_->relaxCurrentPose();
    QVERIFY(window_->isRelaxing());
    window_->closeCase();
    QVERIFY(!window_->hasCase());
    QVERIFY(!window_->isRelaxing());
    QCOMPARE(c->jointCount(), 0);
    QCOMPARE(window_->jointPanel()->tree()->topLevelItemCount(), 0);
    QVERIFY2(errors_.isEmpty(), qPrintable(errors_.join("; ")));
  }

  void closeDuringPreparationAndExport() {
    errors_.clear();
    // Closing while a case is prepared cancels it.
    window_->openPhantom("tiny");
    QVERIFY(window_->isOpening());
    window_->closeCase();
    QVERIFY(!window_->isOpening());
    QVERIFY(!window_->hasCase());
    // Closing while a series is written: the close waits for the export to stop; nothing is left behind.
    // On the case the scan flow saved (quick to open), which kept its label table.
    const QString saved = outDir() + "/scan_case";
    if (QFileInfo::exists(saved + "/manifest.json"))
      window_->openCase(saved);
    else
      window_->openPhantom("tiny");
    QTRY_VERIFY_WITH_TIMEOUT(!window_->isOpening(), 180000);
    QVERIFY2(window_->hasCase(), qPrintable(errors_.join("; ")));
    QVERIFY(window_->legend()->entries().contains("24\tfemur_left"));
    const QString clip = QString(REPOSE_SHARED_DATA) + "/mocap/cmu_short_75frames.bvh";
    if (!QFileInfo::exists(clip)) QSKIP("shared motion capture data not available");
    QVERIFY(window_->loadClip(clip));
    QTimer::singleShot(800, window_, [this] { window_->closeCase(); });
    QVERIFY(window_->exportAnimation(outDir() + "/interrupted"));
    QVERIFY(!QFileInfo::exists(outDir() + "/interrupted/animation.pvd"));
    QTRY_VERIFY_WITH_TIMEOUT(!window_->hasCase(), 10000);
    QVERIFY2(errors_.isEmpty(), qPrintable(errors_.join("; ")));
  }
};

int main(int argc, char** argv) {
  QSurfaceFormat::setDefaultFormat(QVTKOpenGLNativeWidget::defaultFormat());
  QApplication app(argc, argv);
  TestMainWindow test;
  return QTest::qExec(&test, argc, argv);
}
#include "test_gui_main_window.moc"
