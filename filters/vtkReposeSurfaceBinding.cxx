#include "vtkReposeSurfaceBinding.h"

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
#include "tet_locator.h"
#include "ReposeMeshConversion.h"
#include "array_names.h"

#include <memory>
#include <stdexcept>
#include <string>

vtkStandardNewMacro(vtkReposeSurfaceBinding);

// The rest mesh as core matrices and its locator, kept while the mesh's points and cells are unchanged.
struct vtkReposeSurfaceBinding::Internals
{
  vtkUnstructuredGrid* Mesh = nullptr;
  vtkMTimeType PointsTime = 0;
  vtkMTimeType CellsTime = 0;
  repose::Points Nodes;
  repose::Tets Tets;
  std::unique_ptr<repose::TetLocator> Locator;  // refers to Nodes and Tets
};

vtkReposeSurfaceBinding::vtkReposeSurfaceBinding()
  : Impl(new Internals)
{
  this->SetNumberOfInputPorts(2);
}

vtkReposeSurfaceBinding::~vtkReposeSurfaceBinding()
{
  delete this->Impl;
}

int vtkReposeSurfaceBinding::FillInputPortInformation(int port, vtkInformation* info)
{
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), port == 0 ? "vtkPolyData" : "vtkUnstructuredGrid");
  return 1;
}

int vtkReposeSurfaceBinding::RequestData(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  vtkPolyData* surface = vtkPolyData::GetData(inputVector[0]);
  vtkUnstructuredGrid* mesh = vtkUnstructuredGrid::GetData(inputVector[1]);
  vtkPolyData* output = vtkPolyData::GetData(outputVector);
  if (!surface || !mesh)
  {
    vtkErrorMacro(<< "needs rest surfaces (input 0) and the rest tet mesh (input 1)");
    return 0;
  }
  try
  {
    Internals& in = *this->Impl;
    const vtkMTimeType pointsTime = mesh->GetPoints() ? mesh->GetPoints()->GetMTime() : 0;
    const vtkMTimeType cellsTime = mesh->GetCells() ? mesh->GetCells()->GetMTime() : 0;
    if (!in.Locator || in.Mesh != mesh || in.PointsTime != pointsTime || in.CellsTime != cellsTime)
    {
      in.Locator.reset();
      in.Nodes = repose_vtk::ToPoints(mesh->GetPoints());
      in.Tets = repose_vtk::ToTets(mesh, "tet mesh");
      if (in.Tets.rows() == 0)
      {
        throw std::invalid_argument("bind points: the tet mesh has no tets");
      }
      in.Locator = std::make_unique<repose::TetLocator>(in.Nodes, in.Tets);
      in.Mesh = mesh;
      in.PointsTime = pointsTime;
      in.CellsTime = cellsTime;
    }
    const repose::Binding binding = repose::bindPoints(*in.Locator, repose_vtk::ToPoints(surface->GetPoints()));
    const vtkIdType n = static_cast<vtkIdType>(binding.tet.size());
    auto tetArray = vtkSmartPointer<vtkIntArray>::New();
    tetArray->SetName(repose::arrays::kBoundTet);
    tetArray->SetNumberOfTuples(n);
    std::copy(binding.tet.begin(), binding.tet.end(), tetArray->GetPointer(0));
    auto weights = vtkSmartPointer<vtkFloatArray>::New();
    weights->SetName(repose::arrays::kBoundWeights);
    weights->SetNumberOfComponents(4);
    weights->SetNumberOfTuples(n);
    std::copy(binding.bary.data(), binding.bary.data() + 4 * n, weights->GetPointer(0));
    output->ShallowCopy(surface);
    output->GetPointData()->AddArray(tetArray);
    output->GetPointData()->AddArray(weights);
    this->OutsideCount = static_cast<vtkIdType>(binding.outsideCount);
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro(<< e.what());
    return 0;
  }
  return 1;
}

void vtkReposeSurfaceBinding::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "OutsideCount: " << this->OutsideCount << "\n";
}
