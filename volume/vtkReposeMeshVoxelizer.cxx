#include "vtkReposeMeshVoxelizer.h"

#include "ReposeImageConversion.h"
#include "ReposeMeshConversion.h"

#include "vtkCellArray.h"
#include "vtkIdList.h"
#include "vtkImageData.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkIntArray.h"
#include "vtkObjectFactory.h"
#include "vtkPointData.h"
#include "vtkPoints.h"
#include "vtkPolyData.h"
#include "vtkStreamingDemandDrivenPipeline.h"

#include "label_table.h"
#include "mesh_voxelizer.h"
#include "array_names.h"

#include <algorithm>
#include <exception>
#include <stdexcept>
#include <vector>

vtkStandardNewMacro(vtkReposeMeshVoxelizer);

namespace
{

/// Points and polygons (fans of triangles) of a vtkPolyData as a core triangle soup.
void ToTriangles(vtkPolyData* mesh, repose::MeshVertices& V, repose::MeshTriangles& F)
{
  V = repose_vtk::ToPoints(mesh->GetPoints());
  F = repose_vtk::ToTriangleFans(mesh);
}

} // namespace

vtkReposeMeshVoxelizer::vtkReposeMeshVoxelizer()
{
  this->MaxMarrowRadius = repose::kMaxMarrowRadiusMm;
  this->SetNumberOfInputPorts(1);
  this->SetNumberOfOutputPorts(1);
}

vtkReposeMeshVoxelizer::~vtkReposeMeshVoxelizer() = default;

int vtkReposeMeshVoxelizer::FillInputPortInformation(int, vtkInformation* info)
{
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkPolyData");
  info->Set(vtkAlgorithm::INPUT_IS_REPEATABLE(), 1);
  return 1;
}

void vtkReposeMeshVoxelizer::SetPartName(int index, const char* name)
{
  this->PartNames[index] = name ? name : "";
  this->Modified();
}

const char* vtkReposeMeshVoxelizer::GetPartName(int index)
{
  auto it = this->PartNames.find(index);
  if (it != this->PartNames.end() && !it->second.empty())
  {
    return it->second.c_str();
  }
  this->NameBuffer = this->GetPartRole(index) == Skin ? "soft_tissue" : "bone_" + std::to_string(index);
  return this->NameBuffer.c_str();
}

void vtkReposeMeshVoxelizer::SetPartRole(int index, int role)
{
  this->PartRoles[index] = std::max(0, std::min(2, role));
  this->Modified();
}

int vtkReposeMeshVoxelizer::GetPartRole(int index)
{
  auto it = this->PartRoles.find(index);
  return it != this->PartRoles.end() ? it->second : (index == 0 ? Skin : Bone);
}

void vtkReposeMeshVoxelizer::SetPartSource(int index, const char* source)
{
  this->PartSources[index] = source ? source : "";
  this->Modified();
}

void vtkReposeMeshVoxelizer::ClearParts()
{
  this->PartNames.clear();
  this->PartRoles.clear();
  this->PartSources.clear();
  this->Modified();
}

void vtkReposeMeshVoxelizer::SetReferenceImage(vtkImageData* image)
{
  if (this->ReferenceImage != image)
  {
    this->ReferenceImage = image;
    this->Modified();
  }
}

vtkImageData* vtkReposeMeshVoxelizer::GetReferenceImage()
{
  return this->ReferenceImage;
}

int vtkReposeMeshVoxelizer::RequestInformation(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  // The lattice depends on the skin's bounds: the skin's data must be there already.
  const int n = inputVector[0]->GetNumberOfInformationObjects();
  int skin = -1;
  for (int i = 0; i < n; ++i)
  {
    if (this->GetPartRole(i) == Skin)
    {
      skin = i;
      break;
    }
  }
  repose::ImageGrid grid;
  try
  {
    if (this->ReferenceImage)
    {
      grid = repose_vtk::ToGrid(this->ReferenceImage);
    }
    else
    {
      if (skin < 0)
      {
        vtkErrorMacro("no input connection is the skin (SetPartRole(i, Skin))");
        return 0;
      }
      vtkPolyData* mesh = vtkPolyData::GetData(inputVector[0], skin);
      if (mesh && mesh->GetNumberOfPoints() == 0 && this->GetInputAlgorithm(0, skin))
      {
        this->GetInputAlgorithm(0, skin)->Update();
        mesh = vtkPolyData::GetData(inputVector[0], skin);
      }
      if (!mesh || mesh->GetNumberOfPoints() == 0)
      {
        vtkErrorMacro("the skin surface (input " << skin << ") has no points");
        return 0;
      }
      repose::MeshVertices V;
      repose::MeshTriangles F;
      ToTriangles(mesh, V, F);
      try
      {
        grid = repose::gridFittingPoints(
          V, this->VoxelSize, this->PaddingVoxels, static_cast<std::size_t>(this->MaxVoxels));
      }
      catch (const std::invalid_argument& e)
      {
        // Named as the core names it in RequestData: the skin's source, else its label name.
        auto source = this->PartSources.find(skin);
        const std::string where =
          source != this->PartSources.end() && !source->second.empty() ? source->second : this->GetPartName(skin);
        throw std::invalid_argument(where + ": " + e.what());
      }
    }
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro(<< e.what());
    return 0;
  }
  repose_vtk::SetOutputGeometry(grid, outputVector->GetInformationObject(0), VTK_INT);
  return 1;
}

int vtkReposeMeshVoxelizer::RequestUpdateExtent(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector*)
{
  // Whole surfaces, whatever part of the image is asked for.
  for (int i = 0; i < inputVector[0]->GetNumberOfInformationObjects(); ++i)
  {
    vtkInformation* inInfo = inputVector[0]->GetInformationObject(i);
    inInfo->Set(vtkStreamingDemandDrivenPipeline::UPDATE_PIECE_NUMBER(), 0);
    inInfo->Set(vtkStreamingDemandDrivenPipeline::UPDATE_NUMBER_OF_PIECES(), 1);
    inInfo->Set(vtkStreamingDemandDrivenPipeline::UPDATE_NUMBER_OF_GHOST_LEVELS(), 0);
  }
  return 1;
}

int vtkReposeMeshVoxelizer::RequestData(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  this->LabelTableTSV.clear();
  this->Report.clear();
  this->NumberOfWarnings = 0;
  vtkImageData* output = vtkImageData::GetData(outputVector);
  const int n = inputVector[0]->GetNumberOfInformationObjects();
  if (!output || n == 0)
  {
    vtkErrorMacro("no surface on input 0");
    return 0;
  }
  try
  {
    std::vector<repose::VoxelizePart> parts(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i)
    {
      repose::VoxelizePart& p = parts[static_cast<std::size_t>(i)];
      p.name = this->GetPartName(i);
      auto source = this->PartSources.find(i);
      p.source = source != this->PartSources.end() ? source->second : std::string();
      const int role = this->GetPartRole(i);
      p.role = role == Skin ? repose::VoxelizeRole::Skin
                            : (role == Tissue ? repose::VoxelizeRole::Tissue : repose::VoxelizeRole::Bone);
      vtkPolyData* mesh = vtkPolyData::GetData(inputVector[0], i);
      if (!mesh || mesh->GetNumberOfPolys() == 0)
      {
        throw std::invalid_argument((p.source.empty() ? p.name : p.source) + ": the surface has no polygons");
      }
      ToTriangles(mesh, p.V, p.F);
    }
    repose::LabelVoxelizeOptions options;
    options.voxelMm = this->VoxelSize;
    options.padVoxels = this->PaddingVoxels;
    options.maxVoxels = static_cast<std::size_t>(this->MaxVoxels);
    options.maxMarrowRadiusMm = this->MaxMarrowRadius;
    options.hollowBones = this->HollowBones;
    repose::ImageGrid grid;
    if (this->ReferenceImage)
    {
      grid = repose_vtk::ToGrid(this->ReferenceImage);
    }
    const repose::LabelVoxelization result = repose::voxelizeLabels(parts, grid, options);

    const repose::ImageGrid& g = result.labels.grid;
    output->SetExtent(0, g.dims[0] - 1, 0, g.dims[1] - 1, 0, g.dims[2] - 1);
    output->SetOrigin(g.origin.data());
    output->SetSpacing(g.spacing.data());
    double d[9];
    for (int r = 0; r < 3; ++r)
    {
      for (int c = 0; c < 3; ++c)
      {
        d[3 * r + c] = g.direction(r, c);
      }
    }
    output->SetDirectionMatrix(d);
    vtkNew<vtkIntArray> values;
    values->SetName(repose::arrays::kLabels);
    values->SetNumberOfTuples(static_cast<vtkIdType>(result.labels.data.size()));
    std::copy(result.labels.data.begin(), result.labels.data.end(), values->GetPointer(0));
    output->GetPointData()->SetScalars(values);

    this->LabelTableTSV = repose::labelTableToTsv(result.table);
    this->Report = result.text();
    this->NumberOfWarnings = static_cast<int>(result.warnings.size());
    this->Seconds = result.seconds;
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro(<< e.what());
    return 0;
  }
  return 1;
}

void vtkReposeMeshVoxelizer::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "VoxelSize: " << this->VoxelSize << "\n";
  os << indent << "PaddingVoxels: " << this->PaddingVoxels << "\n";
  os << indent << "MaxVoxels: " << this->MaxVoxels << "\n";
  os << indent << "MaxMarrowRadius: " << this->MaxMarrowRadius << "\n";
  os << indent << "HollowBones: " << this->HollowBones << "\n";
  os << indent << "ReferenceImage: " << this->ReferenceImage.GetPointer() << "\n";
  os << indent << "Parts: " << this->PartNames.size() << " named\n";
}
