#include "ReposeMaskContouring.h"

#include "vtkDataArray.h"
#include "vtkDiscreteFlyingEdges3D.h"
#include "vtkFlyingEdges3D.h"
#include "vtkImageCast.h"
#include "vtkImageConstantPad.h"
#include "vtkImageData.h"
#include "vtkImageResize.h"
#include "vtkMatrix3x3.h"
#include "vtkMatrix4x4.h"
#include "vtkNew.h"
#include "vtkPointData.h"
#include "vtkPolyData.h"
#include "vtkQuadricDecimation.h"
#include "vtkTransform.h"
#include "vtkTransformPolyDataFilter.h"
#include "vtkUnsignedCharArray.h"
#include "vtkWindowedSincPolyDataFilter.h"

#include <algorithm>

namespace repose_vtk
{
vtkSmartPointer<vtkImageData> InIndexFrame(vtkImageData* mask)
{
  auto local = vtkSmartPointer<vtkImageData>::New();
  local->ShallowCopy(mask);
  local->SetOrigin(0, 0, 0);
  local->SetDirectionMatrix(1, 0, 0, 0, 1, 0, 0, 0, 1);
  return local;
}

vtkSmartPointer<vtkImageData> ResampledMask(vtkImageData* local, double meshingSpacing)
{
  const double* spacing = local->GetSpacing();
  if (!(meshingSpacing > 0 && meshingSpacing > 1.01 * std::min({ spacing[0], spacing[1], spacing[2] })))
  {
    return nullptr;
  }
  // Antialiased (sinc) resampling of the 0/1 mask as float; contoured at 0.5.
  vtkNew<vtkImageCast> toFloat;
  toFloat->SetInputData(local);
  toFloat->SetOutputScalarTypeToFloat();
  vtkNew<vtkImageResize> resize;
  resize->SetInputConnection(toFloat->GetOutputPort());
  resize->SetResizeMethodToOutputSpacing();
  resize->SetOutputSpacing(std::max(meshingSpacing, spacing[0]), std::max(meshingSpacing, spacing[1]),
    std::max(meshingSpacing, spacing[2]));
  resize->InterpolateOn();
  resize->Update();
  return resize->GetOutput();
}

namespace
{
/// Non-zero voxels as 1 so that any mask values work with the discrete contour.
vtkSmartPointer<vtkImageData> Binary(vtkImageData* image)
{
  auto binary = vtkSmartPointer<vtkImageData>::New();
  binary->CopyStructure(image);
  vtkDataArray* in = image->GetPointData()->GetScalars();
  vtkNew<vtkUnsignedCharArray> values;
  values->SetNumberOfTuples(in->GetNumberOfTuples());
  for (vtkIdType p = 0; p < in->GetNumberOfTuples(); ++p)
  {
    values->SetValue(p, in->GetComponent(p, 0) != 0 ? 1 : 0);
  }
  binary->GetPointData()->SetScalars(values);
  return binary;
}
}

vtkSmartPointer<vtkPolyData> ContourPadded(vtkImageData* volume, bool resampled)
{
  int ext[6];
  volume->GetExtent(ext);
  vtkNew<vtkImageConstantPad> pad;
  pad->SetInputData(volume);
  pad->SetConstant(0);
  pad->SetOutputWholeExtent(ext[0] - 1, ext[1] + 1, ext[2] - 1, ext[3] + 1, ext[4] - 1, ext[5] + 1);
  pad->Update();
  if (resampled)
  {
    vtkNew<vtkFlyingEdges3D> contour;
    contour->SetInputConnection(pad->GetOutputPort());
    contour->SetValue(0, 0.5);
    contour->ComputeNormalsOff();
    contour->ComputeGradientsOff();
    contour->ComputeScalarsOff();
    contour->Update();
    return contour->GetOutput();
  }
  vtkNew<vtkDiscreteFlyingEdges3D> contour;
  contour->SetInputData(Binary(pad->GetOutput()));
  contour->SetValue(0, 1);
  contour->ComputeNormalsOff();
  contour->ComputeGradientsOff();
  contour->ComputeScalarsOff();
  contour->Update();
  return contour->GetOutput();
}

vtkSmartPointer<vtkPolyData> SmoothedAndDecimated(
  vtkPolyData* given, int iterations, double passBand, double targetReduction)
{
  vtkSmartPointer<vtkPolyData> surface = given;
  if (iterations > 0)
  {
    vtkNew<vtkWindowedSincPolyDataFilter> smooth;
    smooth->SetInputData(surface);
    smooth->SetNumberOfIterations(iterations);
    smooth->SetPassBand(passBand);
    smooth->NormalizeCoordinatesOn();
    smooth->BoundarySmoothingOff();
    smooth->FeatureEdgeSmoothingOff();
    smooth->NonManifoldSmoothingOff();
    smooth->Update();
    surface = smooth->GetOutput();
  }
  if (targetReduction > 0)
  {
    vtkNew<vtkQuadricDecimation> decimate;
    decimate->SetInputData(surface);
    decimate->SetTargetReduction(targetReduction);
    decimate->VolumePreservationOn();
    decimate->Update();
    surface = decimate->GetOutput();
  }
  return surface;
}

vtkSmartPointer<vtkPolyData> ToPhysical(vtkPolyData* surface, vtkImageData* mask)
{
  vtkNew<vtkMatrix4x4> m;
  vtkMatrix3x3* d = mask->GetDirectionMatrix();
  const double* origin = mask->GetOrigin();
  for (int r = 0; r < 3; ++r)
  {
    for (int c = 0; c < 3; ++c)
    {
      m->SetElement(r, c, d->GetElement(r, c));
    }
    m->SetElement(r, 3, origin[r]);
  }
  vtkNew<vtkTransform> transform;
  transform->SetMatrix(m);
  vtkNew<vtkTransformPolyDataFilter> toPhysical;
  toPhysical->SetInputData(surface);
  toPhysical->SetTransform(transform);
  toPhysical->SetOutputPointsPrecision(vtkAlgorithm::DOUBLE_PRECISION);
  toPhysical->Update();
  return toPhysical->GetOutput();
}
}
