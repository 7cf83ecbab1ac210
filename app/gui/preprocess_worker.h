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

/// The label table for a case directory: labels.tsv in it or beside it, else names inferred from
/// nothing (empty table).
LabelTable findCaseLabelTable(const std::string& caseDir);

}  // namespace repose
