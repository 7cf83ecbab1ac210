#include "vtkReposeBodyMesher.h"

#include "vtkCellArray.h"
#include "vtkCellData.h"
#include "vtkCellType.h"
#include "vtkDataArray.h"
#include "vtkIdTypeArray.h"
#include "vtkImageData.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkIntArray.h"
#include "vtkMatrix3x3.h"
#include "vtkNew.h"
#include "vtkObjectFactory.h"
#include "vtkPointData.h"
#include "vtkPoints.h"
#include "vtkPolyData.h"
#include "vtkReposeSurfaceExtractor.h"
#include "ReposeImageConversion.h"
#include "ReposeMeshConversion.h"
#include "vtkSmartPointer.h"
#include "vtkUnsignedCharArray.h"
#include "vtkUnstructuredGrid.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <stdexcept>
#include <sstream>

#include "array_names.h"
#include "body_meshing.h"
#include "image_grid.h"
#include "skeleton.h"

vtkStandardNewMacro(vtkReposeBodyMesher);

namespace
{
using Clock = std::chrono::steady_clock;
double SecondsSince(Clock::time_point t)
{
  return std::chrono::duration<double>(Clock::now() - t).count();
}


// Triangle surface -> core arrays; false when a cell is not a triangle.
bool ToTriangles(vtkPolyData* surface, repose::Points& V, repose::Triangles& F)
{
  V = repose_vtk::ToPoints(surface->GetPoints());
  vtkCellArray* polys = surface->GetPolys();
  F.resize(polys->GetNumberOfCells(), 3);
  vtkIdType row = 0;
  vtkIdType npts;
  const vtkIdType* pts;
  for (polys->InitTraversal(); polys->GetNextCell(npts, pts); ++row)
  {
    if (npts != 3)
    {
      return false;
    }
    F.row(row) << int(pts[0]), int(pts[1]), int(pts[2]);
  }
  return surface->GetNumberOfCells() == polys->GetNumberOfCells();
}

// Core mesh -> the filter's output: double points, tets, "FixedBone" per node, "Label" per tet.
void ToTetGrid(const repose::TetMesh& mesh, vtkUnstructuredGrid* output)
{
  const vtkIdType nv = mesh.nodes.rows(), nt = mesh.tets.rows();
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(nv);
  for (vtkIdType v = 0; v < nv; ++v)
  {
    points->SetPoint(v, mesh.nodes(v, 0), mesh.nodes(v, 1), mesh.nodes(v, 2));
  }
  vtkNew<vtkIdTypeArray> offsets, connectivity;
  offsets->SetNumberOfValues(nt + 1);
  connectivity->SetNumberOfValues(4 * nt);
  for (vtkIdType c = 0; c <= nt; ++c)
  {
    offsets->SetValue(c, 4 * c);
  }
  for (vtkIdType c = 0; c < nt; ++c)
  {
    for (int k = 0; k < 4; ++k)
    {
      connectivity->SetValue(4 * c + k, mesh.tets(c, k));
    }
  }
  vtkNew<vtkCellArray> cells;
  cells->SetData(offsets, connectivity);
  output->SetPoints(points);
  output->SetCells(VTK_TETRA, cells);

  vtkNew<vtkIntArray> fixedBone;
  fixedBone->SetName(repose::arrays::kFixedBone);
  fixedBone->SetNumberOfValues(nv);
  std::copy(mesh.fixedBone.begin(), mesh.fixedBone.end(), fixedBone->GetPointer(0));
  output->GetPointData()->AddArray(fixedBone);
  vtkNew<vtkIntArray> label;
  label->SetName(repose::arrays::kLabel);
  label->SetNumberOfValues(nt);
  std::copy(mesh.tetLabel.begin(), mesh.tetLabel.end(), label->GetPointer(0));
  output->GetCellData()->AddArray(label);
}
}

vtkReposeBodyMesher::vtkReposeBodyMesher()
{
  this->SetNumberOfInputPorts(2);
}

int vtkReposeBodyMesher::FillInputPortInformation(int port, vtkInformation* info)
{
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkImageData");
  if (port == 1)
  {
    info->Set(vtkAlgorithm::INPUT_IS_OPTIONAL(), 1);
  }
  return 1;
}

void vtkReposeBodyMesher::SetIntensityData(vtkImageData* image)
{
  this->SetInputData(1, image);
}

struct vtkReposeBodyMesher::Steps
{
  static void ResetFigures(vtkReposeBodyMesher* self)
  {
    self->NumberOfNodes = self->NumberOfTets = self->NumberOfSurfaceTriangles = 0;
    self->NumberOfSeedPoints = self->NumberOfFixedNodes = self->NumberOfFreedContactNodes = 0;
    self->NumberOfContactVoxelsCut = 0;
    self->MeshingSpacingUsed = 0;
    self->ContactReport.clear();
    self->TotalSeconds = self->TetGenSeconds = 0;
    self->Report.clear();
  }

  static void CopyFigures(vtkReposeBodyMesher* self, const repose::BodyMeshing& meshed)
  {
    self->MeshingSpacingUsed = meshed.meshingSpacingMm;
    self->NumberOfContactVoxelsCut = static_cast<vtkIdType>(meshed.contactVoxelsCut);
    self->ContactReport = meshed.contactReport;
    self->NumberOfSeedPoints = static_cast<vtkIdType>(meshed.seedPoints);
    self->NumberOfSurfaceTriangles = static_cast<vtkIdType>(meshed.surfaceTriangles);
    self->NumberOfFixedNodes = static_cast<vtkIdType>(meshed.fixedNodes);
    self->NumberOfFreedContactNodes = static_cast<vtkIdType>(meshed.freedContactNodes);
    self->TetGenSeconds = meshed.tetgenSeconds;
    self->NumberOfNodes = meshed.mesh.nodes.rows();
    self->NumberOfTets = meshed.mesh.tets.rows();
  }

  static repose::BodyMeshingOptions Options(const vtkReposeBodyMesher* self)
  {
    repose::BodyMeshingOptions options;
    options.mask.body.bodyThreshold = self->BodyThreshold;
    options.mask.meshSpacingMm = self->MeshingSpacing;
    options.mask.maxTets = static_cast<double>(self->MaxTets);
    options.mask.skinLabels = self->SkinLabels;
    options.mask.peelOuterLayer = self->PeelOuterLayer;
    options.mask.separateContacts = self->SeparateContacts;
    options.tets.radiusEdgeRatio = self->RadiusEdgeRatio;
    options.tets.maxTetVolume = self->MaxTetVolume;
    options.surfaceReduction = self->SurfaceReduction;
    options.seedSurfaceStep = self->SeedSurfaceStep;
    options.seedInteriorStep = self->SeedInteriorStep;
    return options;
  }

  /// The surface is VTK's: contoured, smoothed and decimated by vtkReposeSurfaceExtractor.
  static auto SurfaceExtraction(int smoothing)
  {
    return [smoothing](const repose::MaskVolume& body, double reduction, repose::Points& V, repose::Triangles& F) {
      vtkNew<vtkPolyData> surface;
      if (!vtkReposeSurfaceExtractor::ContourMask(repose_vtk::ToImage(body), 0, smoothing, 0.1, reduction, surface))
      {
        return false;
      }
      if (!ToTriangles(surface, V, F))
      {
        throw std::invalid_argument("the body surface has non-triangle cells");
      }
      return true;
    };
  }
};

int vtkReposeBodyMesher::RequestData(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  const auto start = Clock::now();
  Steps::ResetFigures(this);
  vtkImageData* labelImage = vtkImageData::GetData(inputVector[0]);
  vtkImageData* intensityImage =
    inputVector[1]->GetNumberOfInformationObjects() > 0 ? vtkImageData::GetData(inputVector[1]) : nullptr;
  vtkUnstructuredGrid* output = vtkUnstructuredGrid::GetData(outputVector);
  if (!labelImage || !labelImage->GetPointData()->GetScalars())
  {
    vtkErrorMacro("the label image (input 0) has no scalars");
    return 0;
  }
  if (this->SkeletonJSON.empty())
  {
    vtkErrorMacro("SkeletonJSON is empty: the bones (and so the fixed nodes) come from the skeleton");
    return 0;
  }
  std::ostringstream report;
  repose::BodyMeshing meshed;
  try
  {
    const auto t = Clock::now();
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
    const repose::Skeleton skeleton = repose::parseSkeletonJson(this->SkeletonJSON);
    report << "input: " << labels.grid.dims[0] << "x" << labels.grid.dims[1] << "x" << labels.grid.dims[2]
           << " voxels, spacing " << labels.grid.spacing.transpose() << " mm, " << skeleton.size()
           << " joints" << (intensityImage ? ", with intensity image" : "") << " (" << SecondsSince(t)
           << " s)\n";
    auto progress = [this](const std::string& text)
    {
      this->SetProgressText(text.c_str());
      this->UpdateProgress(0.3);
      this->SetProgressText(nullptr); // said once
    };
    repose::meshBody(labels, intensityImage ? &intensity : nullptr, skeleton, Steps::Options(this),
      Steps::SurfaceExtraction(this->SurfaceSmoothingIterations), progress, meshed);
    report << meshed.report;
    for (const std::string& warning : meshed.warnings)
    {
      vtkWarningMacro(<< warning);
    }
    Steps::CopyFigures(this, meshed);
    ToTetGrid(meshed.mesh, output);
    this->TotalSeconds = SecondsSince(start);
    report << "output: " << this->NumberOfNodes << " nodes, " << this->NumberOfTets << " tets; total "
           << this->TotalSeconds << " s\n";
    this->Report = report.str();
  }
  catch (const std::exception& e)
  {
    Steps::CopyFigures(this, meshed);
    this->Report = report.str() + meshed.report + "error: " + e.what() + "\n";
    vtkErrorMacro(<< e.what());
    return 0;
  }
  return 1;
}

void vtkReposeBodyMesher::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "SkeletonJSON: " << (this->SkeletonJSON.empty() ? "(empty)" : "(set)") << "\n";
  os << indent << "BodyThreshold: " << this->BodyThreshold << "\n";
  os << indent << "PeelOuterLayer: " << this->PeelOuterLayer << "\n";
  os << indent << "SeparateContacts: " << this->SeparateContacts << "\n";
  os << indent << "SkinLabels:";
  for (int label : this->SkinLabels)
  {
    os << " " << label;
  }
  os << "\n";
  os << indent << "MeshingSpacing: " << this->MeshingSpacing << "\n";
  os << indent << "MaxTets: " << this->MaxTets << "\n";
  os << indent << "MeshingSpacingUsed: " << this->MeshingSpacingUsed << "\n";
  os << indent << "RadiusEdgeRatio: " << this->RadiusEdgeRatio << "\n";
  os << indent << "MaxTetVolume: " << this->MaxTetVolume << "\n";
  os << indent << "SurfaceSmoothingIterations: " << this->SurfaceSmoothingIterations << "\n";
  os << indent << "SeedSurfaceStep: " << this->SeedSurfaceStep << "\n";
  os << indent << "SeedInteriorStep: " << this->SeedInteriorStep << "\n";
  os << indent << "NumberOfNodes: " << this->NumberOfNodes << "\n";
  os << indent << "NumberOfTets: " << this->NumberOfTets << "\n";
}
