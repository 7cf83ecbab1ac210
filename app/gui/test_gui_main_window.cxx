// The main window on the tiny phantom, driven like a user: open (background preprocessing), pose
// through the joint controls and by dragging in the 3D view, undo, export, motion capture, FEM,
// errors as messages, and an image baseline of the 3D view. Needs an X display (xvfb-run).
#include <QCheckBox>
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

#include "animation_panel.h"
#include "joint_panel.h"
#include "main_window.h"
#include "repose_pipeline.h"
#include "scene_view.h"
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
}  // namespace

class TestMainWindow : public QObject {
  Q_OBJECT
  MainWindow* window_ = nullptr;
  QStringList errors_;
  double restTissue_[6], restSkin_[6];

private slots:
  void initTestCase() {
    QDir(outDir()).removeRecursively();
    QDir().mkpath(outDir());
    window_ = new MainWindow;
    window_->setErrorHandler([this](const QString& m) { errors_ << m; });
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
    flexion->setValue(-70);  // as keyboard or a click on the slider track does: one step
    QCOMPARE(window_->controller()->angles(hip).x(), -70.0);
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
    // Upwards: the shin swings forward about the left-right axis (knee flexion).
    for (int i = 1; i <= 10; ++i) send(QEvent::MouseMove, press + QPoint(0, -5 * i), Qt::NoButton, Qt::LeftButton);
    QVERIFY(std::fabs(window_->controller()->angles(knee).x()) > 10);
    send(QEvent::MouseButtonRelease, press + QPoint(0, -50), Qt::LeftButton, Qt::NoButton);
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
    window_->controller()->setAngles(hip, {-60, 0, 0});
    window_->controller()->setAngles(knee, {45, 0, 0});
    const QString labels = outDir() + "/posed_labels.nii.gz";
    QVERIFY(window_->exportPosedLabels(labels));
    QVERIFY(window_->exportPosedSurfaces(outDir() + "/posed_surfaces.vtp"));
    QVERIFY(window_->exportPosedMesh(outDir() + "/posed_mesh.vtu"));
    QVERIFY(window_->savePose(outDir() + "/pose.json"));
    QVERIFY(window_->exportScreenshot(outDir() + "/screenshot.png"));
    for (const char* f : {"posed_surfaces.vtp", "posed_mesh.vtu", "pose.json", "screenshot.png"})
      QVERIFY2(QFileInfo(outDir() + "/" + f).size() > 100, f);
    // The posed volume on disk: the rigid femur keeps its voxel count and moves forward with the flexed hip.
    auto posed = readLabelVolume(labels.toStdString());
    vtkImageData* rest = window_->pipeline()->restLabels();
    auto centroid = [](vtkImageData* image, int label, long& count) {
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      count = 0;
      int dims[3];
      image->GetDimensions(dims);
      for (int k = 0; k < dims[2]; ++k)
        for (int j = 0; j < dims[1]; ++j)
          for (int i = 0; i < dims[0]; ++i)
            if (int(image->GetScalarComponentAsDouble(i, j, k, 0)) == label) {
              double x[3];
              const int ijk[3] = {i, j, k};
              image->TransformIndexToPhysicalPoint(ijk, x);
              sum += Eigen::Vector3d(x[0], x[1], x[2]);
              ++count;
            }
      return Eigen::Vector3d(sum / std::max(count, 1L));
    };
    long femurPosed = 0, femurRest = 0;
    const Eigen::Vector3d posedCentre = centroid(posed, 24, femurPosed);  // femur_left
    const Eigen::Vector3d restCentre = centroid(rest, 24, femurRest);
    QVERIFY(femurRest > 0);
    QVERIFY2(std::fabs(double(femurPosed) / femurRest - 1) < 0.15, "the rigid femur changed size");
    QVERIFY2(posedCentre.y() < restCentre.y() - 50, "the femur did not move forward");
    // Reset, then the saved pose brings it back.
    window_->controller()->resetAll();
    QVERIFY(window_->loadPose(outDir() + "/pose.json"));
    QVERIFY(std::fabs(window_->controller()->angles(hip).x() + 60) < 1e-6);
    QVERIFY(std::fabs(window_->controller()->angles(knee).x() - 45) < 1e-6);
    QVERIFY(errors_.isEmpty());
  }

  void posedViewMatchesBaseline() {
    // A known pose, a fixed view size and camera: compare with Testing/Data/Baseline.
    window_->controller()->resetAll();
    auto* c = window_->controller();
    c->setAngles(c->skeleton().find("left_hip"), {-60, 0, 0});
    c->setAngles(c->skeleton().find("left_knee"), {45, 0, 0});
    c->setAngles(c->skeleton().find("right_shoulder"), {0, 80, 0});
    c->setAngles(c->skeleton().find("right_elbow"), {-90, 0, 0});
    window_->scene()->setSelectedJoint(c->skeleton().find("left_knee"));
    window_->scene()->setFixedSize(500, 500);
    QApplication::processEvents();
    window_->scene()->resetCamera();
    window_->scene()->renderer()->GetActiveCamera()->Azimuth(40);  // oblique: the flexions show
    window_->scene()->renderer()->ResetCamera();
    const QString candidate = outDir() + "/GuiPosedView.png";
    QVERIFY(window_->exportScreenshot(candidate));
    window_->scene()->setMinimumSize(400, 300);
    window_->scene()->setMaximumSize(QWIDGETSIZE_MAX, QWIDGETSIZE_MAX);
    const QString baseline = QString(REPOSE_BASELINE_DIR) + "/GuiPosedView.png";
    QDir().mkpath(REPOSE_TEMPORARY_DIR);
    const QString keep = QString(REPOSE_TEMPORARY_DIR) + "/GuiPosedView.png";
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
    qInfo("GuiPosedView: thresholded image error %.3f (threshold 10)", error);
    if (error > 10) {
      QFile::remove(keep);
      QFile::copy(candidate, keep);
    }
    QVERIFY2(error <= 10, qPrintable(QString("image differs from the baseline; candidate in %1").arg(keep)));
  }

  void motionCapture() {
    const int hip = window_->controller()->skeleton().find("left_hip");
    window_->controller()->resetAll();
    window_->controller()->setAngles(hip, {-10, 0, 0});
    window_->controller()->setAngles(hip, {-20, 0, 0});
    const QString mocap = QString(REPOSE_SHARED_DATA) + "/mocap";
    const QString walk = mocap + "/cmu_131_01_walk.bvh";
    if (!QFileInfo::exists(walk)) QSKIP("shared motion capture data not available");
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
    // Frames do not fill the undo history: one undo returns to the last edit before the clip.
    window_->controller()->undo();
    QVERIFY(std::fabs(window_->controller()->angles(hip).x() + 10) < 1e-6);
    window_->controller()->resetAll();
    // A short clip exported as a ParaView series.
    const QString shortClip = mocap + "/cmu_short_75frames.bvh";
    QVERIFY(window_->loadClip(shortClip));
    QVERIFY(window_->exportAnimation(outDir() + "/series", 25));
    QVERIFY(QFileInfo::exists(outDir() + "/series/animation.pvd"));
    QCOMPARE(QDir(outDir() + "/series/frames").entryList(QDir::Files).size(), 6);  // 3 frames x mesh+surfaces
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
    c->setAngles(c->skeleton().find("left_hip"), {-60, 0, 0});
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
    QVERIFY(window_->relaxationSummary().contains("CG iterations"));
    // The knee set meanwhile is shown once the solver is done (skinning again, up to date).
    QVERIFY(!window_->pipeline()->relaxationSummary().size());
    // Posing again returns to interactive skinning.
    c->setAngles(c->skeleton().find("left_hip"), {-50, 0, 0});
    QVERIFY(errors_.isEmpty());
  }

  void femRelaxationCancelled() {
    errors_.clear();
    auto* c = window_->controller();
    c->setAngles(c->skeleton().find("left_hip"), {-70, 0, 0});
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
    // The next relaxation runs to its end.
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
    c->setAngles(c->skeleton().find("left_hip"), {-40, 0, 0});
    relax(false);
    QVERIFY(!window_->relaxationSummary().contains("started from the last relaxation"));
    // A small pose change, solved from the last relaxation: fewer Newton steps than from its skinning.
    c->setAngles(c->skeleton().find("left_hip"), {-44, 0, 0});
    relax(true);
    QVERIFY2(window_->relaxationSummary().contains("started from the last relaxation"),
             qPrintable(window_->relaxationSummary()));
    // Every Newton step counts, the strained region's own (from skinning only) too.
    auto newtonSteps = [&]() {
      auto* r = window_->pipeline()->relaxation();
      return r->GetNewtonIterations() + r->GetStrainedRegionNewtonIterations();
    };
    const int fromLast = newtonSteps();
    c->setAngles(c->skeleton().find("left_hip"), {-45, 0, 0});  // away and back: the same pose, relaxed again
    c->setAngles(c->skeleton().find("left_hip"), {-44, 0, 0});
    relax(false);
    QVERIFY(!window_->relaxationSummary().contains("started from the last relaxation"));
    const int fromSkinning = newtonSteps();
    qInfo("Newton steps: %d from the last relaxation, %d from skinning", fromLast, fromSkinning);
    QVERIFY2(fromLast < fromSkinning, qPrintable(QString("Newton steps: %1 from the last relaxation, %2 from skinning")
                                                     .arg(fromLast).arg(fromSkinning)));
    QCOMPARE(done.count(), 3);
  }
};

int main(int argc, char** argv) {
  QSurfaceFormat::setDefaultFormat(QVTKOpenGLNativeWidget::defaultFormat());
  QApplication app(argc, argv);
  TestMainWindow test;
  return QTest::qExec(&test, argc, argv);
}
#include "test_gui_main_window.moc"
