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

#include "pull_resample_cache.h"
#include "resample_pull.h"
#include "ReposeMeshConversion.h"
#include "array_names.h"

#include <algorithm>
#include <array>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

vtkStandardNewMacro(vtkReposePosedVolume);

namespace
{
// The newest MTime of a rest mesh's cells and cell types: its topology changed since.
vtkMTimeType TopologyTime(vtkUnstructuredGrid* mesh)
{
  vtkCellArray* cells = mesh->GetCells();
  return std::max(cells ? cells->GetMTime() : 0,
    mesh->GetCellTypesArray() ? mesh->GetCellTypesArray()->GetMTime() : 0);
}
}

// The rest inputs converted for the core, with what they were converted from: an input is set again
// in the cache only when its VTK object or MTime changed.
struct vtkReposePosedVolume::Internals
{
  repose::PullResampleCache Cache;
  vtkCellArray* Cells = nullptr;
  vtkMTimeType CellsTime = 0;
  vtkIdType NumberOfCells = -1;
  vtkPoints* RestPoints = nullptr;
  vtkMTimeType RestPointsTime = 0;
  vtkDataArray* Scalars = nullptr;
  vtkMTimeType ScalarsTime = 0;
  int ScalarsKind = -1;  // 0 labels, 1 intensities
  vtkDataArray* FixedArray = nullptr;
  vtkMTimeType FixedTime = 0;
  std::size_t FixedSize = 0;
  // The last label output array, for reuse by the next pose.
  vtkSmartPointer<vtkIntArray> LastLabels;

  void UpdateTets(vtkUnstructuredGrid* mesh);
  void UpdateRestNodes(vtkPoints* points);
  void UpdateScalars(vtkDataArray* scalars, int kind);
  void UpdateFixedBone(vtkDataArray* fixed);
  // An int array of `voxels` tuples for the labels, the last pose's when it can be reused.
  vtkIntArray* LabelArray(vtkImageData* output, vtkIdType voxels);
  // The rest side brought up to date (tets, nodes, grid, the values resampled, the fixed nodes);
  // whether bones are kept rigid.
  bool UpdateRest(vtkReposePosedVolume* self, vtkUnstructuredGrid* restMesh, const repose::ImageGrid& rest,
    vtkDataArray* scalars, int kind);
  // The posed grid's values (labels, intensities or displacements) over `voxels` voxels.
  vtkSmartPointer<vtkDataArray> Resample(vtkReposePosedVolume* self, const repose::Points& posedNodes,
    const repose::ImageGrid& outGrid, const repose::PullResampleOptions& options, vtkIdType voxels, int kind,
    bool rigid, vtkImageData* output, repose::PullResampleReport& report);
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
/// The grid of an image: its extent, origin, spacing and direction matrix.
repose::ImageGrid GridOfImage(vtkImageData* image)
{
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
  return GridFromInfo(ext, image->GetOrigin(), image->GetSpacing(), direction);
}

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

void vtkReposePosedVolume::Internals::UpdateTets(vtkUnstructuredGrid* mesh)
{
  vtkCellArray* cells = mesh->GetCells();
  const vtkMTimeType time = TopologyTime(mesh);
  if (this->Cells != cells || this->CellsTime != time || this->NumberOfCells != mesh->GetNumberOfCells())
  {
    this->Cells = nullptr;
    this->Cache.setTets(repose_vtk::ToTets(mesh, "rest mesh"));
    this->Cells = cells;
    this->CellsTime = time;
    this->NumberOfCells = mesh->GetNumberOfCells();
  }
}

void vtkReposePosedVolume::Internals::UpdateRestNodes(vtkPoints* points)
{
  if (this->RestPoints != points || !points || this->RestPointsTime != points->GetMTime())
  {
    this->RestPoints = nullptr;
    this->Cache.setRestNodes(repose_vtk::ToPoints(points));
    this->RestPoints = points;
    this->RestPointsTime = points ? points->GetMTime() : 0;
  }
}

void vtkReposePosedVolume::Internals::UpdateScalars(vtkDataArray* scalars, int kind)
{
  if (this->Scalars != scalars || this->ScalarsTime != scalars->GetMTime() || this->ScalarsKind != kind)
  {
    this->Scalars = nullptr;
    if (kind == 0)
    {
      std::vector<std::int32_t> labels;
      CopyScalars(scalars, labels);
      this->Cache.setLabels(std::move(labels));
    }
    else
    {
      std::vector<float> values;
      CopyScalars(scalars, values);
      this->Cache.setIntensities(std::move(values));
    }
    this->Scalars = scalars;
    this->ScalarsTime = scalars->GetMTime();
    this->ScalarsKind = kind;
  }
}

void vtkReposePosedVolume::Internals::UpdateFixedBone(vtkDataArray* fixed)
{
  const std::size_t n = static_cast<std::size_t>(fixed->GetNumberOfTuples());
  if (this->FixedArray != fixed || this->FixedTime != fixed->GetMTime() || this->FixedSize != n)
  {
    this->FixedArray = nullptr;
    std::vector<int> bone(n);
    for (std::size_t v = 0; v < n; ++v)
    {
      bone[v] = static_cast<int>(fixed->GetTuple1(static_cast<vtkIdType>(v)));
    }
    this->Cache.setFixedBone(std::move(bone));
    this->FixedArray = fixed;
    this->FixedTime = fixed->GetMTime();
    this->FixedSize = n;
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

bool vtkReposePosedVolume::Internals::UpdateRest(vtkReposePosedVolume* self, vtkUnstructuredGrid* restMesh,
  const repose::ImageGrid& rest, vtkDataArray* scalars, int kind)
{
  // Rest-side conversions are cached: between poses only the posed nodes change.
  this->UpdateTets(restMesh);
  this->UpdateRestNodes(restMesh->GetPoints());
  this->Cache.setRestGrid(rest);
  if (!self->OutputDisplacement)
  {
    this->UpdateScalars(scalars, kind);
  }
  vtkDataArray* fixed = restMesh->GetPointData()->GetArray(repose::arrays::kFixedBone);
  const bool rigid = self->RigidBones && fixed && fixed->GetNumberOfTuples() == restMesh->GetNumberOfPoints();
  if (rigid && kind == 0 && !self->OutputDisplacement)
  {
    this->UpdateFixedBone(fixed);
  }
  return rigid;
}

vtkSmartPointer<vtkDataArray> vtkReposePosedVolume::Internals::Resample(vtkReposePosedVolume* self,
  const repose::Points& posedNodes, const repose::ImageGrid& outGrid, const repose::PullResampleOptions& options,
  vtkIdType voxels, int kind, bool rigid, vtkImageData* output, repose::PullResampleReport& report)
{
  self->RigidBoneVoxels = 0;
  self->ContestedBoneVoxels = 0;
  if (self->OutputDisplacement)
  {
    auto array = vtkSmartPointer<vtkFloatArray>::New();
    array->SetNumberOfComponents(3);
    array->SetNumberOfTuples(voxels);
    this->Cache.displacementInto(posedNodes, outGrid, options, array->GetPointer(0), &report);
    return array;
  }
  if (kind == 0)
  {
    vtkIntArray* array = this->LabelArray(output, voxels);
    const repose::RigidBoneCounts counts = this->Cache.labelsInto(posedNodes, outGrid, options,
      array->GetPointer(0), static_cast<std::int32_t>(self->BackgroundValue), rigid, &report);
    self->RigidBoneVoxels = static_cast<vtkIdType>(counts.changedVoxels);
    self->ContestedBoneVoxels = static_cast<vtkIdType>(counts.contestedVoxels);
    return array;
  }
  auto array = vtkSmartPointer<vtkFloatArray>::New();
  array->SetNumberOfTuples(voxels);
  this->Cache.intensitiesInto(posedNodes, outGrid, options, array->GetPointer(0),
    static_cast<float>(self->BackgroundValue), &report);
  return array;
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
    const repose::ImageGrid rest = GridOfImage(image);
    const int kind = this->Interpolation == Nearest ? 0 : 1;
    const bool rigid = this->Internal->UpdateRest(this, restMesh, rest, scalars, kind);
    const repose::Points posedNodes = repose_vtk::ToPoints(posedMesh->GetPoints());
    const repose::ImageGrid outGrid = repose::posedOutputGrid(
      rest, posedNodes, GridOptions(rest, this->PaddingVoxels, this->ExtrapolationDistance, this->MaxVoxels));
    int full[6];
    double origin[3], spacing[3], direction[9];
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
    const vtkIdType voxels = static_cast<vtkIdType>(repose::extentGrid(outGrid, voi).voxelCount());
    repose::PullResampleReport report;
    vtkSmartPointer<vtkDataArray> outScalars =
      this->Internal->Resample(this, posedNodes, outGrid, options, voxels, kind, rigid, output, report);
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

vtkIntArray* vtkReposePosedVolume::Internals::LabelArray(vtkImageData* output, vtkIdType voxels)
{
  // Written in place: the core fills every voxel. The previous pose's array is reused when nothing
  // but this filter and its own output (about to be replaced) holds it: a fresh one costs page
  // faults over the whole volume on every pose.
  vtkSmartPointer<vtkIntArray> array = this->LastLabels;
  this->LastLabels = nullptr;
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
  this->LastLabels = array;
  return array;
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
