#include "vtkReposePosedVolume.h"

#include "vtkCellArray.h"
#include "vtkCellType.h"
#include "vtkDataArray.h"
#include "vtkFieldData.h"
#include "vtkFloatArray.h"
#include "vtkImageData.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkIntArray.h"
#include "vtkMatrix3x3.h"
#include "vtkObjectFactory.h"
#include "vtkPointData.h"
#include "vtkPoints.h"
#include "vtkStreamingDemandDrivenPipeline.h"
#include "vtkUnstructuredGrid.h"

#include "resample_pull.h"
#include "rigid_bone_overlay.h"
#include "tet_boundary.h"
#include "ReposeMeshConversion.h"
#include "array_names.h"

#include <algorithm>
#include <array>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

vtkStandardNewMacro(vtkReposePosedVolume);

struct vtkReposePosedVolume::Internals
{
  // Boundary of the rest mesh's tets, and what it was computed from.
  std::unique_ptr<repose::TetBoundary> Boundary;
  vtkCellArray* Cells = nullptr;
  vtkMTimeType CellsTime = 0;
  vtkIdType NumberOfCells = -1;
  // Rest-grid voxels inside the rest mesh, and the rest points and grid it was computed for.
  std::unique_ptr<repose::MaskVolume> Coverage;
  std::unique_ptr<repose::MaskVolume> Distance;  // restMeshDistance(Coverage)
  vtkMTimeType CoverageTime = 0;
  // Rest tets (same key as the boundary, plus the cell types).
  repose::Tets Tets;
  vtkCellArray* TetsCells = nullptr;
  vtkMTimeType TetsTime = 0;
  vtkIdType TetsCount = -1;
  // Rest nodes, and the points they were converted from.
  repose::Points RestNodes;
  vtkPoints* RestPoints = nullptr;
  vtkMTimeType RestPointsTime = 0;
  // Rest scalars as core volumes (one of the two), and the array they were converted from.
  repose::LabelVolume Labels;
  repose::IntensityVolume Values;
  vtkDataArray* Scalars = nullptr;
  vtkMTimeType ScalarsTime = 0;
  int ScalarsKind = -1;
  // Rest label boxes for the rigid-bone overlay (follow Labels; unset until first needed).
  std::unique_ptr<std::vector<Eigen::AlignedBox3i>> LabelBoxes;
  std::array<int, 3> LabelBoxesDims = { { -1, -1, -1 } };
  // The last label output array, for reuse by the next pose.
  vtkSmartPointer<vtkIntArray> LastLabels;
  // Fixed bone per rest node, and the array it was converted from.
  std::vector<int> FixedBone;
  vtkDataArray* FixedArray = nullptr;
  vtkMTimeType FixedTime = 0;
};

namespace
{
template <class S, class D>
void CopyCast(const S* src, std::size_t n, D* dst)
{
  for (std::size_t i = 0; i < n; ++i)
  {
    dst[i] = static_cast<D>(src[i]);
  }
}

template <class D>
void CopyScalars(vtkDataArray* array, std::vector<D>& dst)
{
  const std::size_t n = static_cast<std::size_t>(array->GetNumberOfTuples());
  dst.resize(n);
  switch (array->GetDataType())
  {
    vtkTemplateMacro(CopyCast(static_cast<const VTK_TT*>(array->GetVoidPointer(0)), n, dst.data()));
    default:
      throw std::invalid_argument(std::string("unsupported image scalar type ") + array->GetDataTypeAsString());
  }
}

// Rest grid from pipeline information (voxel of extent start is the grid's first voxel).
repose::ImageGrid GridFromInfo(const int ext[6], const double origin[3], const double spacing[3],
  const double direction[9])
{
  repose::ImageGrid g;
  for (int a = 0; a < 3; ++a)
  {
    g.dims[a] = ext[2 * a + 1] - ext[2 * a] + 1;
    g.spacing[a] = spacing[a];
    g.origin[a] = origin[a];
    for (int b = 0; b < 3; ++b)
    {
      g.direction(a, b) = direction[3 * a + b];
    }
  }
  g.origin = g.indexToPhysical(Eigen::Vector3d(ext[0], ext[2], ext[4]));
  return g;
}

// The requested sub-extent clamped to the full extent; throws if that is empty.
std::array<int, 6> ClampedSubExtent(const int full[6], const int sub[6])
{
  std::array<int, 6> e;
  for (int a = 0; a < 3; ++a)
  {
    e[2 * a] = std::max(full[2 * a], sub[2 * a]);
    e[2 * a + 1] = std::min(full[2 * a + 1], sub[2 * a + 1]);
    if (e[2 * a] > e[2 * a + 1])
    {
      throw std::invalid_argument("output sub-extent [" + std::to_string(sub[0]) + " " + std::to_string(sub[1]) +
        " " + std::to_string(sub[2]) + " " + std::to_string(sub[3]) + " " + std::to_string(sub[4]) + " " +
        std::to_string(sub[5]) + "] does not overlap the posed grid's extent [0 " + std::to_string(full[1]) +
        " 0 " + std::to_string(full[3]) + " 0 " + std::to_string(full[5]) + "]");
    }
  }
  return e;
}

// The posed grid's bound: the body's margin covers the extrapolation, so cropping never cuts it.
repose::PosedGridOptions GridOptions(const repose::ImageGrid& rest, int padding, double extrapolation, double maxVoxels)
{
  repose::PosedGridOptions options;
  options.paddingVoxels = padding;
  options.bodyPaddingVoxels = std::max(padding, repose::extrapolationReachVoxels(rest, extrapolation));
  options.maxVoxels = maxVoxels;
  return options;
}

void GridToArrays(const repose::ImageGrid& g, int ext[6], double origin[3], double spacing[3], double direction[9])
{
  for (int a = 0; a < 3; ++a)
  {
    ext[2 * a] = 0;
    ext[2 * a + 1] = g.dims[a] - 1;
    origin[a] = g.origin[a];
    spacing[a] = g.spacing[a];
    for (int b = 0; b < 3; ++b)
    {
      direction[3 * a + b] = g.direction(a, b);
    }
  }
}
}

vtkReposePosedVolume::vtkReposePosedVolume()
  : Internal(new Internals)
{
  this->SetNumberOfInputPorts(3);
  this->SetNumberOfOutputPorts(1);
}

vtkReposePosedVolume::~vtkReposePosedVolume()
{
  delete this->Internal;
}

int vtkReposePosedVolume::FillInputPortInformation(int port, vtkInformation* info)
{
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), port == 0 ? "vtkImageData" : "vtkUnstructuredGrid");
  return 1;
}

int vtkReposePosedVolume::RequestInformation(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  // The output lattice depends on the posed node positions, so the posed mesh is brought up to date
  // here (unstructured data: no extents to negotiate).
  int algPort = 0;
  vtkAlgorithm* posedAlg = this->GetInputAlgorithm(2, 0, algPort);
  if (!posedAlg)
  {
    vtkErrorMacro(<< "posed tet mesh (input 2) is not set");
    return 0;
  }
  posedAlg->Update(algPort);
  vtkInformation* imageInfo = inputVector[0]->GetInformationObject(0);
  vtkUnstructuredGrid* posed = vtkUnstructuredGrid::GetData(inputVector[2]);
  if (!imageInfo || !posed)
  {
    vtkErrorMacro(<< "rest image (input 0) and posed tet mesh (input 2) are required");
    return 0;
  }
  int ext[6];
  double origin[3] = { 0, 0, 0 }, spacing[3] = { 1, 1, 1 };
  double direction[9] = { 1, 0, 0, 0, 1, 0, 0, 0, 1 };
  imageInfo->Get(vtkStreamingDemandDrivenPipeline::WHOLE_EXTENT(), ext);
  if (imageInfo->Has(vtkDataObject::ORIGIN()))
  {
    imageInfo->Get(vtkDataObject::ORIGIN(), origin);
  }
  if (imageInfo->Has(vtkDataObject::SPACING()))
  {
    imageInfo->Get(vtkDataObject::SPACING(), spacing);
  }
  if (imageInfo->Has(vtkDataObject::DIRECTION()))
  {
    imageInfo->Get(vtkDataObject::DIRECTION(), direction);
  }
  try
  {
    const repose::ImageGrid rest = GridFromInfo(ext, origin, spacing, direction);
    const repose::ImageGrid out =
      repose::posedOutputGrid(rest, repose_vtk::ToPoints(posed->GetPoints()),
        GridOptions(rest, this->PaddingVoxels, this->ExtrapolationDistance, this->MaxVoxels));
    GridToArrays(out, ext, origin, spacing, direction);
    std::copy(ext, ext + 6, this->FullOutputExtent);
    if (this->RestrictToSubExtent)
    {
      const std::array<int, 6> sub = ClampedSubExtent(ext, this->OutputSubExtent);
      std::copy(sub.begin(), sub.end(), ext);
    }
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro(<< e.what());
    return 0;
  }
  vtkInformation* outInfo = outputVector->GetInformationObject(0);
  outInfo->Set(vtkStreamingDemandDrivenPipeline::WHOLE_EXTENT(), ext, 6);
  outInfo->Set(vtkDataObject::ORIGIN(), origin, 3);
  outInfo->Set(vtkDataObject::SPACING(), spacing, 3);
  outInfo->Set(vtkDataObject::DIRECTION(), direction, 9);
  vtkDataObject::SetPointDataActiveScalarInfo(
    outInfo, this->Interpolation == Nearest ? VTK_INT : VTK_FLOAT, 1);
  return 1;
}

int vtkReposePosedVolume::RequestUpdateExtent(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector*)
{
  // The whole rest image is needed whatever part of the output is requested.
  vtkInformation* imageInfo = inputVector[0]->GetInformationObject(0);
  int ext[6];
  imageInfo->Get(vtkStreamingDemandDrivenPipeline::WHOLE_EXTENT(), ext);
  imageInfo->Set(vtkStreamingDemandDrivenPipeline::UPDATE_EXTENT(), ext, 6);
  return 1;
}

int vtkReposePosedVolume::RequestData(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  vtkImageData* image = vtkImageData::GetData(inputVector[0]);
  vtkUnstructuredGrid* restMesh = vtkUnstructuredGrid::GetData(inputVector[1]);
  vtkUnstructuredGrid* posedMesh = vtkUnstructuredGrid::GetData(inputVector[2]);
  vtkImageData* output = vtkImageData::GetData(outputVector);
  if (!image || !restMesh || !posedMesh)
  {
    vtkErrorMacro(<< "needs a rest image (input 0), a rest tet mesh (input 1) and a posed tet mesh (input 2)");
    return 0;
  }
  vtkDataArray* scalars = image->GetPointData()->GetScalars();
  if (!scalars || scalars->GetNumberOfComponents() != 1)
  {
    vtkErrorMacro(<< "rest image has no single-component scalars");
    return 0;
  }
  try
  {
    if (restMesh->GetNumberOfPoints() != posedMesh->GetNumberOfPoints() ||
      restMesh->GetNumberOfCells() != posedMesh->GetNumberOfCells())
    {
      throw std::invalid_argument("rest and posed tet meshes differ in topology (" +
        std::to_string(restMesh->GetNumberOfPoints()) + " vs " +
        std::to_string(posedMesh->GetNumberOfPoints()) + " nodes)");
    }
    int ext[6];
    image->GetExtent(ext);
    double direction[9];
    for (int a = 0; a < 3; ++a)
    {
      for (int b = 0; b < 3; ++b)
      {
        direction[3 * a + b] = image->GetDirectionMatrix()->GetElement(a, b);
      }
    }
    const repose::ImageGrid rest = GridFromInfo(ext, image->GetOrigin(), image->GetSpacing(), direction);
    // Rest-side conversions are cached: between poses only the posed nodes change.
    Internals& in = *this->Internal;
    vtkCellArray* cells = restMesh->GetCells();
    const vtkMTimeType cellsTime = std::max(cells ? cells->GetMTime() : 0,
      restMesh->GetCellTypesArray() ? restMesh->GetCellTypesArray()->GetMTime() : 0);
    if (in.TetsCells != cells || in.TetsTime != cellsTime || in.TetsCount != restMesh->GetNumberOfCells())
    {
      in.TetsCells = nullptr;
      in.Tets = repose_vtk::ToTets(restMesh, "rest mesh");
      in.TetsCells = cells;
      in.TetsTime = cellsTime;
      in.TetsCount = restMesh->GetNumberOfCells();
    }
    const repose::Tets& tets = in.Tets;
    vtkPoints* restPoints = restMesh->GetPoints();
    if (in.RestPoints != restPoints || !restPoints || in.RestPointsTime != restPoints->GetMTime())
    {
      in.RestNodes = repose_vtk::ToPoints(restPoints);
      in.RestPoints = restPoints;
      in.RestPointsTime = restPoints ? restPoints->GetMTime() : 0;
    }
    const repose::Points& restNodes = in.RestNodes;
    const repose::Points posedNodes = repose_vtk::ToPoints(posedMesh->GetPoints());
    const repose::ImageGrid outGrid = repose::posedOutputGrid(
      rest, posedNodes, GridOptions(rest, this->PaddingVoxels, this->ExtrapolationDistance, this->MaxVoxels));
    int full[6];
    double origin[3], spacing[3];
    GridToArrays(outGrid, full, origin, spacing, direction);
    std::copy(full, full + 6, this->FullOutputExtent);
    repose::PullResampleOptions options;
    options.extrapolationDistance = this->ExtrapolationDistance;
    std::array<int, 6> voi = { full[0], full[1], full[2], full[3], full[4], full[5] };
    if (this->RestrictToSubExtent)
    {
      voi = ClampedSubExtent(full, this->OutputSubExtent);
      options.outputExtent = voi;
    }
    const repose::ImageGrid voiGrid = repose::extentGrid(outGrid, voi);
    const vtkIdType voxels = static_cast<vtkIdType>(voiGrid.voxelCount());
    // Rest scalars: converted again only when the array changes.
    const int kind = this->Interpolation == Nearest ? 0 : 1;
    if (!this->OutputDisplacement &&
      (in.Scalars != scalars || in.ScalarsTime != scalars->GetMTime() || in.ScalarsKind != kind))
    {
      in.Scalars = nullptr;
      in.LabelBoxes.reset();
      in.Labels.data.clear();
      in.Values.data.clear();
      if (kind == 0)
      {
        CopyScalars(scalars, in.Labels.data);
      }
      else
      {
        CopyScalars(scalars, in.Values.data);
      }
      in.Scalars = scalars;
      in.ScalarsTime = scalars->GetMTime();
      in.ScalarsKind = kind;
    }
    in.Labels.grid = rest;
    in.Values.grid = rest;
    if (this->ExtrapolationDistance != 0)
    {
      // The boundary depends on the rest topology only: recompute it when the cells change.
      if (!in.Boundary || in.Cells != cells || in.CellsTime != cellsTime ||
        in.NumberOfCells != restMesh->GetNumberOfCells())
      {
        in.Boundary.reset(new repose::TetBoundary(repose::tetBoundary(tets)));
        in.Cells = cells;
        in.CellsTime = cellsTime;
        in.NumberOfCells = restMesh->GetNumberOfCells();
      }
      options.boundary = in.Boundary.get();
      // Rest coverage depends on the rest points and grid too (MTimes grow monotonically, so the
      // newest of the inputs identifies them).
      const vtkMTimeType coverageTime = std::max({ cellsTime, restMesh->GetPoints()->GetMTime(),
        restMesh->GetMTime(), image->GetMTime() });
      if (!in.Coverage || in.CoverageTime != coverageTime || !in.Coverage->grid.sameGridAs(rest))
      {
        in.Coverage.reset(new repose::MaskVolume(repose::restMeshCoverage(rest, restNodes, tets)));
        in.Distance.reset(new repose::MaskVolume(repose::restMeshDistance(*in.Coverage)));
        in.CoverageTime = coverageTime;
      }
      options.restCoverage = in.Coverage.get();
      options.restDistance = in.Distance.get();
    }
    repose::PullResampleReport report;
    vtkSmartPointer<vtkDataArray> outScalars;
    this->ContestedBoneVoxels = 0;
    if (this->OutputDisplacement)
    {
      auto array = vtkSmartPointer<vtkFloatArray>::New();
      array->SetNumberOfComponents(3);
      array->SetNumberOfTuples(voxels);
      repose::displacementPullInto(rest, restNodes, posedNodes, tets, outGrid, options, array->GetPointer(0), &report);
      this->RigidBoneVoxels = 0;
      outScalars = array;
    }
    else if (this->Interpolation == Nearest)
    {
      const repose::LabelVolume& labels = in.Labels;
      // Written in place: the core fills every voxel. The previous pose's array is reused when nothing
      // but this filter and its own output (about to be replaced) holds it: a fresh one costs page
      // faults over the whole volume on every pose.
      vtkSmartPointer<vtkIntArray> array = in.LastLabels;
      in.LastLabels = nullptr;
      const int holders = array ? 1 + (output->GetPointData()->GetScalars() == array.GetPointer() ? 1 : 0) : 0;
      // Poses change the output grid a little: allocated with some room, reused while it holds the
      // grid and is not much larger.
      if (!array || array->GetReferenceCount() != holders || array->GetSize() < voxels ||
        array->GetSize() > voxels + voxels / 4)
      {
        array = vtkSmartPointer<vtkIntArray>::New();
        array->Allocate(voxels + voxels / 8);
      }
      array->SetNumberOfTuples(voxels);
      in.LastLabels = array;
      repose::resampleLabelsPullInto(labels, restNodes, posedNodes, tets, outGrid, options, array->GetPointer(0),
        static_cast<std::int32_t>(this->BackgroundValue), &report);
      this->RigidBoneVoxels = 0;
      this->ContestedBoneVoxels = 0;
      vtkDataArray* fixed = restMesh->GetPointData()->GetArray(repose::arrays::kFixedBone);
      if (this->RigidBones && fixed && fixed->GetNumberOfTuples() == restMesh->GetNumberOfPoints())
      {
        // Pose-independent inputs of the overlay are converted once.
        if (in.FixedArray != fixed || in.FixedTime != fixed->GetMTime() ||
          in.FixedBone.size() != static_cast<std::size_t>(fixed->GetNumberOfTuples()))
        {
          in.FixedArray = nullptr;
          in.FixedBone.resize(static_cast<std::size_t>(fixed->GetNumberOfTuples()));
          for (vtkIdType v = 0; v < fixed->GetNumberOfTuples(); ++v)
          {
            in.FixedBone[static_cast<std::size_t>(v)] = static_cast<int>(fixed->GetTuple1(v));
          }
          in.FixedArray = fixed;
          in.FixedTime = fixed->GetMTime();
        }
        const std::array<int, 3> dims = { { rest.dims[0], rest.dims[1], rest.dims[2] } };
        if (!in.LabelBoxes || in.LabelBoxesDims != dims)
        {
          in.LabelBoxes.reset(new std::vector<Eigen::AlignedBox3i>(repose::restLabelBoxes(labels)));
          in.LabelBoxesDims = dims;
        }
        const auto bones = repose::rigidBonesFromMesh(labels, restNodes, posedNodes, in.FixedBone);
        std::size_t contested = 0;
        this->RigidBoneVoxels = static_cast<vtkIdType>(repose::overlayRigidBones(
          array->GetPointer(0), voiGrid, labels, bones, in.LabelBoxes.get(), &contested));
        this->ContestedBoneVoxels = static_cast<vtkIdType>(contested);
      }
      outScalars = array;
    }
    else
    {
      auto array = vtkSmartPointer<vtkFloatArray>::New();
      array->SetNumberOfTuples(voxels);
      repose::resampleIntensityPullInto(in.Values, restNodes, posedNodes, tets, outGrid, options,
        array->GetPointer(0), static_cast<float>(this->BackgroundValue), &report);
      outScalars = array;
    }
    outScalars->SetName(this->OutputDisplacement ? repose::arrays::kDisplacement
        : scalars->GetName()                       ? scalars->GetName()
                                                   : repose::arrays::kImageScalars);
    outScalars->Modified();
    // The full grid's origin: the sub-extent's voxels keep their indices.
    output->Initialize();
    output->SetExtent(voi.data());
    output->SetOrigin(origin);
    output->SetSpacing(spacing);
    output->SetDirectionMatrix(direction);
    output->GetPointData()->SetScalars(outScalars);
    output->GetFieldData()->PassData(image->GetFieldData()); // e.g. a DICOM input's patient and study
    this->CoveredVoxels = static_cast<vtkIdType>(report.coveredVoxels);
    this->ExtrapolatedVoxels = static_cast<vtkIdType>(report.extrapolatedVoxels);
    this->InvertedTets = static_cast<vtkIdType>(report.invertedTets);
    this->LastResampleTime = report.seconds;
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro(<< e.what());
    return 0;
  }
  return 1;
}

void vtkReposePosedVolume::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "RigidBones: " << this->RigidBones << "\n";
  os << indent << "OutputDisplacement: " << this->OutputDisplacement << "\n";
  os << indent << "Interpolation: " << (this->Interpolation == Nearest ? "Nearest" : "Linear") << "\n";
  os << indent << "BackgroundValue: " << this->BackgroundValue << "\n";
  os << indent << "PaddingVoxels: " << this->PaddingVoxels << "\n";
  os << indent << "MaxVoxels: " << this->MaxVoxels << "\n";
  os << indent << "ExtrapolationDistance: " << this->ExtrapolationDistance << "\n";
  os << indent << "CoveredVoxels: " << this->CoveredVoxels << "\n";
  os << indent << "ExtrapolatedVoxels: " << this->ExtrapolatedVoxels << "\n";
  os << indent << "InvertedTets: " << this->InvertedTets << "\n";
  os << indent << "LastResampleTime: " << this->LastResampleTime << "\n";
  os << indent << "RestrictToSubExtent: " << this->RestrictToSubExtent << "\n";
  os << indent << "OutputSubExtent: " << this->OutputSubExtent[0] << " " << this->OutputSubExtent[1] << " "
     << this->OutputSubExtent[2] << " " << this->OutputSubExtent[3] << " " << this->OutputSubExtent[4] << " "
     << this->OutputSubExtent[5] << "\n";
}
