#include "vtkReposeSurfaceDeformer.h"

#include "vtkCellData.h"
#include "vtkCellType.h"
#include "vtkAOSDataArrayTemplate.h"
#include "vtkDataArray.h"
#include "vtkFloatArray.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkIntArray.h"
#include "vtkObjectFactory.h"
#include "vtkPointData.h"
#include "vtkPoints.h"
#include "vtkPolyData.h"
#include "vtkSmartPointer.h"
#include "vtkUnstructuredGrid.h"

#include "barycentric_binding.h"
#include "array_names.h"

#include <chrono>
#include <stdexcept>
#include <string>
#include <vector>

vtkStandardNewMacro(vtkReposeSurfaceDeformer);

// Cached per-vertex binding: each vertex's own 4 node ids ("local tets"), so a pose needs only the
// posed node positions.
struct vtkReposeSurfaceDeformer::Internals
{
  repose::NodeBinding Bound;  // 4 node ids + 4 float weights per vertex
  vtkMTimeType SurfaceTime = 0;
  vtkPolyData* Surface = nullptr;
  vtkMTimeType CellsTime = 0;
  vtkUnstructuredGrid* Mesh = nullptr;
  std::vector<float> Nodes;  // only for posed points that are neither float nor double AOS
  // Output points, reused while the vertex count is unchanged (no allocation per pose).
  vtkSmartPointer<vtkPoints> Moved;

  /// Bound from the surface's BoundTet/BoundWeights and the mesh's cells, kept while neither changes.
  void Bind(vtkPolyData* surface, vtkUnstructuredGrid* mesh);
  /// Moved: the bound vertices at the mesh's (posed) nodes.
  void Deform(vtkPolyData* surface, vtkUnstructuredGrid* mesh);
};

namespace
{
/// The surface's binding as the core reads it: vertex p in "tet" p, whose corners are the node ids of
/// the tet it is bound to (so makeNodeBinding gives each vertex its 4 nodes and weights).
void ToLocalBinding(vtkPolyData* surface, vtkUnstructuredGrid* mesh, repose::Binding& local, repose::Tets& localTets)
{
  vtkIntArray* tetArray = vtkIntArray::SafeDownCast(surface->GetPointData()->GetArray(repose::arrays::kBoundTet));
  vtkFloatArray* weights =
    vtkFloatArray::SafeDownCast(surface->GetPointData()->GetArray(repose::arrays::kBoundWeights));
  if (!tetArray || !weights || weights->GetNumberOfComponents() != 4)
  {
    throw std::invalid_argument(
      "input surface has no BoundTet/BoundWeights point data; bind it with vtkReposeSurfaceBinding first");
  }
  const vtkIdType n = surface->GetNumberOfPoints();
  if (tetArray->GetNumberOfTuples() != n || weights->GetNumberOfTuples() != n)
  {
    throw std::invalid_argument("BoundTet/BoundWeights hold " + std::to_string(tetArray->GetNumberOfTuples()) + "/" +
      std::to_string(weights->GetNumberOfTuples()) + " values for " + std::to_string(n) +
      " surface points; bind the surface again");
  }
  const vtkIdType nCells = mesh->GetNumberOfCells();
  localTets.resize(n, 4);
  local.tet.resize(static_cast<std::size_t>(n));
  local.bary.resize(n, 4);
  vtkIdType npts;
  const vtkIdType* pts;
  for (vtkIdType p = 0; p < n; ++p)
  {
    const int t = tetArray->GetValue(p);
    if (t < 0 || t >= nCells || mesh->GetCellType(t) != VTK_TETRA)
    {
      throw std::invalid_argument("vertex " + std::to_string(p) + " is bound to tet " + std::to_string(t) +
        ", which is not a tetrahedron of the posed mesh (was it bound to another mesh?)");
    }
    mesh->GetCellPoints(t, npts, pts);
    for (int a = 0; a < 4; ++a)
    {
      localTets(p, a) = static_cast<int>(pts[a]);
      local.bary(p, a) = weights->GetTypedComponent(p, a);
    }
    local.tet[static_cast<std::size_t>(p)] = static_cast<int>(p);
  }
}
}

void vtkReposeSurfaceDeformer::Internals::Bind(vtkPolyData* surface, vtkUnstructuredGrid* mesh)
{
  const vtkMTimeType cellsTime = mesh->GetCells() ? mesh->GetCells()->GetMTime() : 0;
  if (this->Surface == surface && this->SurfaceTime == surface->GetMTime() && this->Mesh == mesh &&
    this->CellsTime == cellsTime)
  {
    return;
  }
  this->Surface = nullptr;
  repose::Binding local;
  repose::Tets localTets;
  ToLocalBinding(surface, mesh, local, localTets);
  this->Bound = repose::makeNodeBinding(local, localTets);
  this->Surface = surface;
  this->SurfaceTime = surface->GetMTime();
  this->Mesh = mesh;
  this->CellsTime = cellsTime;
}

void vtkReposeSurfaceDeformer::Internals::Deform(vtkPolyData* surface, vtkUnstructuredGrid* mesh)
{
  const vtkIdType n = surface->GetNumberOfPoints();
  vtkPoints* nodes = mesh->GetPoints();
  const vtkIdType nv = nodes ? nodes->GetNumberOfPoints() : 0;
  if (!this->Moved || this->Moved->GetNumberOfPoints() != n)
  {
    this->Moved = vtkSmartPointer<vtkPoints>::New();
    this->Moved->SetDataTypeToFloat();
    this->Moved->SetNumberOfPoints(n);
  }
  float* dst = vtkArrayDownCast<vtkFloatArray>(this->Moved->GetData())->GetPointer(0);
  vtkDataArray* data = nodes ? nodes->GetData() : nullptr;
  // Read the posed nodes in place (vtkReposeSkinning writes float).
  if (auto* f = vtkArrayDownCast<vtkAOSDataArrayTemplate<float>>(data))
  {
    repose::applyBinding(this->Bound, f->GetPointer(0), static_cast<std::size_t>(nv), dst);
  }
  else if (auto* d = vtkArrayDownCast<vtkAOSDataArrayTemplate<double>>(data))
  {
    repose::applyBinding(this->Bound, d->GetPointer(0), static_cast<std::size_t>(nv), dst);
  }
  else
  {
    this->Nodes.resize(3 * static_cast<std::size_t>(nv));
    for (vtkIdType v = 0; v < nv; ++v)
    {
      double x[3];
      nodes->GetPoint(v, x);
      for (int c = 0; c < 3; ++c)
        this->Nodes[3 * v + c] = static_cast<float>(x[c]);
    }
    repose::applyBinding(this->Bound, this->Nodes.data(), static_cast<std::size_t>(nv), dst);
  }
  // Same points object, new contents: mark it (and its array) modified for renderers/bounds.
  this->Moved->GetData()->Modified();
  this->Moved->Modified();
}

vtkReposeSurfaceDeformer::vtkReposeSurfaceDeformer()
  : Impl(new Internals)
{
  this->SetNumberOfInputPorts(2);
}

vtkReposeSurfaceDeformer::~vtkReposeSurfaceDeformer()
{
  delete this->Impl;
}

int vtkReposeSurfaceDeformer::FillInputPortInformation(int port, vtkInformation* info)
{
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), port == 0 ? "vtkPolyData" : "vtkUnstructuredGrid");
  return 1;
}

int vtkReposeSurfaceDeformer::RequestData(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  vtkPolyData* surface = vtkPolyData::GetData(inputVector[0]);
  vtkUnstructuredGrid* mesh = vtkUnstructuredGrid::GetData(inputVector[1]);
  vtkPolyData* output = vtkPolyData::GetData(outputVector);
  if (!surface || !mesh)
  {
    vtkErrorMacro(<< "needs a bound surface (input 0) and the posed tet mesh (input 1)");
    return 0;
  }
  const auto start = std::chrono::steady_clock::now();
  try
  {
    this->Impl->Bind(surface, mesh);
    this->Impl->Deform(surface, mesh);
    output->ShallowCopy(surface);
    output->SetPoints(this->Impl->Moved);
    // Normals of the rest surface are wrong after deformation; renderers recompute them if needed.
    output->GetPointData()->SetNormals(nullptr);
    output->GetCellData()->SetNormals(nullptr);
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro(<< e.what());
    return 0;
  }
  this->LastDeformTime = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return 1;
}

void vtkReposeSurfaceDeformer::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "LastDeformTime: " << this->LastDeformTime << "\n";
}
