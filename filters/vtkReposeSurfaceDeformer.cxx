#include "vtkReposeSurfaceDeformer.h"

#include "vtkCellData.h"
#include "vtkCellType.h"
#include "vtkDataArray.h"
#include "vtkFloatArray.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkIntArray.h"
#include "vtkObjectFactory.h"
#include "vtkPointData.h"
#include "vtkPoints.h"
#include "vtkPolyData.h"
#include "vtkUnstructuredGrid.h"

#include "barycentric_binding.h"

#include <chrono>
#include <stdexcept>
#include <string>

vtkStandardNewMacro(vtkReposeSurfaceDeformer);

// Cached per-vertex binding: each vertex's own 4 node ids ("local tets"), so a pose needs only the
// posed node positions.
struct vtkReposeSurfaceDeformer::Internals
{
  repose::Binding Local;   // tet[p] == p
  repose::Tets LocalTets;  // #P by 4 node ids of the bound tet
  vtkMTimeType SurfaceTime = 0;
  vtkPolyData* Surface = nullptr;
  vtkMTimeType CellsTime = 0;
  vtkUnstructuredGrid* Mesh = nullptr;
  repose::Points Nodes;
  repose::Points Moved;
};

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
  Internals& in = *this->Impl;
  try
  {
    vtkIntArray* tetArray = vtkIntArray::SafeDownCast(surface->GetPointData()->GetArray("BoundTet"));
    vtkFloatArray* weights = vtkFloatArray::SafeDownCast(surface->GetPointData()->GetArray("BoundWeights"));
    if (!tetArray || !weights || weights->GetNumberOfComponents() != 4)
    {
      throw std::invalid_argument(
        "input surface has no BoundTet/BoundWeights point data; bind it with vtkReposeSurfaceBinding first");
    }
    const vtkIdType n = surface->GetNumberOfPoints();
    const vtkMTimeType cellsTime = mesh->GetCells() ? mesh->GetCells()->GetMTime() : 0;
    if (in.Surface != surface || in.SurfaceTime != surface->GetMTime() || in.Mesh != mesh ||
      in.CellsTime != cellsTime)
    {
      const vtkIdType nCells = mesh->GetNumberOfCells();
      in.Local.tet.resize(static_cast<std::size_t>(n));
      in.Local.bary.resize(n, 4);
      in.LocalTets.resize(n, 4);
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
          in.LocalTets(p, a) = static_cast<int>(pts[a]);
          in.Local.bary(p, a) = weights->GetTypedComponent(p, a);
        }
        in.Local.tet[static_cast<std::size_t>(p)] = static_cast<int>(p);
      }
      in.Surface = surface;
      in.SurfaceTime = surface->GetMTime();
      in.Mesh = mesh;
      in.CellsTime = cellsTime;
    }
    vtkPoints* nodes = mesh->GetPoints();
    const vtkIdType nv = nodes ? nodes->GetNumberOfPoints() : 0;
    in.Nodes.resize(nv, 3);
    for (vtkIdType v = 0; v < nv; ++v)
    {
      double x[3];
      nodes->GetPoint(v, x);
      in.Nodes.row(v) << x[0], x[1], x[2];
    }
    repose::applyBinding(in.Local, in.LocalTets, in.Nodes, in.Moved);
    auto moved = vtkSmartPointer<vtkPoints>::New();
    moved->SetDataTypeToFloat();
    moved->SetNumberOfPoints(n);
    float* dst = static_cast<vtkFloatArray*>(moved->GetData())->GetPointer(0);
    for (vtkIdType i = 0; i < 3 * n; ++i)
    {
      dst[i] = static_cast<float>(in.Moved.data()[i]);
    }
    output->ShallowCopy(surface);
    output->SetPoints(moved);
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
