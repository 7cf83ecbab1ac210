#pragma once
// Asks where to write a motion clip's ParaView series and which frames: first, last and stride, with
// the number of frames and the estimated size on disk (every frame is a whole posed mesh and its
// surfaces: tens of megabytes each on a real scan).
#include <algorithm>

#include <QDialog>

class QLabel;
class QLineEdit;
class QSpinBox;

namespace repose {

struct SeriesExportSettings {
  QString dir;
  int first = 0, last = 0, stride = 1;  ///< frame indices (0-based, last included)
  /// Frames written: first, first + stride, ... up to last.
  int frameCount() const { return last < first ? 0 : (last - first) / std::max(1, stride) + 1; }
};

class SeriesExportDialog : public QDialog {
  Q_OBJECT
public:
  /// `megabytesPerFrame`: the estimate shown per frame written.
  SeriesExportDialog(int frameCount, double frameTime, double megabytesPerFrame, QWidget* parent = nullptr);
  SeriesExportSettings settings() const;
  void setSettings(const SeriesExportSettings& settings);
  /// "25 frames (0.025 s apart), about 380 MB".
  QString estimate() const;

private:
  QLineEdit* dir_;
  QSpinBox *first_, *last_, *stride_;
  QLabel* estimate_;
  double frameTime_, megabytesPerFrame_;
};

}  // namespace repose
