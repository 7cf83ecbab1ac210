#include "vtkReposeSurfaceExtractor.h"

#include "ReposeImageConversion.h"

#include "vtkAppendPolyData.h"
#include "vtkCellData.h"
#include "vtkDataArray.h"
#include "vtkDiscreteFlyingEdges3D.h"
#include "vtkFlyingEdges3D.h"
#include "vtkImageCast.h"
#include "vtkImageConstantPad.h"
#include "vtkImageData.h"
#include "vtkImageResize.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkIntArray.h"
#include "vtkMatrix3x3.h"
#include "vtkMatrix4x4.h"
#include "vtkNew.h"
#include "vtkObjectFactory.h"
#include "vtkPointData.h"
#include "vtkPolyData.h"
#include "vtkPolyDataNormals.h"
#include "vtkQuadricDecimation.h"
#include "vtkSmartPointer.h"
#include "vtkTransform.h"
#include "vtkTransformPolyDataFilter.h"
#include "vtkUnsignedCharArray.h"
#include "vtkWindowedSincPolyDataFilter.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <exception>
#include <limits>
#include <map>
#include <set>

#include "body_mask.h"
#include "image_grid.h"
#include "skeleton.h"
#include "array_names.h"
#include "label_boxes.h"

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
  // The same voxels in the axis-aligned index frame: point = spacing * ijk.
  vtkNew<vtkImageData> local;
  local->ShallowCopy(mask);
  local->SetOrigin(0, 0, 0);
  local->SetDirectionMatrix(1, 0, 0, 0, 1, 0, 0, 0, 1);

  vtkSmartPointer<vtkImageData> volume = local;
  bool resampled = false;
  const double* spacing = mask->GetSpacing();
  if (meshingSpacing > 0 &&
    meshingSpacing > 1.01 * std::min({ spacing[0], spacing[1], spacing[2] }))
  {
    // Antialiased (sinc) resampling of the 0/1 mask as float; contoured at 0.5 below.
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
    volume = resize->GetOutput();
    resampled = true;
  }

  // A background layer all around so the surface closes where the mask touches the image border.
  int ext[6];
  volume->GetExtent(ext);
  vtkNew<vtkImageConstantPad> pad;
  pad->SetInputData(volume);
  pad->SetConstant(0);
  pad->SetOutputWholeExtent(ext[0] - 1, ext[1] + 1, ext[2] - 1, ext[3] + 1, ext[4] - 1, ext[5] + 1);
  pad->Update();

  vtkSmartPointer<vtkPolyData> surface;
  if (resampled)
  {
    vtkNew<vtkFlyingEdges3D> contour;
    contour->SetInputConnection(pad->GetOutputPort());
    contour->SetValue(0, 0.5);
    contour->ComputeNormalsOff();
    contour->ComputeGradientsOff();
    contour->ComputeScalarsOff();
    contour->Update();
    surface = contour->GetOutput();
  }
  else
  {
    // Non-zero voxels as 1 so that any mask values work with the discrete contour.
    vtkNew<vtkImageData> binary;
    binary->CopyStructure(pad->GetOutput());
    vtkDataArray* in = pad->GetOutput()->GetPointData()->GetScalars();
    vtkNew<vtkUnsignedCharArray> values;
    values->SetNumberOfTuples(in->GetNumberOfTuples());
    for (vtkIdType p = 0; p < in->GetNumberOfTuples(); ++p)
    {
      values->SetValue(p, in->GetComponent(p, 0) != 0 ? 1 : 0);
    }
    binary->GetPointData()->SetScalars(values);
    vtkNew<vtkDiscreteFlyingEdges3D> contour;
    contour->SetInputData(binary);
    contour->SetValue(0, 1);
    contour->ComputeNormalsOff();
    contour->ComputeGradientsOff();
    contour->ComputeScalarsOff();
    contour->Update();
    surface = contour->GetOutput();
  }
  if (surface->GetNumberOfCells() == 0)
  {
    output->Initialize();
    return 0;
  }

  if (smoothingIterations > 0)
  {
    vtkNew<vtkWindowedSincPolyDataFilter> smooth;
    smooth->SetInputData(surface);
    smooth->SetNumberOfIterations(smoothingIterations);
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

  // Index frame -> physical: x = origin + direction * local.
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
  output->ShallowCopy(toPhysical->GetOutput());
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
      vtkNew<vtkPolyDataNormals> normals;
      normals->SetInputData(surface);
      normals->SplittingOff();
      normals->ConsistencyOn();
      normals->AutoOrientNormalsOn();
      normals->ComputePointNormalsOn();
      normals->ComputeCellNormalsOff();
      normals->Update();
      vtkPolyData* withNormals = normals->GetOutput();
      SetCellLabel(withNormals, label);
      append->AddInputData(withNormals);
      ++pieces;
    };

    if (this->ExtractSkin)
    {
      repose::BodyMaskOptions options;
      options.bodyThreshold = this->BodyThreshold;
      const repose::MaskVolume body =
        repose::bodyMask(labels, intensityImage ? &intensity : nullptr, options);
      addSurface(repose_vtk::ToImage(body), SkinLabel);
    }
    if (this->ExtractBones)
    {
      if (this->SkeletonJSON.empty())
      {
        vtkErrorMacro("SkeletonJSON is empty: the bone labels come from the skeleton");
        return 0;
      }
      const repose::Skeleton skeleton = repose::parseSkeletonJson(this->SkeletonJSON);
      // Each bone contoured on its own crop (labels above kMaxBoxedLabel: on the whole grid).
      const std::vector<Eigen::AlignedBox3i> boxes = repose::labelBoxes(labels);
      const Eigen::AlignedBox3i wholeGrid(Eigen::Vector3i::Zero(),
        Eigen::Vector3i(labels.grid.dims[0] - 1, labels.grid.dims[1] - 1, labels.grid.dims[2] - 1));
      std::set<int> boneLabels;
      for (const auto& joint : skeleton.joints)
      {
        boneLabels.insert(joint.labels.begin(), joint.labels.end());
      }
      for (const int label : boneLabels)
      {
        const Eigen::AlignedBox3i box = boxes.empty() ? wholeGrid
          : (label > 0 && static_cast<std::size_t>(label) < boxes.size() ? boxes[static_cast<std::size_t>(label)]
                                                                         : Eigen::AlignedBox3i());
        const repose::MaskVolume crop = repose::labelCrop(labels, label, box);
        if (std::find(crop.data.begin(), crop.data.end(), 1) == crop.data.end())
        {
          vtkWarningMacro("bone label " << label << " does not occur in the label image");
          continue;
        }
        addSurface(repose_vtk::ToImage(crop), label);
      }
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
