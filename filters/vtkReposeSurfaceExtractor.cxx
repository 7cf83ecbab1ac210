#include "vtkReposeSurfaceExtractor.h"

#include "ReposeImageConversion.h"

#include "ReposeMaskContouring.h"

#include "vtkAppendPolyData.h"
#include "vtkCellData.h"
#include "vtkImageData.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkIntArray.h"
#include "vtkNew.h"
#include "vtkObjectFactory.h"
#include "vtkPointData.h"
#include "vtkPolyData.h"
#include "vtkPolyDataNormals.h"
#include "vtkSmartPointer.h"

#include <exception>

#include "array_names.h"
#include "body_mask.h"
#include "bone_masks.h"
#include "image_grid.h"
#include "skeleton.h"

vtkStandardNewMacro(vtkReposeSurfaceExtractor);

namespace
{

void SetCellLabel(vtkPolyData* surface, int label)
{
  vtkNew<vtkIntArray> labels;
  labels->SetName(repose::arrays::kLabel);
  labels->SetNumberOfTuples(surface->GetNumberOfCells());
  labels->FillValue(label);
  surface->GetCellData()->AddArray(labels);
}

/// surface with outward point normals and the cell data Label.
vtkSmartPointer<vtkPolyData> Labelled(vtkPolyData* surface, int label)
{
  vtkNew<vtkPolyDataNormals> normals;
  normals->SetInputData(surface);
  normals->SplittingOff();
  normals->ConsistencyOn();
  normals->AutoOrientNormalsOn();
  normals->ComputePointNormalsOn();
  normals->ComputeCellNormalsOff();
  normals->Update();
  vtkSmartPointer<vtkPolyData> withNormals = normals->GetOutput();
  SetCellLabel(withNormals, label);
  return withNormals;
}
}

vtkReposeSurfaceExtractor::vtkReposeSurfaceExtractor()
{
  this->SetNumberOfInputPorts(2);
}

int vtkReposeSurfaceExtractor::FillInputPortInformation(int port, vtkInformation* info)
{
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkImageData");
  if (port == 1)
  {
    info->Set(vtkAlgorithm::INPUT_IS_OPTIONAL(), 1);
  }
  return 1;
}

void vtkReposeSurfaceExtractor::SetIntensityData(vtkImageData* image)
{
  this->SetInputData(1, image);
}

int vtkReposeSurfaceExtractor::ContourMask(vtkImageData* mask, double meshingSpacing,
  int smoothingIterations, double passBand, double targetReduction, vtkPolyData* output)
{
  if (!mask || !output || !mask->GetPointData()->GetScalars())
  {
    return 0;
  }
  const vtkSmartPointer<vtkImageData> local = repose_vtk::InIndexFrame(mask);
  const vtkSmartPointer<vtkImageData> resampled = repose_vtk::ResampledMask(local, meshingSpacing);
  vtkSmartPointer<vtkPolyData> surface =
    repose_vtk::ContourPadded(resampled ? resampled.Get() : local.Get(), resampled != nullptr);
  if (surface->GetNumberOfCells() == 0)
  {
    output->Initialize();
    return 0;
  }
  surface = repose_vtk::SmoothedAndDecimated(surface, smoothingIterations, passBand, targetReduction);
  output->ShallowCopy(repose_vtk::ToPhysical(surface, mask));
  return 1;
}

int vtkReposeSurfaceExtractor::RequestData(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  vtkImageData* labelImage = vtkImageData::GetData(inputVector[0]);
  vtkImageData* intensityImage =
    inputVector[1]->GetNumberOfInformationObjects() > 0 ? vtkImageData::GetData(inputVector[1]) : nullptr;
  vtkPolyData* output = vtkPolyData::GetData(outputVector);
  if (!labelImage || !labelImage->GetPointData()->GetScalars())
  {
    vtkErrorMacro("the label image (input 0) has no scalars");
    return 0;
  }
  try
  {
    repose::LabelVolume labels;
    if (!repose_vtk::ToVolume(labelImage, labels))
    {
      vtkErrorMacro("the label image must have one scalar component per voxel");
      return 0;
    }
    repose::IntensityVolume intensity;
    if (intensityImage && !repose_vtk::ToVolume(intensityImage, intensity))
    {
      vtkErrorMacro("the intensity image (input 1) must have one scalar component per voxel");
      return 0;
    }
    vtkNew<vtkAppendPolyData> append;
    int pieces = 0;
    auto addSurface = [&](vtkImageData* mask, int label) {
      vtkNew<vtkPolyData> surface;
      if (!ContourMask(mask, 0, this->SmoothingIterations, this->PassBand, this->TargetReduction, surface))
      {
        vtkWarningMacro("no surface for label " << label);
        return;
      }
      append->AddInputData(Labelled(surface, label));
      ++pieces;
    };
    if (this->ExtractSkin)
    {
      repose::BodyMaskOptions options;
      options.bodyThreshold = this->BodyThreshold;
      addSurface(repose_vtk::ToImage(repose::bodyMask(labels, intensityImage ? &intensity : nullptr, options)),
        SkinLabel);
    }
    if (this->ExtractBones)
    {
      if (this->SkeletonJSON.empty())
      {
        vtkErrorMacro("SkeletonJSON is empty: the bone labels come from the skeleton");
        return 0;
      }
      repose::forEachBoneMask(labels, repose::parseSkeletonJson(this->SkeletonJSON),
        [&](int label, const repose::MaskVolume* mask) {
          if (!mask)
          {
            vtkWarningMacro("bone label " << label << " does not occur in the label image");
            return;
          }
          addSurface(repose_vtk::ToImage(*mask), label);
        });
    }
    if (pieces == 0)
    {
      vtkErrorMacro("no surface was extracted");
      return 0;
    }
    append->Update();
    output->ShallowCopy(append->GetOutput());
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro(<< e.what());
    return 0;
  }
  return 1;
}

void vtkReposeSurfaceExtractor::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "SkeletonJSON: " << (this->SkeletonJSON.empty() ? "(empty)" : "(set)") << "\n";
  os << indent << "BodyThreshold: " << this->BodyThreshold << "\n";
  os << indent << "ExtractSkin: " << this->ExtractSkin << "\n";
  os << indent << "ExtractBones: " << this->ExtractBones << "\n";
  os << indent << "SmoothingIterations: " << this->SmoothingIterations << "\n";
  os << indent << "PassBand: " << this->PassBand << "\n";
  os << indent << "TargetReduction: " << this->TargetReduction << "\n";
}
