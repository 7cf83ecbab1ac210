#include "slice_views.h"

#include <algorithm>
#include <cmath>

#include <QEvent>
#include <QGridLayout>
#include <QLabel>
#include <QMouseEvent>
#include <QSlider>
#include <QToolTip>
#include <QVBoxLayout>
#include <QVTKOpenGLNativeWidget.h>
#include <vtkActor.h>
#include <vtkActor2D.h>
#include <vtkCallbackCommand.h>
#include <vtkCamera.h>
#include <vtkCellArray.h>
#include <vtkCoordinate.h>
#include <vtkDataArray.h>
#include <vtkGenericOpenGLRenderWindow.h>
#include <vtkImageData.h>
#include <vtkImageMapToColors.h>
#include <vtkImageProperty.h>
#include <vtkImageSlice.h>
#include <vtkImageSliceMapper.h>
#include <vtkInteractorStyleImage.h>
#include <vtkLookupTable.h>
#include <vtkMath.h>
#include <vtkObjectFactory.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkPolyDataMapper2D.h>
#include <vtkProperty.h>
#include <vtkProperty2D.h>
#include <vtkRenderWindowInteractor.h>
#include <vtkRenderer.h>
#include <vtkTextActor.h>
#include <vtkTextProperty.h>

#include "label_colors.h"
#include "lps_image.h"

namespace repose {

/// vtkInteractorStyleImage (left drag: window/level, right drag: zoom, middle: pan) where a left
/// click also moves the linked cursor.
class SliceInteractorStyle : public vtkInteractorStyleImage {
public:
  static SliceInteractorStyle* New();
  vtkTypeMacro(SliceInteractorStyle, vtkInteractorStyleImage);
  SliceViews* views = nullptr;
  int view = 0;
  void OnLeftButtonDown() override;
};
vtkStandardNewMacro(SliceInteractorStyle);

namespace {
const char* kNames[3] = {"Axial", "Coronal", "Sagittal"};
const int kNormal[3] = {2, 1, 0};  // the LPS axis normal to each view

/// Patient direction of an LPS vector's dominant axis: x+ left, y+ posterior, z+ superior.
QString letterFor(const double v[3]) {
  int a = 0;
  for (int i = 1; i < 3; ++i)
    if (std::fabs(v[i]) > std::fabs(v[a])) a = i;
  static const char* letters[3][2] = {{"R", "L"}, {"A", "P"}, {"I", "S"}};
  return letters[a][v[a] > 0 ? 1 : 0];
}

/// "L 12.0" / "P 3.5" / "S 100.0": an LPS coordinate as a patient direction.
QString patientCoordinate(int axis, double v) {
  static const char* letters[3][2] = {{"R", "L"}, {"A", "P"}, {"I", "S"}};
  return QString("%1 %2").arg(letters[axis][v >= 0 ? 1 : 0]).arg(std::fabs(v), 0, 'f', 1);
}

/// 1, 2 or 5 times a power of ten, at most `mm`.
double niceLength(double mm) {
  const double p = std::pow(10.0, std::floor(std::log10(std::max(mm, 1e-6))));
  for (double m : {5.0, 2.0, 1.0})
    if (m * p <= mm) return m * p;
  return p;
}

/// An actor drawing `lines` in one colour (Actor/Mapper: 3D or 2D).
template <class Actor, class Mapper>
vtkSmartPointer<Actor> lineActor(vtkPolyData* lines, double r, double g, double b, double width) {
  auto mapper = vtkSmartPointer<Mapper>::New();
  mapper->SetInputData(lines);
  auto actor = vtkSmartPointer<Actor>::New();
  actor->SetMapper(mapper);
  actor->GetProperty()->SetColor(r, g, b);
  actor->GetProperty()->SetLineWidth(width);
  actor->PickableOff();
  return actor;
}

vtkSmartPointer<vtkTextActor> makeText(int size, double r, double g, double b) {
  auto text = vtkSmartPointer<vtkTextActor>::New();
  text->GetTextProperty()->SetFontSize(size);
  text->GetTextProperty()->SetColor(r, g, b);
  text->GetTextProperty()->SetShadow(true);
  return text;
}
}  // namespace

struct SliceViews::Impl {
  struct View {
    QVTKOpenGLNativeWidget* widget = nullptr;
    QSlider* slider = nullptr;
    vtkSmartPointer<vtkRenderer> renderer;
    vtkSmartPointer<vtkImageSliceMapper> baseMapper, overlayMapper;
    vtkSmartPointer<vtkImageSlice> base, overlay;
    vtkSmartPointer<vtkPolyData> cross, scaleBar;
    vtkSmartPointer<vtkActor> crossActor;
    vtkSmartPointer<vtkActor2D> scaleBarActor;
    QLabel* status = nullptr;  // above the view: the slice's position and the label at the cursor
    vtkSmartPointer<vtkTextActor> scaleText, letters[4];  // letters: left, right, top, bottom edges
    vtkSmartPointer<SliceInteractorStyle> style;
    vtkSmartPointer<vtkCallbackCommand> beforeRender;
  };
  View views[3];
  vtkSmartPointer<vtkImageData> labels, image;  // display copies: identity direction, world = LPS
  vtkSmartPointer<vtkImageMapToColors> colors;
  LabelTable table;
  int dims[3] = {0, 0, 0};
  double origin[3] = {0, 0, 0}, spacing[3] = {1, 1, 1};
  Eigen::Vector3d cursor = Eigen::Vector3d::Zero();  // LPS mm
  bool hasGrid = false;
  double overlayOpacity = 0.5;

  int sliceIndex(int axis, double mm) const {
    return std::clamp(int(std::lround((mm - origin[axis]) / spacing[axis])), 0, std::max(0, dims[axis] - 1));
  }
  Eigen::Vector3d clampToGrid(const Eigen::Vector3d& p) const {
    Eigen::Vector3d c;
    for (int a = 0; a < 3; ++a) c[a] = std::clamp(p[a], origin[a], origin[a] + spacing[a] * (dims[a] - 1));
    return c;
  }
  bool inGrid(const Eigen::Vector3d& p, int ijk[3]) const {
    for (int a = 0; a < 3; ++a) {
      const double u = (p[a] - origin[a]) / spacing[a];
      if (u < -0.5 || u > dims[a] - 0.5) return false;
      ijk[a] = std::clamp(int(std::lround(u)), 0, dims[a] - 1);
    }
    return true;
  }
  /// World point under display pixel (x, y) on the view's current slice plane.
  Eigen::Vector3d worldAt(int v, int x, int y) const {
    vtkRenderer* r = views[v].renderer;
    r->SetDisplayPoint(x, y, 0);
    r->DisplayToWorld();
    double w[4];
    r->GetWorldPoint(w);
    Eigen::Vector3d p(w[0], w[1], w[2]);
    if (w[3] != 0) p /= w[3];
    const int n = kNormal[v];
    p[n] = origin[n] + spacing[n] * sliceIndex(n, cursor[n]);
    return p;
  }
};

void SliceInteractorStyle::OnLeftButtonDown() {
  if (views && views->d_->hasGrid) {
    const int* p = this->Interactor->GetEventPosition();
    views->setCursorPosition(views->d_->worldAt(view, p[0], p[1]));
  }
  vtkInteractorStyleImage::OnLeftButtonDown();
}

SliceViews::SliceViews(QWidget* parent) : QWidget(parent), d_(new Impl) {
  auto* grid = new QGridLayout(this);
  grid->setContentsMargins(0, 0, 0, 0);
  grid->setSpacing(2);
  d_->colors = vtkSmartPointer<vtkImageMapToColors>::New();
  d_->colors->SetOutputFormatToRGBA();
  for (int v = 0; v < 3; ++v) {
    Impl::View& view = d_->views[v];
    auto* box = new QWidget(this);
    auto* layout = new QVBoxLayout(box);
    layout->setContentsMargins(0, 0, 0, 0);
    layout->setSpacing(1);
    view.widget = new QVTKOpenGLNativeWidget(box);
    view.widget->setMinimumSize(160, 160);
    view.widget->setMouseTracking(true);
    view.widget->installEventFilter(this);
    auto window = vtkSmartPointer<vtkGenericOpenGLRenderWindow>::New();
    view.widget->setRenderWindow(window);
    view.renderer = vtkSmartPointer<vtkRenderer>::New();
    view.renderer->SetBackground(0, 0, 0);
    window->AddRenderer(view.renderer);
    view.baseMapper = vtkSmartPointer<vtkImageSliceMapper>::New();
    view.overlayMapper = vtkSmartPointer<vtkImageSliceMapper>::New();
    view.baseMapper->SetOrientation(kNormal[v]);
    view.overlayMapper->SetOrientation(kNormal[v]);
    view.overlayMapper->SetInputConnection(d_->colors->GetOutputPort());
    view.base = vtkSmartPointer<vtkImageSlice>::New();
    view.base->SetMapper(view.baseMapper);
    view.overlay = vtkSmartPointer<vtkImageSlice>::New();
    view.overlay->SetMapper(view.overlayMapper);
    view.overlay->GetProperty()->SetOpacity(d_->overlayOpacity);
    view.overlay->GetProperty()->SetInterpolationTypeToNearest();  // labels have no in-between values
    view.overlay->PickableOff();
    view.cross = vtkSmartPointer<vtkPolyData>::New();
    view.crossActor = lineActor<vtkActor, vtkPolyDataMapper>(view.cross, 1.0, 0.85, 0.1, 1);
    view.status = new QLabel(kNames[v], box);
    view.status->setTextInteractionFlags(Qt::TextSelectableByMouse);
    // Orientation letters at the middle of each edge.
    const double at[4][2] = {{0.02, 0.5}, {0.98, 0.5}, {0.5, 0.98}, {0.5, 0.02}};
    for (int e = 0; e < 4; ++e) {
      view.letters[e] = makeText(16, 1.0, 0.85, 0.3);
      vtkTextProperty* t = view.letters[e]->GetTextProperty();
      t->SetBold(true);
      t->SetJustification(e == 0 ? VTK_TEXT_LEFT : e == 1 ? VTK_TEXT_RIGHT : VTK_TEXT_CENTERED);
      t->SetVerticalJustification(e == 3 ? VTK_TEXT_BOTTOM : e == 2 ? VTK_TEXT_TOP : VTK_TEXT_CENTERED);
      view.letters[e]->GetPositionCoordinate()->SetCoordinateSystemToNormalizedViewport();
      view.letters[e]->SetPosition(at[e][0], at[e][1]);
    }
    // Scale bar, bottom right, in display pixels (rebuilt before every render from the zoom).
    view.scaleBar = vtkSmartPointer<vtkPolyData>::New();
    view.scaleBarActor = lineActor<vtkActor2D, vtkPolyDataMapper2D>(view.scaleBar, 0.9, 0.9, 0.9, 2);
    view.scaleText = makeText(12, 0.9, 0.9, 0.9);
    view.scaleText->GetTextProperty()->SetJustificationToCentered();
    view.beforeRender = vtkSmartPointer<vtkCallbackCommand>::New();
    view.beforeRender->SetClientData(this);
    view.beforeRender->SetCallback([](vtkObject* caller, unsigned long, void* self, void*) {
      auto* views = static_cast<SliceViews*>(self);
      for (int i = 0; i < 3; ++i)
        if (views->d_->views[i].renderer.Get() == caller) views->updateAnnotations(i);
    });
    view.renderer->AddObserver(vtkCommand::StartEvent, view.beforeRender);
    view.style = vtkSmartPointer<SliceInteractorStyle>::New();
    view.style->views = this;
    view.style->view = v;
    view.style->SetInteractionModeToImage2D();
    view.style->SetCurrentImageNumber(0);
    view.widget->interactor()->SetInteractorStyle(view.style);
    view.slider = new QSlider(Qt::Horizontal, box);
    view.slider->setToolTip(QString("%1 slice").arg(kNames[v]));
    layout->addWidget(view.status);
    layout->addWidget(view.widget, 1);
    layout->addWidget(view.slider);
    grid->addWidget(box, 0, v);
    connect(view.slider, &QSlider::valueChanged, this, [this, v](int index) {
      Eigen::Vector3d c = d_->cursor;
      const int n = kNormal[v];
      c[n] = d_->origin[n] + d_->spacing[n] * index;
      setCursorPosition(c);
    });
  }
}

SliceViews::~SliceViews() {
  for (auto& v : d_->views) {
    v.style->views = nullptr;
    v.renderer->RemoveObserver(v.beforeRender);
  }
  delete d_;
}

bool SliceViews::hasVolumes() const { return d_->hasGrid; }
vtkRenderWindow* SliceViews::renderWindow(View view) const { return d_->views[view].widget->renderWindow(); }
vtkRenderer* SliceViews::renderer(View view) const { return d_->views[view].renderer; }

void SliceViews::clear() {
  d_->hasGrid = false;
  d_->labels = d_->image = nullptr;
  for (int i = 0; i < 3; ++i) d_->views[i].status->setText(kNames[i]);
  for (auto& v : d_->views) {
    v.renderer->RemoveAllViewProps();
    v.widget->renderWindow()->Render();
  }
}

void SliceViews::setVolumes(vtkImageData* labels, vtkImageData* image, const LabelTable& table,
                            const std::vector<int>& boneLabels) {
  if (!labels) return clear();
  const bool first = !d_->hasGrid;
  d_->labels = lpsAlignedImage(labels, true);
  double range[2] = {0, 1};
  if (image) {
    image->GetPointData()->GetScalars()->GetRange(range);
    d_->image = lpsAlignedImage(image, false, range[0]);
  } else {
    d_->image = nullptr;
  }
  d_->table = table;
  d_->labels->GetDimensions(d_->dims);
  d_->labels->GetOrigin(d_->origin);
  d_->labels->GetSpacing(d_->spacing);
  d_->labels->GetPointData()->GetScalars()->GetRange(range);
  d_->colors->SetLookupTable(labelLookupTable(int(std::max(1.0, range[1])), table, boneLabels, 1.0));
  d_->colors->SetInputData(d_->labels);
  vtkImageData* base = d_->image ? d_->image.Get() : d_->labels.Get();
  double baseRange[2];
  base->GetPointData()->GetScalars()->GetRange(baseRange);
  for (int v = 0; v < 3; ++v) {
    Impl::View& view = d_->views[v];
    view.baseMapper->SetInputData(base);
    if (!view.renderer->HasViewProp(view.base)) {
      for (vtkProp* p : std::initializer_list<vtkProp*>{view.base, view.overlay, view.crossActor, view.scaleBarActor,
                                                        view.scaleText})
        view.renderer->AddViewProp(p);
      for (auto& letter : view.letters) view.renderer->AddViewProp(letter);
    }
    view.overlay->SetVisibility(d_->overlayOpacity > 0);
    QSignalBlocker block(view.slider);
    view.slider->setRange(0, d_->dims[kNormal[v]] - 1);
  }
  d_->hasGrid = true;
  if (first) {
    for (int a = 0; a < 3; ++a) d_->cursor[a] = d_->origin[a] + d_->spacing[a] * (d_->dims[a] / 2);
    if (d_->image)  // a soft-tissue window for CT, the whole range otherwise
      setWindowLevel(baseRange[1] - baseRange[0] > 1000 ? 400 : baseRange[1] - baseRange[0],
                     baseRange[1] - baseRange[0] > 1000 ? 40 : 0.5 * (baseRange[0] + baseRange[1]));
    else
      setWindowLevel(std::max(1.0, baseRange[1] - baseRange[0]) * 4, baseRange[1] * 1.5);
    fitViews();
  } else {
    // The posed grid moves with the body: the cursor keeps its place in space (within the grid).
    d_->cursor = d_->clampToGrid(d_->cursor);
  }
  updateCursor();
  keepCursorInSight();
  render();
}

void SliceViews::fitViews() {
  for (int v = 0; v < 3; ++v) {
    vtkCamera* camera = d_->views[v].renderer->GetActiveCamera();
    camera->ParallelProjectionOn();
    camera->SetFocalPoint(0, 0, 0);
    // Radiological convention (see the header): screen right = direction of projection x view up.
    if (v == Axial) camera->SetPosition(0, 0, -1), camera->SetViewUp(0, -1, 0);
    if (v == Coronal) camera->SetPosition(0, -1, 0), camera->SetViewUp(0, 0, 1);
    if (v == Sagittal) camera->SetPosition(1, 0, 0), camera->SetViewUp(0, 0, 1);
    d_->views[v].renderer->ResetCamera();
    // ResetCamera fits the 3D bounding sphere, which leaves a slice small: fit the slice's own
    // width and height to the view instead.
    const int h = v == Sagittal ? 1 : 0, vert = v == Axial ? 1 : 2;
    const double width = d_->dims[h] * d_->spacing[h], height = d_->dims[vert] * d_->spacing[vert];
    const int* size = d_->views[v].renderer->GetSize();
    const double aspect = size[1] > 0 ? double(size[0]) / size[1] : 1.0;
    camera->SetParallelScale(0.52 * std::max(height, width / std::max(aspect, 1e-3)));
  }
}

void SliceViews::keepCursorInSight() {
  // A view whose cursor left the visible area (the body moved with the pose) pans to centre it.
  for (int v = 0; v < 3; ++v) {
    vtkRenderer* r = d_->views[v].renderer;
    const int* size = r->GetSize();
    const Eigen::Vector2d p = displayPosition(View(v), d_->cursor);
    const double mx = 0.05 * size[0], my = 0.05 * size[1];
    if (p.x() >= mx && p.x() <= size[0] - mx && p.y() >= my && p.y() <= size[1] - my) continue;
    vtkCamera* camera = r->GetActiveCamera();
    double f[3], pos[3];
    camera->GetFocalPoint(f);
    camera->GetPosition(pos);
    const int n = kNormal[v];
    for (int a = 0; a < 3; ++a)
      if (a != n) {
        const double shift = d_->cursor[a] - f[a];
        f[a] += shift, pos[a] += shift;
      }
    camera->SetFocalPoint(f);
    camera->SetPosition(pos);
  }
}

void SliceViews::setCursorPosition(const Eigen::Vector3d& lps) {
  if (!d_->hasGrid) return;
  const Eigen::Vector3d c = d_->clampToGrid(lps);
  if ((c - d_->cursor).norm() < 1e-9) return;
  d_->cursor = c;
  updateCursor();
  render();
  emit cursorChanged(c);
}

Eigen::Vector3d SliceViews::cursorPosition() const { return d_->cursor; }

void SliceViews::centreOn(const Eigen::Vector3d& lps) {
  if (!d_->hasGrid) return;
  d_->cursor = d_->clampToGrid(lps);
  for (int v = 0; v < 3; ++v) {
    vtkCamera* camera = d_->views[v].renderer->GetActiveCamera();
    double f[3], pos[3];
    camera->GetFocalPoint(f);
    camera->GetPosition(pos);
    for (int a = 0; a < 3; ++a)
      if (a != kNormal[v]) pos[a] += d_->cursor[a] - f[a], f[a] = d_->cursor[a];
    camera->SetFocalPoint(f);
    camera->SetPosition(pos);
  }
  updateCursor();
  render();
  emit cursorChanged(d_->cursor);
}

int SliceViews::labelAt(const Eigen::Vector3d& lps) const {
  int ijk[3];
  if (!d_->hasGrid || !d_->inGrid(lps, ijk)) return 0;
  return int(d_->labels->GetScalarComponentAsDouble(ijk[0], ijk[1], ijk[2], 0));
}

int SliceViews::labelAtCursor() const { return labelAt(d_->cursor); }

QString SliceViews::labelName(int value) const {
  const LabelInfo* info = d_->table.find(value);
  return info ? QString::fromStdString(info->name) : QString("label %1").arg(value);
}

void SliceViews::updateCursor() {
  if (!d_->hasGrid) return;
  const double* o = d_->origin;
  const double* s = d_->spacing;
  const int label = labelAtCursor();
  const QString labelText = label ? QString("%1 (%2)").arg(labelName(label)).arg(label) : QString("background");
  for (int v = 0; v < 3; ++v) {
    Impl::View& view = d_->views[v];
    const int n = kNormal[v];
    const int index = d_->sliceIndex(n, d_->cursor[n]);
    view.baseMapper->SetSliceNumber(index);
    view.overlayMapper->SetSliceNumber(index);
    {
      QSignalBlocker block(view.slider);
      view.slider->setValue(index);
    }
    // Two lines through the cursor across the grid, on the shown slice nudged towards the camera.
    double plane[3];
    for (int a = 0; a < 3; ++a) plane[a] = d_->cursor[a];
    plane[n] = o[n] + s[n] * index + (v == Sagittal ? s[n] : -s[n]);
    auto points = vtkSmartPointer<vtkPoints>::New();
    for (int along : {(n + 1) % 3, (n + 2) % 3})
      for (int end = 0; end < 2; ++end) {
        double p[3] = {plane[0], plane[1], plane[2]};
        p[along] = o[along] + (end ? s[along] * (d_->dims[along] - 1) : 0.0);
        points->InsertNextPoint(p);
      }
    auto lines = vtkSmartPointer<vtkCellArray>::New();
    const vtkIdType l0[2] = {0, 1}, l1[2] = {2, 3};
    lines->InsertNextCell(2, l0);
    lines->InsertNextCell(2, l1);
    view.cross->SetPoints(points);
    view.cross->SetLines(lines);
    view.cross->Modified();
    view.status->setText(QString("%1  %2 mm   %3").arg(kNames[v], patientCoordinate(n, o[n] + s[n] * index), labelText));
  }
}

void SliceViews::updateAnnotations(int v) {
  Impl::View& view = d_->views[v];
  vtkCamera* camera = view.renderer->GetActiveCamera();
  double dop[3], up[3], right[3], opposite[3];
  camera->GetDirectionOfProjection(dop);
  camera->GetViewUp(up);
  vtkMath::Cross(dop, up, right);  // screen right
  const double* toward[4] = {right, right, up, up};
  for (int e = 0; e < 4; ++e) {
    const double sign = (e == 0 || e == 3) ? -1 : 1;  // left and bottom edges look the other way
    for (int a = 0; a < 3; ++a) opposite[a] = sign * toward[e][a];
    view.letters[e]->SetInput(letterFor(opposite).toUtf8().constData());
  }
  // Scale bar: about a fifth of the view wide, 1-2-5 mm steps.
  const int* size = view.renderer->GetSize();
  if (size[1] <= 0 || camera->GetParallelScale() <= 0) return;
  const double pixelsPerMm = size[1] / (2.0 * camera->GetParallelScale());
  const double mm = niceLength(0.2 * size[0] / pixelsPerMm);
  const double length = mm * pixelsPerMm, x1 = size[0] - 14.0, x0 = x1 - length, y = 16.0, tick = 5.0;
  auto points = vtkSmartPointer<vtkPoints>::New();
  const double xy[4][2] = {{x0, y + tick}, {x0, y}, {x1, y}, {x1, y + tick}};
  for (const auto& p : xy) points->InsertNextPoint(p[0], p[1], 0);
  auto line = vtkSmartPointer<vtkCellArray>::New();
  const vtkIdType ids[4] = {0, 1, 2, 3};
  line->InsertNextCell(4, ids);
  view.scaleBar->SetPoints(points);
  view.scaleBar->SetLines(line);
  view.scaleBar->Modified();
  view.scaleText->SetInput(QString("%1 mm").arg(mm).toUtf8().constData());
  view.scaleText->SetPosition(0.5 * (x0 + x1), y + tick + 2);
}

QStringList SliceViews::orientationLetters(View view) const {
  QStringList letters;
  for (const auto& letter : d_->views[view].letters) letters << QString::fromUtf8(letter->GetInput() ? letter->GetInput() : "");
  return letters;
}

QString SliceViews::scaleBarCaption(View view) const {
  const char* t = d_->views[view].scaleText->GetInput();
  return t ? QString::fromUtf8(t) : QString();
}

QString SliceViews::statusLine(View view) const { return d_->views[view].status->text(); }

Eigen::Vector2d SliceViews::displayPosition(View view, const Eigen::Vector3d& lps) const {
  vtkRenderer* r = d_->views[view].renderer;
  r->SetWorldPoint(lps.x(), lps.y(), lps.z(), 1.0);
  r->WorldToDisplay();
  double d[3];
  r->GetDisplayPoint(d);
  return {d[0], d[1]};
}

QString SliceViews::describeAt(View view, int x, int y) const {
  if (!d_->hasGrid) return QString();
  const Eigen::Vector3d p = d_->worldAt(view, x, y);
  int ijk[3];
  if (!d_->inGrid(p, ijk)) return QString();
  const int label = int(d_->labels->GetScalarComponentAsDouble(ijk[0], ijk[1], ijk[2], 0));
  QString text = label ? QString("%1 (label %2)").arg(labelName(label)).arg(label) : QString("background (label 0)");
  if (d_->image) text += QString("\nvalue %1").arg(d_->image->GetScalarComponentAsDouble(ijk[0], ijk[1], ijk[2], 0), 0, 'f', 0);
  text += QString("\n%1, %2, %3 mm").arg(patientCoordinate(0, p.x()), patientCoordinate(1, p.y()), patientCoordinate(2, p.z()));
  return text;
}

bool SliceViews::eventFilter(QObject* watched, QEvent* event) {
  if (event->type() == QEvent::MouseMove) {
    auto* mouse = static_cast<QMouseEvent*>(event);
    for (int v = 0; v < 3; ++v) {
      QWidget* w = d_->views[v].widget;
      if (watched != w) continue;
      if (mouse->buttons() != Qt::NoButton) {
        QToolTip::hideText();
        break;
      }
      const double ratio = w->devicePixelRatioF();
      const QString text = describeAt(View(v), int(mouse->pos().x() * ratio), int((w->height() - 1 - mouse->pos().y()) * ratio));
      if (text.isEmpty())
        QToolTip::hideText();
      else
        QToolTip::showText(mouse->globalPos(), text, w);
    }
  }
  return QWidget::eventFilter(watched, event);
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
