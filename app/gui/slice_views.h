#pragma once
// Three orthogonal slice views (axial, coronal, sagittal) of the posed volumes: the CT (or the
// label volume in grey when there is no CT) with the label overlay, window/level by left drag,
// and a cursor linked across the views (click to move it; sliders pick the slices).
#include <QWidget>
#include <vtkSmartPointer.h>

#include "label_table.h"

class QLabel;
class QSlider;
class vtkImageData;

namespace repose {

class SliceViews : public QWidget {
  Q_OBJECT
public:
  explicit SliceViews(QWidget* parent = nullptr);
  ~SliceViews() override;

  /// Shows new volumes (same grid as before keeps the cursor and slices). `image` may be null.
  void setVolumes(vtkImageData* labels, vtkImageData* image, const LabelTable& table,
                  const std::vector<int>& boneLabels);
  void clear();
  /// Cursor in voxel indices (i, j, k); clamped to the volume.
  void setCursor(int i, int j, int k);
  void cursor(int ijk[3]) const;
  void setOverlayOpacity(double opacity);
  void setWindowLevel(double window, double level);
  void render();
  /// Label value under the cursor in the shown label volume (0 outside).
  int labelAtCursor() const;

signals:
  void cursorChanged(int i, int j, int k);

private:
  void updateCursor();
  struct Impl;
  Impl* d_;
  friend class SliceInteractorStyle;
};

}  // namespace repose
