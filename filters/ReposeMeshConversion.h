#ifndef ReposeMeshConversion_h
#define ReposeMeshConversion_h
// vtkPoints / tet vtkUnstructuredGrid <-> core point and tet matrices (tet_mesh.h), shared by the
// filters, the volume module and the app so that every route converts a mesh the same way.
// Header-only and not wrapped: it exchanges core (Eigen) types. Coordinates are copied exactly
// (float or double to double), so results do not depend on which route converted them.

#include "vtkCellArray.h"
#include "vtkCellType.h"
#include "vtkIdList.h"
#include "vtkNew.h"
#include "vtkPolyData.h"
#include "vtkDataArray.h"
#include "vtkPoints.h"
#include "vtkSmartPointer.h"
#include "vtkUnstructuredGrid.h"

#include <stdexcept>
#include <string>
#include <vector>

#include "tet_mesh.h"

namespace repose_vtk
{

/// #P by 3 node coordinates (any VTK point type, read without per-point virtual calls for float and
/// double). An empty matrix for null points.
inline repose::Points ToPoints(vtkPoints* points)
{
  const vtkIdType n = points ? points->GetNumberOfPoints() : 0;
  repose::Points P(n, 3);
  if (n == 0)
  {
    return P;
  }
  vtkDataArray* data = points->GetData();
  if (data->GetDataType() == VTK_FLOAT || data->GetDataType() == VTK_DOUBLE)
  {
    const vtkIdType count = 3 * n;
    if (data->GetDataType() == VTK_FLOAT)
    {
      const float* src = static_cast<const float*>(data->GetVoidPointer(0));
      for (vtkIdType i = 0; i < count; ++i)
      {
        P.data()[i] = src[i];
      }
    }
    else
    {
      const double* src = static_cast<const double*>(data->GetVoidPointer(0));
      std::copy(src, src + count, P.data());
    }
    return P;
  }
  for (vtkIdType i = 0; i < n; ++i)
  {
    double x[3];
    points->GetPoint(i, x);
    P.row(i) << x[0], x[1], x[2];
  }
  return P;
}

/// #T by 4 node ids of a mesh whose every cell is a tetrahedron. Throws std::invalid_argument naming
/// `what` and the first other cell.
inline repose::Tets ToTets(vtkUnstructuredGrid* mesh, const char* what = "tet mesh")
{
  const vtkIdType n = mesh ? mesh->GetNumberOfCells() : 0;
  repose::Tets T(n, 4);
  vtkIdType npts;
  const vtkIdType* pts;
  for (vtkIdType c = 0; c < n; ++c)
  {
    if (mesh->GetCellType(c) != VTK_TETRA)
    {
      throw std::invalid_argument(std::string(what) + " cell " + std::to_string(c) +
        " is not a tetrahedron; pass a tet mesh (e.g. from vtkReposeBodyMesher)");
    }
    mesh->GetCellPoints(c, npts, pts);
    for (int a = 0; a < 4; ++a)
    {
      T(c, a) = static_cast<int>(pts[a]);
    }
  }
  return T;
}

/// The polygons of a surface as triangles (#F by 3 node ids): a polygon of n corners becomes the fan
/// (0, k, k+1), k = 1..n-2, in cell order. Vertices and lines are skipped.
inline repose::Triangles ToTriangleFans(vtkPolyData* surface)
{
  std::vector<int> tris;
  vtkCellArray* polys = surface->GetPolys();
  vtkNew<vtkIdList> ids;
  for (polys->InitTraversal(); polys->GetNextCell(ids);)
  {
    for (vtkIdType k = 1; k + 1 < ids->GetNumberOfIds(); ++k)
    {
      tris.push_back(static_cast<int>(ids->GetId(0)));
      tris.push_back(static_cast<int>(ids->GetId(k)));
      tris.push_back(static_cast<int>(ids->GetId(k + 1)));
    }
  }
  repose::Triangles F(static_cast<Eigen::Index>(tris.size() / 3), 3);
  std::copy(tris.begin(), tris.end(), F.data());
  return F;
}

/// vtkPoints of the given VTK data type holding P's rows.
inline vtkSmartPointer<vtkPoints> ToPoints(const repose::Points& P, int dataType)
{
  auto points = vtkSmartPointer<vtkPoints>::New();
  points->SetDataType(dataType);
  points->SetNumberOfPoints(P.rows());
  for (vtkIdType v = 0; v < P.rows(); ++v)
  {
    points->SetPoint(v, P(v, 0), P(v, 1), P(v, 2));
  }
  return points;
}

/// The first component of every tuple of an array, as ints.
inline std::vector<int> ToInts(vtkDataArray* array)
{
  std::vector<int> values(static_cast<std::size_t>(array->GetNumberOfTuples()));
  for (vtkIdType i = 0; i < array->GetNumberOfTuples(); ++i)
  {
    values[static_cast<std::size_t>(i)] = static_cast<int>(array->GetTuple1(i));
  }
  return values;
}

} // namespace repose_vtk

#endif
