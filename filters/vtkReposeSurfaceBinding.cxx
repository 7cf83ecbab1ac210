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
#include "array_names.h"

#include <stdexcept>
#include <string>

vtkStandardNewMacro(vtkReposeSurfaceBinding);

namespace
{
repose::Points ToPoints(vtkPoints* points)
{
  const vtkIdType n = points ? points->GetNumberOfPoints() : 0;
  repose::Points P(n, 3);
  for (vtkIdType i = 0; i < n; ++i)
  {
    double x[3];
    points->GetPoint(i, x);
    P.row(i) << x[0], x[1], x[2];
  }
  return P;
}

repose::Tets ToTets(vtkUnstructuredGrid* mesh)
{
  const vtkIdType n = mesh->GetNumberOfCells();
  repose::Tets T(n, 4);
  vtkIdType npts;
  const vtkIdType* pts;
  for (vtkIdType c = 0; c < n; ++c)
  {
    if (mesh->GetCellType(c) != VTK_TETRA)
    {
      throw std::invalid_argument("tet mesh cell " + std::to_string(c) +
        " is not a tetrahedron; bind to a tet mesh (e.g. from vtkReposeBodyMesher)");
    }
    mesh->GetCellPoints(c, npts, pts);
    for (int a = 0; a < 4; ++a)
    {
      T(c, a) = static_cast<int>(pts[a]);
    }
  }
  return T;
}
}

vtkReposeSurfaceBinding::vtkReposeSurfaceBinding()
{
  this->SetNumberOfInputPorts(2);
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
    const repose::Points nodes = ToPoints(mesh->GetPoints());
    const repose::Tets tets = ToTets(mesh);
    const repose::Points points = ToPoints(surface->GetPoints());
    const repose::Binding binding = repose::bindPoints(nodes, tets, points);
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
