#pragma once
// Three orthogonal slice views of the posed volumes (the CT, or the label volume in grey when there
// is no CT) with the label overlay, in the radiological convention of 3D Slicer and clinical
// viewers, world = patient LPS millimetres:
//   axial    seen from the feet:   patient's left on screen right, anterior up;
//   coronal  seen from the front:  patient's left on screen right, superior up;
//   sagittal seen from the left:   anterior on screen left, superior up (Slicer's sagittal).
// Each view carries orientation letters (R/L, A/P, S/I) at its edges, a millimetre scale bar, and a
// status line above it (slice position, label under the cursor). The cursor is a physical point (LPS mm),
// shared by the views: it stays where it is in the body when the posed grid changes, and the views
// pan to keep it in sight. Hovering shows the label's name, the CT value and the position.
// Left click moves the cursor, left drag sets window/level, the sliders pick the slices.
#include <Eigen/Core>
#include <QStringList>
#include <QWidget>
#include <vtkSmartPointer.h>

#include "label_table.h"

class vtkImageData;
class vtkRenderWindow;
class vtkRenderer;

namespace repose {

class SliceViews : public QWidget {
  Q_OBJECT
public:
  enum View { Axial = 0, Coronal = 1, Sagittal = 2 };
  explicit SliceViews(QWidget* parent = nullptr);
  ~SliceViews() override;

  /// Shows new volumes on any grid and direction (`image` may be null). The first volumes after
  /// clear() fit the views and put the cursor at the centre; later ones keep the cursor's physical
  /// position (clamped into the new grid) and the zoom.
  void setVolumes(vtkImageData* labels, vtkImageData* image, const LabelTable& table,
                  const std::vector<int>& boneLabels);
  /// Forgets volumes, cursor and cameras (a new case).
  void clear();
  bool hasVolumes() const;
  /// Cursor in LPS millimetres; clamped into the volume.
  void setCursorPosition(const Eigen::Vector3d& lps);
  Eigen::Vector3d cursorPosition() const;
  /// Moves the cursor to `lps` and pans every view to centre it (zoom unchanged).
  void centreOn(const Eigen::Vector3d& lps);
  void setOverlayOpacity(double opacity);
  void setWindowLevel(double window, double level);
  void render();

  /// Label value under the cursor / at a physical point (0 outside).
  int labelAtCursor() const;
  int labelAt(const Eigen::Vector3d& lps) const;
  /// The table's name of a label, "label N" when it has none.
  QString labelName(int value) const;

  // --- what a view shows (tests, tooltips) ----------------------------------------------------
  vtkRenderWindow* renderWindow(View view) const;
  vtkRenderer* renderer(View view) const;
  /// The letters at the left, right, top and bottom edges, e.g. {"R", "L", "A", "P"} (axial).
  QStringList orientationLetters(View view) const;
  /// The scale bar's caption ("50 mm") as last drawn.
  QString scaleBarCaption(View view) const;
  /// The view's status line as last drawn.
  QString statusLine(View view) const;
  /// The tooltip at display pixel (x, y) (VTK pixels, origin bottom left); empty off the volume.
  QString describeAt(View view, int x, int y) const;
  /// Display position (VTK pixels) of a physical point in a view.
  Eigen::Vector2d displayPosition(View view, const Eigen::Vector3d& lps) const;

signals:
  void cursorChanged(const Eigen::Vector3d& lps);

protected:
  bool eventFilter(QObject* watched, QEvent* event) override;

private:
  void updateCursor();
  void updateAnnotations(int view);  // letters and scale bar, before every render
  void fitViews();
  void keepCursorInSight();
  struct Impl;
  Impl* d_;
  friend class SliceInteractorStyle;
};

}  // namespace repose
