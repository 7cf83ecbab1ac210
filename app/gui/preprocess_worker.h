#pragma once
// Opens a case off the UI thread: builds the phantom or reads a scan, finds the skeleton
// (optionally automatically), preprocesses (mesh, weights, surfaces, binding), or loads a prepared
// case directory. Reports progress per stage; cancel() stops it at the next stage boundary.
#include <atomic>
#include <memory>

#include <QString>
#include <QThread>
#include <vtkImageData.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkUnstructuredGrid.h>

#include "label_table.h"
#include "repose_pipeline.h"
#include "skeleton.h"


namespace repose {

struct OpenRequest {
  enum Kind { Phantom, Case, Scan };
  Kind kind = Phantom;
  QString phantomSize = "small";  ///< tiny | small | medium | large
  QString caseDir;                ///< Case: a prepared case directory
  QString labelsPath, imagePath, labelTablePath, skeletonPath;  ///< Scan (image, table optional)
  bool autoSkeleton = false;      ///< Scan: find the skeleton from the bone labels
  QString saveCaseDir;            ///< Phantom/Scan: also save the prepared case here (optional)
  PrepareSettings settings;
};

struct OpenResult {
  std::shared_ptr<Pipeline> pipeline;
  LabelTable table;
  vtkSmartPointer<vtkImageData> image;  ///< rest CT, may be null
  QString title;                        ///< what was opened, for the window title
  QString report;                       ///< preprocessing figures, one per line
};

class PreprocessWorker : public QThread {
  Q_OBJECT
public:
  explicit PreprocessWorker(const OpenRequest& request, QObject* parent = nullptr);
  void cancel() { cancelled_ = true; }
  bool cancelled() const { return cancelled_; }
  /// Valid after finished() when error() is empty and not cancelled.
  const OpenResult& result() const { return result_; }
  const QString& error() const { return error_; }

signals:
  void progress(int step, int steps, const QString& stage);

protected:
  void run() override;

private:
  void open();
  OpenRequest request_;
  OpenResult result_;
  QString error_;
  std::atomic<bool> cancelled_{false};
  int step_ = 0, steps_ = 1;
};

/// The label table of a case directory: the manifest's "labelTable" (prepare keeps the table it was
/// given as labels.tsv), else labels.tsv in the case or beside it; for older cases of the built-in
/// phantom (the skeleton's joints and bone labels are the phantom's) the phantom's names; else an
/// empty table (labels are then shown as "label N"). A broken table only costs the names.
LabelTable findCaseLabelTable(const std::string& caseDir, const Skeleton& skeleton);
/// The built-in phantom's label names.
LabelTable phantomLabelTable();

}  // namespace repose
