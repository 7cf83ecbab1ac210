#include "slice_views.h"

#include <algorithm>
#include <cmath>

#include <QGridLayout>
#include <QLabel>
#include <QSlider>
#include <QVBoxLayout>
#include <QVTKOpenGLNativeWidget.h>
#include <vtkActor.h>
#include <vtkCamera.h>
#include <vtkCellArray.h>
#include <vtkDataArray.h>
#include <vtkGenericOpenGLRenderWindow.h>
#include <vtkImageData.h>
#include <vtkImageMapToColors.h>
#include <vtkImageProperty.h>
#include <vtkImageSlice.h>
#include <vtkImageSliceMapper.h>
#include <vtkInteractorStyleImage.h>
#include <vtkLookupTable.h>
#include <vtkMatrix3x3.h>
#include <vtkObjectFactory.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkProperty.h>
#include <vtkRenderWindowInteractor.h>
#include <vtkRenderer.h>
#include <vtkTextActor.h>
#include <vtkTextProperty.h>

#include "label_colors.h"

namespace repose {

/// vtkInteractorStyleImage (left drag: window/level, right drag: zoom, middle: pan) where a left
/// click also moves the linked cursor.
class SliceInteractorStyle : public vtkInteractorStyleImage {
public:
  static SliceInteractorStyle* New();
  vtkTypeMacro(SliceInteractorStyle, vtkInteractorStyleImage);
  SliceViews* views = nullptr;
  int axis = 2;
  void OnLeftButtonDown() override;
};
vtkStandardNewMacro(SliceInteractorStyle);

namespace {
const char* kNames[3] = {"Sagittal", "Coronal", "Axial"};
}

struct SliceViews::Impl {
  struct View {
    QVTKOpenGLNativeWidget* widget = nullptr;
    QSlider* slider = nullptr;
    vtkSmartPointer<vtkRenderer> renderer;
    vtkSmartPointer<vtkImageSliceMapper> baseMapper, overlayMapper;
    vtkSmartPointer<vtkImageSlice> base, overlay;
    vtkSmartPointer<vtkPolyData> cross;
    vtkSmartPointer<vtkActor> crossActor;
    vtkSmartPointer<vtkTextActor> text;
    vtkSmartPointer<SliceInteractorStyle> style;
    int axis = 2;  // the axis normal to the slice
  };
  View views[3];  // shown as axial, coronal, sagittal
  vtkSmartPointer<vtkImageData> labels, image;  // display copies (identity direction)
  vtkSmartPointer<vtkImageMapToColors> colors;
  int dims[3] = {0, 0, 0};
  int cursor[3] = {0, 0, 0};
  double cursorWorld[3] = {0, 0, 0};  // mm, survives a change of grid
  bool hasGrid = false;
  double overlayOpacity = 0.5;
};

void SliceInteractorStyle::OnLeftButtonDown() {
  if (views && views->d_->hasGrid) {
    const int* p = this->Interactor->GetEventPosition();
    SliceViews::Impl::View* view = nullptr;
    for (auto& v : views->d_->views)
      if (v.axis == axis) view = &v;
    if (view) {
      vtkRenderer* r = view->renderer;
      r->SetDisplayPoint(p[0], p[1], 0);
      r->DisplayToWorld();
      double w[4];
      r->GetWorldPoint(w);
      if (w[3] != 0)
        for (int a = 0; a < 3; ++a) w[a] /= w[3];
      double o[3], s[3];
      views->d_->labels->GetOrigin(o);
      views->d_->labels->GetSpacing(s);
      int ijk[3];
      views->cursor(ijk);
      for (int a = 0; a < 3; ++a)
        if (a != axis) ijk[a] = int(std::lround((w[a] - o[a]) / s[a]));
      views->setCursor(ijk[0], ijk[1], ijk[2]);
    }
  }
  vtkInteractorStyleImage::OnLeftButtonDown();
}

SliceViews::SliceViews(QWidget* parent) : QWidget(parent), d_(new Impl) {
  auto* grid = new QGridLayout(this);
  grid->setContentsMargins(0, 0, 0, 0);
  grid->setSpacing(2);
  const int axes[3] = {2, 1, 0};
  d_->colors = vtkSmartPointer<vtkImageMapToColors>::New();
  d_->colors->SetOutputFormatToRGBA();
  for (int v = 0; v < 3; ++v) {
    Impl::View& view = d_->views[v];
    view.axis = axes[v];
    auto* box = new QWidget(this);
    auto* layout = new QVBoxLayout(box);
    layout->setContentsMargins(0, 0, 0, 0);
    layout->setSpacing(1);
    view.widget = new QVTKOpenGLNativeWidget(box);
    view.widget->setMinimumSize(160, 160);
    auto window = vtkSmartPointer<vtkGenericOpenGLRenderWindow>::New();
    view.widget->setRenderWindow(window);
    view.renderer = vtkSmartPointer<vtkRenderer>::New();
    view.renderer->SetBackground(0, 0, 0);
    window->AddRenderer(view.renderer);
    view.baseMapper = vtkSmartPointer<vtkImageSliceMapper>::New();
    view.overlayMapper = vtkSmartPointer<vtkImageSliceMapper>::New();
    view.baseMapper->SetOrientation(view.axis);
    view.overlayMapper->SetOrientation(view.axis);
    view.overlayMapper->SetInputConnection(d_->colors->GetOutputPort());
    view.base = vtkSmartPointer<vtkImageSlice>::New();
    view.base->SetMapper(view.baseMapper);
    view.overlay = vtkSmartPointer<vtkImageSlice>::New();
    view.overlay->SetMapper(view.overlayMapper);
    view.overlay->GetProperty()->SetOpacity(d_->overlayOpacity);
    view.overlay->PickableOff();
    view.cross = vtkSmartPointer<vtkPolyData>::New();
    auto crossMapper = vtkSmartPointer<vtkPolyDataMapper>::New();
    crossMapper->SetInputData(view.cross);
    view.crossActor = vtkSmartPointer<vtkActor>::New();
    view.crossActor->SetMapper(crossMapper);
    view.crossActor->GetProperty()->SetColor(1.0, 0.85, 0.1);
    view.crossActor->PickableOff();
    view.text = vtkSmartPointer<vtkTextActor>::New();
    view.text->GetTextProperty()->SetFontSize(13);
    view.text->GetTextProperty()->SetColor(0.9, 0.9, 0.9);
    view.text->SetPosition(6, 6);
    view.style = vtkSmartPointer<SliceInteractorStyle>::New();
    view.style->views = this;
    view.style->axis = view.axis;
    view.style->SetInteractionModeToImage2D();
    view.style->SetCurrentImageNumber(0);
    view.widget->interactor()->SetInteractorStyle(view.style);
    view.slider = new QSlider(Qt::Horizontal, box);
    view.slider->setToolTip(QString("%1 slice").arg(kNames[view.axis]));
    layout->addWidget(view.widget, 1);
    layout->addWidget(view.slider);
    grid->addWidget(box, 0, v);
    connect(view.slider, &QSlider::valueChanged, this, [this, axis = view.axis](int value) {
      int ijk[3];
      cursor(ijk);
      ijk[axis] = value;
      setCursor(ijk[0], ijk[1], ijk[2]);
    });
  }
}

SliceViews::~SliceViews() {
  for (auto& v : d_->views) v.style->views = nullptr;
  delete d_;
}

void SliceViews::clear() {
  d_->hasGrid = false;
  for (auto& v : d_->views) {
    v.renderer->RemoveAllViewProps();
    v.widget->renderWindow()->Render();
  }
}

void SliceViews::setVolumes(vtkImageData* labels, vtkImageData* image, const LabelTable& table,
                            const std::vector<int>& boneLabels) {
  if (!labels) return clear();
  int dims[3];
  labels->GetDimensions(dims);
  // Posed volumes grow with the pose: keep the cursor where it is in space, and the camera.
  const bool first = !d_->hasGrid;
  // Shown in the voxel-aligned frame: the direction matrix is dropped for display.
  d_->labels = vtkSmartPointer<vtkImageData>::New();
  d_->labels->ShallowCopy(labels);
  d_->labels->GetDirectionMatrix()->Identity();
  d_->image = nullptr;
  if (image) {
    d_->image = vtkSmartPointer<vtkImageData>::New();
    d_->image->ShallowCopy(image);
    d_->image->GetDirectionMatrix()->Identity();
  }
  double range[2];
  d_->labels->GetPointData()->GetScalars()->GetRange(range);
  d_->colors->SetLookupTable(labelLookupTable(int(std::max(1.0, range[1])), table, boneLabels, 1.0));
  d_->colors->SetInputData(d_->labels);
  vtkImageData* base = d_->image ? d_->image.Get() : d_->labels.Get();
  double baseRange[2];
  base->GetPointData()->GetScalars()->GetRange(baseRange);
  for (auto& v : d_->views) {
    v.baseMapper->SetInputData(base);
    if (!v.renderer->HasViewProp(v.base)) {
      v.renderer->AddViewProp(v.base);
      v.renderer->AddViewProp(v.overlay);
      v.renderer->AddViewProp(v.crossActor);
      v.renderer->AddViewProp(v.text);
    }
    v.overlay->SetVisibility(d_->overlayOpacity > 0);
  }
  std::copy(dims, dims + 3, d_->dims);
  double o[3], sp[3];
  d_->labels->GetOrigin(o);
  d_->labels->GetSpacing(sp);
  for (int a = 0; a < 3; ++a)
    d_->cursor[a] = first ? dims[a] / 2 : std::clamp(int(std::lround((d_->cursorWorld[a] - o[a]) / sp[a])), 0, dims[a] - 1);
  for (auto& v : d_->views) {
    QSignalBlocker block(v.slider);
    v.slider->setRange(0, dims[v.axis] - 1);
  }
  if (first) {
    for (int a = 0; a < 3; ++a) d_->cursorWorld[a] = o[a] + sp[a] * d_->cursor[a];
    if (d_->image)  // a soft-tissue window for CT, the whole range otherwise
      setWindowLevel(baseRange[1] - baseRange[0] > 1000 ? 400 : baseRange[1] - baseRange[0],
                     baseRange[1] - baseRange[0] > 1000 ? 40 : 0.5 * (baseRange[0] + baseRange[1]));
    else
      setWindowLevel(std::max(1.0, baseRange[1] - baseRange[0]) * 4, baseRange[1] * 1.5);
    for (auto& v : d_->views) {
      vtkCamera* camera = v.renderer->GetActiveCamera();
      camera->ParallelProjectionOn();
      camera->SetFocalPoint(0, 0, 0);
      // Radiological convention: patient's left on the right of the axial and coronal views.
      if (v.axis == 2) camera->SetPosition(0, 0, -1), camera->SetViewUp(0, -1, 0);
      if (v.axis == 1) camera->SetPosition(0, -1, 0), camera->SetViewUp(0, 0, 1);
      if (v.axis == 0) camera->SetPosition(1, 0, 0), camera->SetViewUp(0, 0, 1);
    }
    d_->hasGrid = true;
    updateCursor();
    for (auto& v : d_->views) {
      v.renderer->ResetCamera();
      // ResetCamera fits the 3D bounding sphere, which leaves a slice small: fit the slice's own
      // width and height to the view instead.
      const int h = v.axis == 2 ? 0 : (v.axis == 1 ? 0 : 1), vert = v.axis == 2 ? 1 : 2;
      const double width = dims[h] * sp[h], height = dims[vert] * sp[vert];
      const int* size = v.renderer->GetSize();
      const double aspect = size[1] > 0 ? double(size[0]) / size[1] : 1.0;
      v.renderer->GetActiveCamera()->SetParallelScale(0.52 * std::max(height, width / std::max(aspect, 1e-3)));
    }
  } else {
    updateCursor();
  }
  render();
}

void SliceViews::setCursor(int i, int j, int k) {
  if (!d_->hasGrid) return;
  const int ijk[3] = {i, j, k};
  bool changed = false;
  double o[3], sp[3];
  d_->labels->GetOrigin(o);
  d_->labels->GetSpacing(sp);
  for (int a = 0; a < 3; ++a) {
    const int c = std::clamp(ijk[a], 0, d_->dims[a] - 1);
    changed |= c != d_->cursor[a];
    d_->cursor[a] = c;
    d_->cursorWorld[a] = o[a] + sp[a] * c;
  }
  if (!changed) return;
  updateCursor();
  render();
  emit cursorChanged(d_->cursor[0], d_->cursor[1], d_->cursor[2]);
}

void SliceViews::cursor(int ijk[3]) const { std::copy(d_->cursor, d_->cursor + 3, ijk); }

int SliceViews::labelAtCursor() const {
  if (!d_->hasGrid) return 0;
  return int(d_->labels->GetScalarComponentAsDouble(d_->cursor[0], d_->cursor[1], d_->cursor[2], 0));
}

void SliceViews::updateCursor() {
  double o[3], s[3];
  d_->labels->GetOrigin(o);
  d_->labels->GetSpacing(s);
  const double lo[3] = {o[0], o[1], o[2]};
  double hi[3], c[3];
  for (int a = 0; a < 3; ++a) {
    hi[a] = o[a] + s[a] * (d_->dims[a] - 1);
    c[a] = o[a] + s[a] * d_->cursor[a];
  }
  const int label = labelAtCursor();
  for (auto& v : d_->views) {
    v.baseMapper->SetSliceNumber(d_->cursor[v.axis]);
    v.overlayMapper->SetSliceNumber(d_->cursor[v.axis]);
    {
      QSignalBlocker block(v.slider);
      v.slider->setValue(d_->cursor[v.axis]);
    }
    // Two lines through the cursor in the slice plane, nudged towards the camera.
    const int a1 = (v.axis + 1) % 3, a2 = (v.axis + 2) % 3;
    auto points = vtkSmartPointer<vtkPoints>::New();
    double p[3];
    const double nudge = v.axis == 0 ? s[0] : -s[v.axis];
    for (int line = 0; line < 2; ++line) {
      const int along = line == 0 ? a1 : a2;
      for (int end = 0; end < 2; ++end) {
        std::copy(c, c + 3, p);
        p[v.axis] += nudge;
        p[along] = end == 0 ? lo[along] : hi[along];
        points->InsertNextPoint(p);
      }
    }
    auto lines = vtkSmartPointer<vtkCellArray>::New();
    const vtkIdType l0[2] = {0, 1}, l1[2] = {2, 3};
    lines->InsertNextCell(2, l0);
    lines->InsertNextCell(2, l1);
    v.cross->SetPoints(points);
    v.cross->SetLines(lines);
    v.cross->Modified();
    v.text->SetInput(QString("%1  slice %2/%3   label %4")
                         .arg(kNames[v.axis])
                         .arg(d_->cursor[v.axis] + 1)
                         .arg(d_->dims[v.axis])
                         .arg(label)
                         .toUtf8()
                         .constData());
  }
}

void SliceViews::setOverlayOpacity(double opacity) {
  d_->overlayOpacity = opacity;
  for (auto& v : d_->views) {
    v.overlay->GetProperty()->SetOpacity(opacity);
    v.overlay->SetVisibility(opacity > 0);
  }
  render();
}

void SliceViews::setWindowLevel(double window, double level) {
  for (auto& v : d_->views) {
    v.base->GetProperty()->SetColorWindow(window);
    v.base->GetProperty()->SetColorLevel(level);
  }
}

void SliceViews::render() {
  for (auto& v : d_->views) v.widget->renderWindow()->Render();
}

}  // namespace repose
