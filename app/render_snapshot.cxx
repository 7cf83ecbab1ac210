#include "render_snapshot.h"
#include "checked_write.h"
#include "array_names.h"

#include <algorithm>
#include <stdexcept>

#include <vtkActor.h>
#include <vtkCamera.h>
#include <vtkCellData.h>
#include <vtkDataArray.h>
#include <vtkPNGWriter.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkPolyDataNormals.h>
#include <vtkProperty.h>
#include <vtkRenderWindow.h>
#include <vtkRenderer.h>
#include <vtkSmartPointer.h>
#include <vtkThreshold.h>
#include <vtkGeometryFilter.h>
#include <vtkWindowToImageFilter.h>
#include <vtkIdList.h>
#include <vtkCellArray.h>

namespace repose {
namespace {

/// Splits surfaces into bone and other triangles by their cell label.
void splitByLabel(vtkPolyData* surfaces, const std::vector<int>& boneLabels, vtkPolyData* bones, vtkPolyData* rest) {
  vtkDataArray* labels = surfaces->GetCellData()->GetArray(repose::arrays::kLabel);
  auto boneCells = vtkSmartPointer<vtkCellArray>::New();
  auto otherCells = vtkSmartPointer<vtkCellArray>::New();
  auto ids = vtkSmartPointer<vtkIdList>::New();
  for (vtkIdType c = 0; c < surfaces->GetNumberOfCells(); ++c) {
    const int label = labels ? static_cast<int>(labels->GetTuple1(c)) : 0;
    bool isBone = false;
    for (int b : boneLabels) isBone = isBone || b == label;
    surfaces->GetCellPoints(c, ids);
    (isBone ? boneCells : otherCells)->InsertNextCell(ids);
  }
  bones->SetPoints(surfaces->GetPoints());
  bones->SetPolys(boneCells);
  rest->SetPoints(surfaces->GetPoints());
  rest->SetPolys(otherCells);
}

void addSurfaces(vtkRenderer* renderer, vtkPolyData* surfaces, const std::vector<int>& boneLabels) {
  auto bones = vtkSmartPointer<vtkPolyData>::New();
  auto skin = vtkSmartPointer<vtkPolyData>::New();
  splitByLabel(surfaces, boneLabels, bones, skin);
  struct Part { vtkPolyData* data; double r, g, b, opacity; };
  for (const Part& part : {Part{bones, 0.95, 0.92, 0.82, 1.0}, Part{skin, 0.93, 0.70, 0.58, 0.35}}) {
    if (part.data->GetNumberOfCells() == 0) continue;
    auto normals = vtkSmartPointer<vtkPolyDataNormals>::New();
    normals->SetInputData(part.data);
    normals->SplittingOff();
    auto mapper = vtkSmartPointer<vtkPolyDataMapper>::New();
    mapper->SetInputConnection(normals->GetOutputPort());
    mapper->ScalarVisibilityOff();
    auto actor = vtkSmartPointer<vtkActor>::New();
    actor->SetMapper(mapper);
    actor->GetProperty()->SetColor(part.r, part.g, part.b);
    actor->GetProperty()->SetOpacity(part.opacity);
    actor->GetProperty()->SetSpecular(0.2);
    renderer->AddActor(actor);
  }
}

/// Places the camera looking at `bounds` from direction `from` (LPS: anterior is -y, left +x,
/// superior +z), head up.
void placeCamera(vtkRenderer* renderer, const double bounds[6], double fx, double fy, double fz) {
  vtkCamera* camera = renderer->GetActiveCamera();
  camera->SetFocalPoint(0, 0, 0);
  camera->SetPosition(fx, fy, fz);
  camera->SetViewUp(0, 0, 1);
  camera->SetViewAngle(25);
  renderer->ResetCamera(bounds);
}

}  // namespace

void renderSideBySide(vtkPolyData* left, vtkPolyData* right, const std::vector<int>& boneLabels,
                      const std::string& pngPath, int width, int height) {
  auto window = vtkSmartPointer<vtkRenderWindow>::New();
  window->SetOffScreenRendering(1);
  window->SetSize(width, height);
  window->SetMultiSamples(0);
  window->SetAlphaBitPlanes(1);
  double bounds[6], b[6];
  left->GetBounds(bounds);
  right->GetBounds(b);
  for (int a = 0; a < 3; ++a) {
    bounds[2 * a] = std::min(bounds[2 * a], b[2 * a]);
    bounds[2 * a + 1] = std::max(bounds[2 * a + 1], b[2 * a + 1]);
  }
  // Rest and posed from the front-right and above (one camera, same scale), then the posed body
  // from its left side, where flexion and extension read unambiguously.
  struct Panel { vtkPolyData* data; double x0, x1; };
  const Panel panels[3] = {{left, 0.0, 0.36}, {right, 0.36, 0.72}, {right, 0.72, 1.0}};
  vtkSmartPointer<vtkCamera> shared;
  for (int v = 0; v < 3; ++v) {
    auto renderer = vtkSmartPointer<vtkRenderer>::New();
    renderer->SetViewport(panels[v].x0, 0, panels[v].x1, 1);
    renderer->SetBackground(0.12, 0.13, 0.16);
    renderer->SetUseDepthPeeling(1);
    addSurfaces(renderer, panels[v].data, boneLabels);
    if (v == 0) {
      placeCamera(renderer, bounds, -0.5, -1, 0.45);
      shared = renderer->GetActiveCamera();
    } else if (v == 1) {
      renderer->SetActiveCamera(shared);
    } else {
      placeCamera(renderer, bounds, 1, 0, 0.1);
    }
    window->AddRenderer(renderer);
  }
  window->Render();
  auto grab = vtkSmartPointer<vtkWindowToImageFilter>::New();
  grab->SetInput(window);
  grab->ReadFrontBufferOff();
  grab->Update();
  auto writer = vtkSmartPointer<vtkPNGWriter>::New();
  writer->SetFileName(pngPath.c_str());
  writer->SetInputConnection(grab->GetOutputPort());
  writeChecked(writer.Get(), pngPath, kPngTail);
}

}  // namespace repose
