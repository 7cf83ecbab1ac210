#include "scene_view.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <vtkActor.h>
#include <vtkCamera.h>
#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkCellPicker.h>
#include <vtkDataArray.h>
#include <vtkGenericOpenGLRenderWindow.h>
#include <vtkGlyph3DMapper.h>
#include <vtkIdList.h>
#include <vtkIntArray.h>
#include <vtkInteractorStyleTrackballCamera.h>
#include <vtkLookupTable.h>
#include <vtkMatrix4x4.h>
#include <vtkObjectFactory.h>
#include <vtkPNGWriter.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkProperty.h>
#include <vtkRegularPolygonSource.h>
#include <vtkRenderWindowInteractor.h>
#include <vtkRenderer.h>
#include <vtkSphereSource.h>
#include <vtkTextActor.h>
#include <vtkTextProperty.h>
#include <vtkWindowToImageFilter.h>

#include "label_colors.h"
#include "surface_lod.h"
#include "array_names.h"

namespace repose {

/// Trackball camera, except that a left drag starting on a bone rotates the bone's joint.
class SceneInteractorStyle : public vtkInteractorStyleTrackballCamera {
public:
  static SceneInteractorStyle* New();
  vtkTypeMacro(SceneInteractorStyle, vtkInteractorStyleTrackballCamera);
  SceneView* view = nullptr;

  void OnLeftButtonDown() override {
    const int* p = this->Interactor->GetEventPosition();
    const int joint = view ? view->pickJoint(p[0], p[1]) : -1;
    if (joint < 0) return vtkInteractorStyleTrackballCamera::OnLeftButtonDown();
    dragging_ = true;
    last_[0] = p[0], last_[1] = p[1];
    view->setSelectedJoint(joint);
    emit view->jointPicked(joint);
    emit view->dragStarted(joint);
  }
  void OnMouseMove() override {
    if (!dragging_) return vtkInteractorStyleTrackballCamera::OnMouseMove();
    const int* p = this->Interactor->GetEventPosition();
    const double dx = p[0] - last_[0], dy = p[1] - last_[1];
    last_[0] = p[0], last_[1] = p[1];
    if ((dx != 0 || dy != 0) && view->onDragRotate) view->onDragRotate(view->selectedJoint(), view->dragRotation(dx, dy));
  }
  void OnLeftButtonUp() override {
    if (!dragging_) return vtkInteractorStyleTrackballCamera::OnLeftButtonUp();
    dragging_ = false;
    emit view->dragEnded();
  }

private:
  bool dragging_ = false;
  int last_[2] = {0, 0};
};
vtkStandardNewMacro(SceneInteractorStyle);

struct SceneView::Impl {
  vtkSmartPointer<vtkRenderer> renderer, overlay;
  vtkSmartPointer<vtkPolyData> skin, tissue, ghost, joints, bones;
  vtkSmartPointer<vtkActor> skinActor, tissueActor, ghostActor, jointActor, boneActor, selectedActor;
  vtkSmartPointer<vtkActor> rings[3];
  vtkSmartPointer<vtkCellPicker> picker;
  vtkSmartPointer<vtkSphereSource> jointSphere;
  vtkSmartPointer<SceneInteractorStyle> style;
  Skeleton skeleton;
  std::vector<int> jointOfLabel;  // label value -> joint (-1)
  std::vector<Eigen::Isometry3d> global;
  // Coarse level for interaction: polydata, actor, and the full-surface vertex of each coarse vertex.
  struct Lod {
    vtkSmartPointer<vtkPolyData> data;
    vtkSmartPointer<vtkActor> actor;
    std::vector<vtkIdType> ids;
  };
  Lod skinLod, tissueLod;
  bool hasLod = false;
  double skinOpacity = 0.3;
  bool skinVisible = true;
  double scale = 10;  // mm, joint sphere radius
  LabelTable table;
  vtkSmartPointer<vtkTextActor> caption;  // names the picked structure
  int root = -1;                          // the skeleton's root joint
  bool hasRootPosition = false;
  Eigen::Vector3d rootPosition = Eigen::Vector3d::Zero();  // posed root centre of the last pose
};

SceneView::SceneView(QWidget* parent) : QVTKOpenGLNativeWidget(parent), d_(new Impl) {
  auto window = vtkSmartPointer<vtkGenericOpenGLRenderWindow>::New();
  // Multisampling multiplies the fill cost; without a GPU (Mesa llvmpipe) it halves the frame rate.
  window->SetMultiSamples(0);
  setRenderWindow(window);
  d_->renderer = vtkSmartPointer<vtkRenderer>::New();
  d_->renderer->SetBackground(0.12, 0.13, 0.16);
  d_->renderer->SetBackground2(0.30, 0.32, 0.38);
  d_->renderer->GradientBackgroundOn();
  d_->overlay = vtkSmartPointer<vtkRenderer>::New();
  d_->overlay->SetLayer(1);
  d_->overlay->InteractiveOff();
  d_->overlay->SetActiveCamera(d_->renderer->GetActiveCamera());
  window->SetNumberOfLayers(2);
  window->AddRenderer(d_->renderer);
  window->AddRenderer(d_->overlay);

  auto makeActor = [](vtkPolyData* data) {
    auto mapper = vtkSmartPointer<vtkPolyDataMapper>::New();
    mapper->SetInputData(data);
    auto actor = vtkSmartPointer<vtkActor>::New();
    actor->SetMapper(mapper);
    return actor;
  };
  d_->skin = vtkSmartPointer<vtkPolyData>::New();
  d_->tissue = vtkSmartPointer<vtkPolyData>::New();
  d_->ghost = vtkSmartPointer<vtkPolyData>::New();
  d_->joints = vtkSmartPointer<vtkPolyData>::New();
  d_->bones = vtkSmartPointer<vtkPolyData>::New();
  d_->skinActor = makeActor(d_->skin);
  d_->skinActor->GetProperty()->SetColor(0.93, 0.75, 0.63);
  d_->skinActor->GetProperty()->SetOpacity(0.3);
  d_->skinActor->GetProperty()->SetSpecular(0.1);
  d_->skinActor->PickableOff();
  d_->tissueActor = makeActor(d_->tissue);
  d_->tissueActor->GetProperty()->SetSpecular(0.2);
  d_->ghostActor = makeActor(d_->ghost);
  d_->ghostActor->GetProperty()->SetRepresentationToWireframe();
  d_->ghostActor->GetProperty()->SetColor(0.3, 0.8, 1.0);
  d_->ghostActor->GetProperty()->SetOpacity(0.25);
  d_->ghostActor->PickableOff();
  d_->ghostActor->VisibilityOff();
  d_->renderer->AddActor(d_->tissueActor);
  d_->renderer->AddActor(d_->skinActor);
  d_->renderer->AddActor(d_->ghostActor);

  // Skeleton overlay: spheres at the joints, lines for the bones, always visible.
  auto sphere = vtkSmartPointer<vtkSphereSource>::New();
  d_->jointSphere = sphere;
  sphere->SetThetaResolution(16);
  sphere->SetPhiResolution(12);
  auto glyphs = vtkSmartPointer<vtkGlyph3DMapper>::New();
  glyphs->SetInputData(d_->joints);
  glyphs->SetSourceConnection(sphere->GetOutputPort());
  glyphs->ScalingOff();
  d_->jointActor = vtkSmartPointer<vtkActor>::New();
  d_->jointActor->SetMapper(glyphs);
  d_->jointActor->GetProperty()->SetColor(0.2, 0.75, 1.0);
  d_->jointActor->PickableOff();
  d_->boneActor = makeActor(d_->bones);
  d_->boneActor->GetProperty()->SetColor(0.2, 0.75, 1.0);
  d_->boneActor->GetProperty()->SetLineWidth(3);
  d_->boneActor->GetProperty()->SetRenderLinesAsTubes(true);
  d_->boneActor->PickableOff();
  auto selectedSphere = vtkSmartPointer<vtkSphereSource>::New();
  selectedSphere->SetThetaResolution(20);
  selectedSphere->SetPhiResolution(16);
  auto selectedMapper = vtkSmartPointer<vtkPolyDataMapper>::New();
  selectedMapper->SetInputConnection(selectedSphere->GetOutputPort());
  d_->selectedActor = vtkSmartPointer<vtkActor>::New();
  d_->selectedActor->SetMapper(selectedMapper);
  d_->selectedActor->GetProperty()->SetColor(1.0, 0.55, 0.1);
  d_->selectedActor->PickableOff();
  d_->selectedActor->VisibilityOff();
  d_->overlay->AddActor(d_->boneActor);
  d_->overlay->AddActor(d_->jointActor);
  d_->overlay->AddActor(d_->selectedActor);
  // Rotation rings of the selected joint about its (posed) x, y, z axes: red, green, blue.
  const double colors[3][3] = {{0.95, 0.25, 0.25}, {0.3, 0.9, 0.3}, {0.3, 0.5, 1.0}};
  for (int a = 0; a < 3; ++a) {
    auto ring = vtkSmartPointer<vtkRegularPolygonSource>::New();
    ring->SetNumberOfSides(64);
    ring->GeneratePolygonOff();
    ring->SetRadius(1.0);
    ring->SetNormal(a == 0 ? 1 : 0, a == 1 ? 1 : 0, a == 2 ? 1 : 0);
    auto mapper = vtkSmartPointer<vtkPolyDataMapper>::New();
    mapper->SetInputConnection(ring->GetOutputPort());
    d_->rings[a] = vtkSmartPointer<vtkActor>::New();
    d_->rings[a]->SetMapper(mapper);
    d_->rings[a]->GetProperty()->SetColor(colors[a][0], colors[a][1], colors[a][2]);
    d_->rings[a]->GetProperty()->SetLineWidth(2.5);
    d_->rings[a]->GetProperty()->SetRenderLinesAsTubes(true);
    d_->rings[a]->PickableOff();
    d_->rings[a]->VisibilityOff();
    d_->overlay->AddActor(d_->rings[a]);
  }

  d_->caption = vtkSmartPointer<vtkTextActor>::New();
  d_->caption->GetTextProperty()->SetFontSize(14);
  d_->caption->GetTextProperty()->SetColor(0.95, 0.95, 0.95);
  d_->caption->GetTextProperty()->SetShadow(true);
  d_->caption->SetPosition(8, 8);
  d_->overlay->AddViewProp(d_->caption);

  d_->picker = vtkSmartPointer<vtkCellPicker>::New();
  d_->picker->SetTolerance(0.0005);
  d_->picker->PickFromListOn();
  d_->picker->AddPickList(d_->tissueActor);
  d_->style = vtkSmartPointer<SceneInteractorStyle>::New();
  d_->style->view = this;
  interactor()->SetInteractorStyle(d_->style);
  d_->renderer->GetActiveCamera()->SetViewUp(0, 0, 1);
}

SceneView::~SceneView() {
  d_->style->view = nullptr;
  delete d_;
}

vtkActor* SceneView::skinActor() const { return d_->skinActor; }
vtkActor* SceneView::tissueActor() const { return d_->tissueActor; }
vtkRenderer* SceneView::renderer() const { return d_->renderer; }

void SceneView::setCase(vtkPolyData* rest, const Skeleton& skeleton, const LabelTable& table) {
  d_->skeleton = skeleton;
  d_->table = table;
  d_->root = -1;
  for (std::size_t j = 0; j < skeleton.size() && d_->root < 0; ++j)
    if (skeleton.joints[j].parent < 0) d_->root = int(j);
  d_->hasRootPosition = false;
  d_->caption->SetInput("");
  d_->global.assign(skeleton.size(), Eigen::Isometry3d::Identity());
  vtkDataArray* labels = rest->GetCellData()->GetArray(repose::arrays::kLabel);
  if (!labels) throw std::runtime_error("the case's surfaces have no cell data 'Label'");
  double range[2];
  labels->GetRange(range, 0);
  const int maxLabel = std::max(1, int(range[1]));
  d_->jointOfLabel = boneOfLabel(skeleton, maxLabel);

  // Split the triangles once; per pose only the shared points change.
  auto skinCells = vtkSmartPointer<vtkCellArray>::New();
  auto tissueCells = vtkSmartPointer<vtkCellArray>::New();
  auto tissueLabels = vtkSmartPointer<vtkIntArray>::New();
  tissueLabels->SetName(repose::arrays::kLabel);
  auto ids = vtkSmartPointer<vtkIdList>::New();
  vtkCellArray* polys = rest->GetPolys();
  const vtkIdType firstPoly = rest->GetNumberOfVerts() + rest->GetNumberOfLines();
  polys->InitTraversal();
  for (vtkIdType c = 0; polys->GetNextCell(ids); ++c) {
    const int label = int(labels->GetTuple1(firstPoly + c));
    if (label < 0) {
      skinCells->InsertNextCell(ids);
    } else {
      tissueCells->InsertNextCell(ids);
      tissueLabels->InsertNextValue(label);
    }
  }
  d_->skin->Initialize();
  d_->skin->SetPoints(rest->GetPoints());
  d_->skin->SetPolys(skinCells);
  d_->tissue->Initialize();
  d_->tissue->SetPoints(rest->GetPoints());
  d_->tissue->SetPolys(tissueCells);
  d_->tissue->GetCellData()->SetScalars(tissueLabels);
  std::vector<int> boneLabels;
  for (const Joint& j : skeleton.joints) boneLabels.insert(boneLabels.end(), j.labels.begin(), j.labels.end());
  auto lut = labelLookupTable(maxLabel, table, boneLabels, 1.0);
  auto* mapper = vtkPolyDataMapper::SafeDownCast(d_->tissueActor->GetMapper());
  mapper->SetLookupTable(lut);
  mapper->SetScalarRange(0, maxLabel);
  mapper->SetScalarModeToUseCellData();
  mapper->ScalarVisibilityOn();
  double skinRgb[3];
  labelColor(-1, table, false, skinRgb);
  d_->skinActor->GetProperty()->SetColor(skinRgb);

  buildLod(rest, lut, maxLabel);
  double b[6];
  rest->GetBounds(b);
  d_->scale = 0.012 * std::sqrt((b[1] - b[0]) * (b[1] - b[0]) + (b[3] - b[2]) * (b[3] - b[2]) + (b[5] - b[4]) * (b[5] - b[4]));
  d_->jointSphere->SetRadius(d_->scale);
  selected_ = -1;
  d_->selectedActor->VisibilityOff();
  for (auto& r : d_->rings) r->VisibilityOff();
  d_->ghostActor->VisibilityOff();
  updateSkeletonGeometry();
  resetCamera();
}

void SceneView::buildLod(vtkPolyData* rest, vtkLookupTable* lut, int maxLabel) {
  dropLod();
  // Above the threshold the interactive display uses a decimated copy (software OpenGL draws about
  // 1-2 M triangles per second per core).
  d_->hasLod = rest->GetNumberOfPolys() > lodThreshold_;
  if (!d_->hasLod) return;
  // About 60 k triangles per part: clustering on a grid of `divisions` along the longest side.
  auto build = [&](Impl::Lod& lod, vtkPolyData* full, vtkActor* like, int divisions) {
    lod.data = decimateKeepingVertices(full, divisions, lod.ids);
    auto mapper = vtkSmartPointer<vtkPolyDataMapper>::New();
    mapper->SetInputData(lod.data);
    auto* fullMapper = vtkPolyDataMapper::SafeDownCast(like->GetMapper());
    mapper->SetScalarVisibility(fullMapper->GetScalarVisibility());
    mapper->SetLookupTable(lut);
    mapper->SetScalarRange(0, maxLabel);
    mapper->SetScalarModeToUseCellData();
    lod.actor = vtkSmartPointer<vtkActor>::New();
    lod.actor->SetMapper(mapper);
    lod.actor->SetProperty(like->GetProperty());
    lod.actor->SetPickable(like->GetPickable());
    lod.actor->VisibilityOff();
    d_->renderer->AddActor(lod.actor);
  };
  build(d_->tissueLod, d_->tissue, d_->tissueActor, 160);
  build(d_->skinLod, d_->skin, d_->skinActor, 100);
  d_->picker->AddPickList(d_->tissueLod.actor);
  setInteractive(interactive_);
}

void SceneView::dropLod() {
  for (Impl::Lod* lod : {&d_->skinLod, &d_->tissueLod}) {
    if (lod->actor) {
      d_->renderer->RemoveActor(lod->actor);
      d_->picker->DeletePickList(lod->actor);
    }
    *lod = Impl::Lod();
  }
  d_->hasLod = false;
}

vtkIdType SceneView::interactiveTriangles() const {
  if (!d_->hasLod) return 0;
  return d_->skinLod.data->GetNumberOfPolys() + d_->tissueLod.data->GetNumberOfPolys();
}

void SceneView::setInteractive(bool interactive) {
  interactive_ = interactive;
  const bool coarse = interactive && d_->hasLod;
  d_->tissueActor->SetVisibility(!coarse);
  d_->skinActor->SetVisibility(!coarse && d_->skinVisible);
  if (d_->hasLod) {
    d_->tissueLod.actor->SetVisibility(coarse);
    d_->skinLod.actor->SetVisibility(coarse && d_->skinVisible);
    if (coarse) updateLodPoints();
  }
}

void SceneView::updateLodPoints() {
  vtkPoints* posed = d_->skin->GetPoints();
  if (!d_->hasLod || !posed) return;
  for (Impl::Lod* lod : {&d_->skinLod, &d_->tissueLod}) {
    auto points = vtkSmartPointer<vtkPoints>::New();
    points->SetDataType(posed->GetDataType());
    points->SetNumberOfPoints(vtkIdType(lod->ids.size()));
    for (std::size_t i = 0; i < lod->ids.size(); ++i) points->SetPoint(vtkIdType(i), posed->GetPoint(lod->ids[i]));
    lod->data->SetPoints(points);
    lod->data->Modified();
  }
}

void SceneView::clearCase() {
  dropLod();
  setInteractive(false);
  d_->skin->Initialize();
  d_->tissue->Initialize();
  d_->joints->Initialize();
  d_->bones->Initialize();
  d_->skeleton = Skeleton();
  d_->global.clear();
  d_->root = -1;
  d_->hasRootPosition = false;
  d_->caption->SetInput("");
  selected_ = -1;
  d_->selectedActor->VisibilityOff();
  for (auto& r : d_->rings) r->VisibilityOff();
  d_->ghostActor->VisibilityOff();
}

void SceneView::updatePose(vtkPolyData* posed, const std::vector<Eigen::Isometry3d>& global) {
  if (posed && posed->GetNumberOfPoints() == d_->skin->GetNumberOfPoints()) {
    d_->skin->SetPoints(posed->GetPoints());
    d_->tissue->SetPoints(posed->GetPoints());
    d_->skin->Modified();
    d_->tissue->Modified();
    if (interactive_) updateLodPoints();
  }
  if (global.size() == d_->skeleton.size()) d_->global = global;
  if (d_->root >= 0 && std::size_t(d_->root) < d_->global.size()) {
    const Eigen::Vector3d r = d_->global[std::size_t(d_->root)] * d_->skeleton.joints[std::size_t(d_->root)].center;
    if (follow_ && d_->hasRootPosition) {  // the camera moves with the body
      vtkCamera* camera = d_->renderer->GetActiveCamera();
      double f[3], p[3];
      camera->GetFocalPoint(f);
      camera->GetPosition(p);
      for (int a = 0; a < 3; ++a) f[a] += r[a] - d_->rootPosition[a], p[a] += r[a] - d_->rootPosition[a];
      camera->SetFocalPoint(f);
      camera->SetPosition(p);
      d_->renderer->ResetCameraClippingRange();
    }
    d_->rootPosition = r;
    d_->hasRootPosition = true;
  }
  updateSkeletonGeometry();
}

void SceneView::updateSkeletonGeometry() {
  const std::size_t n = d_->skeleton.size();
  auto points = vtkSmartPointer<vtkPoints>::New();
  auto lines = vtkSmartPointer<vtkCellArray>::New();
  for (std::size_t j = 0; j < n; ++j) {
    const Eigen::Vector3d c = d_->global[j] * d_->skeleton.joints[j].center;
    points->InsertNextPoint(c.data());
    const int p = d_->skeleton.joints[j].parent;
    if (p >= 0) {
      const vtkIdType line[2] = {vtkIdType(p), vtkIdType(j)};
      lines->InsertNextCell(2, line);
    }
  }
  d_->joints->SetPoints(points);
  d_->bones->SetPoints(points);
  d_->bones->SetLines(lines);
  d_->joints->Modified();
  d_->bones->Modified();
  if (selected_ >= 0 && std::size_t(selected_) < n) {
    const Eigen::Isometry3d& G = d_->global[std::size_t(selected_)];
    const Eigen::Vector3d c = G * d_->skeleton.joints[std::size_t(selected_)].center;
    d_->selectedActor->SetPosition(c.x(), c.y(), c.z());
    d_->selectedActor->SetScale(d_->scale * 1.6);
    auto m = vtkSmartPointer<vtkMatrix4x4>::New();
    const double r = 4.0 * d_->scale;
    for (int i = 0; i < 3; ++i) {
      for (int k = 0; k < 3; ++k) m->SetElement(i, k, G.rotation()(i, k) * r);
      m->SetElement(i, 3, c[i]);
    }
    for (auto& ring : d_->rings) {
      ring->SetUserMatrix(m);
      ring->VisibilityOn();
    }
    d_->selectedActor->VisibilityOn();
  } else {
    d_->selectedActor->VisibilityOff();
    for (auto& ring : d_->rings) ring->VisibilityOff();
  }
}

void SceneView::setGhost(vtkPolyData* surfaces) {
  if (!surfaces) {
    d_->ghostActor->VisibilityOff();
    return;
  }
  d_->ghost->DeepCopy(surfaces);
  d_->ghostActor->VisibilityOn();
}

void SceneView::render() { renderWindow()->Render(); }

void SceneView::setSelectedJoint(int joint) {
  selected_ = (joint >= 0 && std::size_t(joint) < d_->skeleton.size()) ? joint : -1;
  updateSkeletonGeometry();
  render();
}

int SceneView::jointOfLabel(int label) const {
  if (label < 0 || std::size_t(label) >= d_->jointOfLabel.size()) return -1;
  return d_->jointOfLabel[std::size_t(label)];
}

int SceneView::pickJoint(int x, int y) {
  if (!d_->picker->Pick(x, y, 0, d_->renderer)) {
    d_->caption->SetInput("");
    return -1;
  }
  const vtkIdType cell = d_->picker->GetCellId();
  vtkDataSet* picked = d_->picker->GetDataSet();
  vtkDataArray* labels = picked ? picked->GetCellData()->GetArray(repose::arrays::kLabel) : nullptr;
  if (cell < 0 || !labels || cell >= labels->GetNumberOfTuples()) return -1;
  const int label = int(labels->GetTuple1(cell));
  const int joint = jointOfLabel(label);
  const LabelInfo* info = d_->table.find(label);
  QString caption = QString("%1 (label %2)").arg(info ? QString::fromStdString(info->name) : QString("label %1").arg(label)).arg(label);
  if (joint >= 0) caption += ", joint " + QString::fromStdString(d_->skeleton.joints[std::size_t(joint)].name);
  d_->caption->SetInput(caption.toUtf8().constData());
  return joint;
}

QString SceneView::pickedCaption() const {
  const char* text = d_->caption->GetInput();
  return text ? QString::fromUtf8(text) : QString();
}

vtkPolyData* SceneView::interactiveSurface(int which) const {
  if (!d_->hasLod) return nullptr;
  return which == 0 ? d_->skinLod.data.Get() : d_->tissueLod.data.Get();
}

Eigen::Quaterniond SceneView::dragRotation(double dx, double dy) const {
  vtkCamera* camera = d_->renderer->GetActiveCamera();
  double dop[3], up[3];
  camera->GetDirectionOfProjection(dop);
  camera->GetViewUp(up);
  const Eigen::Vector3d d(dop[0], dop[1], dop[2]);
  Eigen::Vector3d u(up[0], up[1], up[2]);
  u = (u - u.dot(d) * d).normalized();
  const Eigen::Vector3d right = d.cross(u);
  const Eigen::Vector3d motion = dx * right + dy * u;
  const double pixels = motion.norm();
  if (pixels == 0) return Eigen::Quaterniond::Identity();
  // The bone's front (towards the viewer) follows the mouse: axis = motion x view direction.
  const Eigen::Vector3d axis = motion.cross(d).normalized();
  return Eigen::Quaterniond(Eigen::AngleAxisd(pixels * 0.5 * M_PI / 180.0, axis));
}

void SceneView::setSkinOpacity(double opacity) {
  d_->skinActor->GetProperty()->SetOpacity(opacity);
  d_->skinVisible = opacity > 0;
  setInteractive(interactive_);
}

void SceneView::setSkeletonVisible(bool visible) {
  d_->jointActor->SetVisibility(visible);
  d_->boneActor->SetVisibility(visible);
}

void SceneView::resetCamera() {
  vtkCamera* camera = d_->renderer->GetActiveCamera();
  // Anterior view (LPS: the patient faces -y), head up.
  camera->SetFocalPoint(0, 0, 0);
  camera->SetPosition(0, -1, 0);
  camera->SetViewUp(0, 0, 1);
  d_->renderer->ResetCamera();
  d_->renderer->ResetCameraClippingRange();
}

void SceneView::saveScreenshot(const std::string& path) {
  render();
  auto grab = vtkSmartPointer<vtkWindowToImageFilter>::New();
  grab->SetInput(renderWindow());
  grab->ReadFrontBufferOff();
  grab->Update();
  auto writer = vtkSmartPointer<vtkPNGWriter>::New();
  writer->SetFileName(path.c_str());
  writer->SetInputConnection(grab->GetOutputPort());
  writer->Write();
  if (writer->GetErrorCode() != 0) throw std::runtime_error(path + ": cannot write the screenshot");
}

}  // namespace repose
