#pragma once
// The Repose main window: start screen, then the workspace (joint panel left, 3D view centre,
// slice views below it, deformation panel and legend right, motion timeline at the bottom). Drives
// one repose::Pipeline: posing on the UI thread (fast), preprocessing, posed-volume resampling and
// FEM relaxation in the background. Every case flow (open, close, open another with more or fewer
// joints, open a scan, close while preparing, relaxing or exporting) ends in a usable window; a
// failure is a dialog with one line.
#include <functional>
#include <memory>
#include <vector>

#include <Eigen/Geometry>
#include <QFutureWatcher>
#include <QMainWindow>
#include <QMessageBox>
#include <vtkImageData.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>

#include "label_table.h"
#include "pose_controller.h"
#include "preprocess_worker.h"

class vtkObject;

class QAction;
class QCheckBox;
class QComboBox;
class QLabel;
class QPushButton;
class QSlider;
class QStackedWidget;

namespace repose {

class AnimationPanel;
class PosedVolumeSampler;
class JointPanel;
class LabelLegend;
class Pipeline;
class SceneView;
class SliceViews;
class StartPage;

/// Times of the last pose update (seconds).
struct FrameTiming {
  double skinning = 0, surfaces = 0, render = 0, total = 0;
};

class MainWindow : public QMainWindow {
  Q_OBJECT
public:
  explicit MainWindow(QWidget* parent = nullptr);
  ~MainWindow() override;

  // --- opening (asynchronous; caseOpened() or openFailed() follows) --------------------------
  void openPhantom(const QString& size, const PrepareSettings& settings = {});
  void openCase(const QString& caseDir);
  void openScan(const OpenRequest& request);
  void cancelOpening();
  bool isOpening() const { return worker_ != nullptr; }
  bool hasCase() const { return bool(pipeline_); }
  bool hasRestImage() const { return bool(restImage_); }
  /// Closes the case (asks first when the pose has unsaved changes; waits for a running export or
  /// relaxation to stop, cancels a preparation).
  void closeCase();

  // --- pose files and exports (throw nothing: errors go to the error handler) ----------------
  bool savePose(const QString& path);
  bool loadPose(const QString& path);
  bool loadRestImage(const QString& path);
  bool exportPosedLabels(const QString& path);
  bool exportPosedImage(const QString& path);
  bool exportPosedMesh(const QString& path);
  bool exportPosedSurfaces(const QString& path);
  bool exportScreenshot(const QString& path);
  /// The loaded clip as a ParaView series: DIR/animation.pvd + frames/ (mesh and surfaces) of
  /// frames first, first + step, ... up to last (-1: the clip's end), and DIR/labels.tsv.
  bool exportAnimation(const QString& dir, int step = 1, int first = 0, int last = -1);
  bool isExporting() const { return exporting_; }
  /// Loads a clip; over a hand-made pose it asks first (Undo brings the pose back). False when the
  /// user declines or on an error.
  bool loadClip(const QString& bvhPath, const QString& mapPath = QString());
  /// Moves the slice views' cursor to the selected joint's posed centre (the root's without a
  /// selection) and pans them there.
  void centreSlicesOnSelection();
  /// The About box's text (version, what Repose is, the libraries it runs on).
  QString aboutText() const;
  /// Skinning "dqs" | "lbs".
  bool setSkinning(const QString& method);
  /// FEM relaxation of the current pose in the background; relaxFinished() follows.
  void relaxCurrentPose();
  /// Stops a running relaxation at the solver's next check (a few seconds at most); relaxFinished()
  /// follows, with the pose left skinned only. The relax button does this while the solver runs.
  void cancelRelaxation();
  bool isRelaxing() const { return relaxing_; }
  QString relaxationSummary() const { return relaxSummary_; }
  /// The relaxation label: while the solver runs, where it is ("Relaxing (FEM): Newton step 3…").
  QString relaxationStatus() const;

  // --- state for tests and the benchmark -----------------------------------------------------
  PoseController* controller() { return &controller_; }
  Pipeline* pipeline() { return pipeline_.get(); }
  SceneView* scene() { return scene_; }
  SliceViews* slices() { return slices_; }
  JointPanel* jointPanel() { return joints_; }
  AnimationPanel* animation() { return animation_; }
  LabelLegend* legend() { return legend_; }
  const LabelTable& labelTable() const { return table_; }
  const FrameTiming& lastFrameTiming() const { return timing_; }
  /// True while the slice views wait for a background resampling of the posed volumes.
  bool slicesPending() const { return sliceWatcher_.isRunning() || slicesDirty_; }
  /// Replaces the error dialog (tests record the one-line messages instead).
  void setErrorHandler(std::function<void(const QString&)> handler) { errorHandler_ = std::move(handler); }
  /// Replaces the question dialogs (unsaved pose, a clip over a hand pose): the handler gets the
  /// question and the buttons offered and returns the button pressed.
  using QuestionHandler = std::function<QMessageBox::StandardButton(const QString&, QMessageBox::StandardButtons)>;
  void setQuestionHandler(QuestionHandler handler) { questionHandler_ = std::move(handler); }
  /// Replaces the save-file dialog (title, suggested name) -> path, empty to cancel.
  void setSavePathHandler(std::function<QString(const QString&, const QString&)> handler) {
    savePathHandler_ = std::move(handler);
  }
  /// Rotates the selected joint as a mouse drag of (dx, dy) pixels does; returns the frame time.
  double simulateDrag(double dx, double dy);

signals:
  void caseOpened();
  void openFailed(const QString& message);
  void relaxFinished();

protected:
  void closeEvent(QCloseEvent* event) override;
  /// Application-wide: the window's shortcuts (Space, Ctrl+E, Ctrl+0, ...) win over whichever
  /// widget has the keyboard focus (a spin box takes Ctrl+E as "end of line", a button Space).
  bool eventFilter(QObject* watched, QEvent* event) override;

private:
  static constexpr const char* kRelaxButtonText = "Relax soft tissue (FEM)";
  void buildMenus();
  void buildWorkspace();
  void startWorker(const OpenRequest& request);
  void workerFinished();
  void installCase(const OpenResult& result);
  void dropCase();  // closes without asking
  /// True to go on: the pose is saved, discarded, or had no unsaved changes. `before` completes
  /// "Save the pose before ...?".
  bool confirmDiscardPose(const QString& before);
  QMessageBox::StandardButton ask(const QString& question, QMessageBox::StandardButtons buttons,
                                  QMessageBox::StandardButton fallback);
  /// While an export runs, asks it to stop and runs `again` once it has: true if deferred.
  bool deferWhileExporting(const std::function<void()>& again);
  void finishRelaxationState();  // widgets and flags back to posing after a relaxation
  Eigen::Vector3d jointCentre(int joint) const;  // posed, LPS mm
  Eigen::Vector3d rootCentre() const;
  void poseChanged();
  void requestSliceUpdate();
  void startSliceUpdate();
  void sliceUpdateFinished();
  void relaxDone();
  void dropRelaxation();
  void stopRelaxation();  // cancels a running relaxation and waits for it
  // On the solver's thread: its progress text, shown in the relaxation label (queued to the UI thread).
  void relaxProgress(vtkObject* caller, unsigned long event, void* data);
  void showAnimationFrame(int frame);
  void updateActions();
  void showError(const QString& message);
  bool guarded(const std::function<void()>& action);
  QString askSavePath(const QString& title, const QString& name, const QString& filter);

  PoseController controller_;
  std::shared_ptr<Pipeline> pipeline_;
  LabelTable table_;
  std::vector<int> boneLabels_;
  vtkSmartPointer<vtkImageData> restImage_;
  std::shared_ptr<PosedVolumeSampler> sliceSampler_;  // the case's posed volumes for the slice views
  void newSliceSampler();
  QString title_;
  PreprocessWorker* worker_ = nullptr;
  FrameTiming timing_;
  bool relaxed_ = false;
  bool relaxing_ = false;  // from relaxCurrentPose() until relaxDone() has run
  bool posedWhileRelaxing_ = false;
  int relaxGeneration_ = 0;
  unsigned long relaxObserver_ = 0;  // the ProgressEvent observer on the relaxation filter while it runs
  QString relaxSummary_;
  bool slicesDirty_ = false;
  Eigen::Vector3d slicesRoot_ = Eigen::Vector3d::Zero();  // posed root centre the slice views show
  int caseGeneration_ = 0;
  std::function<void(const QString&)> errorHandler_;
  QuestionHandler questionHandler_;
  std::function<QString(const QString&, const QString&)> savePathHandler_;
  bool exporting_ = false, abortExport_ = false;
  std::vector<QAction*> shortcutActions_;

  struct SliceResult {
    vtkSmartPointer<vtkImageData> labels, image;
    Eigen::Vector3d root = Eigen::Vector3d::Zero();  // posed root centre of the pose shown
    int generation = 0;
    double seconds = 0;
    QString error;
  };
  QFutureWatcher<SliceResult> sliceWatcher_;
  QFutureWatcher<QString> relaxWatcher_;

  QStackedWidget* stack_;
  StartPage* start_;
  SceneView* scene_;
  SliceViews* slices_;
  JointPanel* joints_;
  AnimationPanel* animation_;
  LabelLegend* legend_;
  QComboBox* skinning_;
  QPushButton* relax_;
  QCheckBox* showBefore_;
  QCheckBox* relaxWarmStart_;
  QLabel* relaxLabel_;
  QSlider* skinOpacity_;
  QLabel* frameLabel_;
  QLabel* sliceLabel_;
  QAction *undo_, *redo_, *savePose_, *loadPose_, *export_[6], *closeCase_, *loadCt_, *loadCtSeries_;
  vtkSmartPointer<vtkPolyData> beforeSurfaces_;
};

}  // namespace repose
