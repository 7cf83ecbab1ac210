#pragma once
// The start screen: open the built-in phantom, a prepared case or a scan; while a case is being
// prepared it shows the stage, a progress bar and a Cancel button.
#include <QWidget>

class QComboBox;
class QLabel;
class QProgressBar;
class QPushButton;

namespace repose {

class StartPage : public QWidget {
  Q_OBJECT
public:
  explicit StartPage(QWidget* parent = nullptr);
  void setBusy(bool busy);
  void setProgress(int step, int steps, const QString& stage);
  QString phantomSize() const;

signals:
  void openPhantomRequested(const QString& size);
  void openCaseRequested();
  void openScanRequested();
  void cancelRequested();

private:
  QComboBox* size_;
  QPushButton *phantom_, *case_, *scan_, *cancel_;
  QProgressBar* bar_;
  QLabel* stage_;
};

}  // namespace repose
