#pragma once
// Asks for the files of a scan to prepare: label volume, optional CT, optional label table, and
// a skeleton.json or the automatic skeleton; optionally where to save the prepared case.
#include <QDialog>

#include "preprocess_worker.h"

class QCheckBox;
class QDoubleSpinBox;
class QLineEdit;

namespace repose {

class OpenScanDialog : public QDialog {
  Q_OBJECT
public:
  explicit OpenScanDialog(QWidget* parent = nullptr);
  OpenRequest request() const;

private:
  QLineEdit *labels_, *image_, *table_, *skeleton_, *save_;
  QCheckBox* auto_;
  QDoubleSpinBox* spacing_;
};

}  // namespace repose
