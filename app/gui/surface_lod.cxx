#include "surface_lod.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <set>

#include <vtkCellArray.h>
#include <vtkCellArrayIterator.h>
#include <vtkCellData.h>
#include <vtkDataArray.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>

namespace repose {
namespace {

/// The grid cell of every vertex, as one key.
std::vector<long long> cellOfVertices(vtkPolyData* full, int divisions) {
  double b[6];
  full->GetBounds(b);
  const double longest = std::max({b[1] - b[0], b[3] - b[2], b[5] - b[4], 1e-6});
  int n[3];
  for (int a = 0; a < 3; ++a) n[a] = std::max(2, int(divisions * (b[2 * a + 1] - b[2 * a]) / longest));
  std::vector<long long> cell(static_cast<std::size_t>(full->GetNumberOfPoints()));
  for (std::size_t i = 0; i < cell.size(); ++i) {
    double x[3];
    full->GetPoint(vtkIdType(i), x);
    long long key = 0;
    for (int a = 2; a >= 0; --a) {
      const double extent = std::max(b[2 * a + 1] - b[2 * a], 1e-9);
      key = key * (n[a] + 1) + std::clamp(int((x[a] - b[2 * a]) / extent * n[a]), 0, n[a]);
    }
    cell[i] = key;
  }
  return cell;
}

/// Union-find whose sets are the pieces of surface connected inside one cell.
struct Clusters {
  std::vector<vtkIdType> parent;
  vtkIdType root(vtkIdType i) {
    while (parent[std::size_t(i)] != i) i = parent[std::size_t(i)] = parent[std::size_t(parent[std::size_t(i)])];
    return i;
  }
  Clusters(vtkPolyData* full, const std::vector<long long>& cell) : parent(cell.size()) {
    std::iota(parent.begin(), parent.end(), vtkIdType(0));
    auto it = vtk::TakeSmartPointer(full->GetPolys()->NewIterator());
    for (it->GoToFirstCell(); !it->IsDoneWithTraversal(); it->GoToNextCell()) {
      vtkIdType size;
      const vtkIdType* v;
      it->GetCurrentCell(size, v);
      for (vtkIdType k = 0; k < size; ++k) {
        const vtkIdType p = v[k], q = v[(k + 1) % size];
        if (cell[std::size_t(p)] == cell[std::size_t(q)]) parent[std::size_t(root(p))] = root(q);
      }
    }
  }
};

/// Per cluster root: the member nearest the cluster's centroid (-1 for non-roots).
std::vector<vtkIdType> representatives(vtkPolyData* full, Clusters& clusters) {
  const std::size_t n = clusters.parent.size();
  std::vector<double> sum(3 * n, 0.0), best(n, 1e300);
  std::vector<int> count(n, 0);
  std::vector<vtkIdType> chosen(n, -1);
  for (std::size_t i = 0; i < n; ++i) {
    double x[3];
    full->GetPoint(vtkIdType(i), x);
    const std::size_t r = std::size_t(clusters.root(vtkIdType(i)));
    for (int a = 0; a < 3; ++a) sum[3 * r + a] += x[a];
    ++count[r];
  }
  for (std::size_t i = 0; i < n; ++i) {
    double x[3];
    full->GetPoint(vtkIdType(i), x);
    const std::size_t r = std::size_t(clusters.root(vtkIdType(i)));
    double d = 0;
    for (int a = 0; a < 3; ++a) d += std::pow(x[a] - sum[3 * r + a] / count[r], 2);
    if (d < best[r]) best[r] = d, chosen[r] = vtkIdType(i);
  }
  return chosen;
}

}  // namespace

vtkSmartPointer<vtkPolyData> decimateKeepingVertices(vtkPolyData* full, int divisions, std::vector<vtkIdType>& ids) {
  Clusters clusters(full, cellOfVertices(full, divisions));
  const std::vector<vtkIdType> representative = representatives(full, clusters);
  // Triangles whose corners fall in three different clusters survive, once each; a cluster becomes
  // a coarse vertex when a surviving triangle uses it.
  std::vector<vtkIdType> coarseOf(clusters.parent.size(), -1);
  ids.clear();
  auto points = vtkSmartPointer<vtkPoints>::New();
  points->SetDataType(full->GetPoints()->GetDataType());
  auto coarseVertex = [&](vtkIdType root) {
    if (coarseOf[std::size_t(root)] < 0) {
      coarseOf[std::size_t(root)] = vtkIdType(ids.size());
      ids.push_back(representative[std::size_t(root)]);
      points->InsertNextPoint(full->GetPoint(ids.back()));
    }
    return coarseOf[std::size_t(root)];
  };
  vtkDataArray* labels = full->GetCellData()->GetScalars();
  vtkSmartPointer<vtkDataArray> coarseLabels;
  if (labels) {
    coarseLabels = vtk::TakeSmartPointer(labels->NewInstance());
    coarseLabels->SetName(labels->GetName());
  }
  auto triangles = vtkSmartPointer<vtkCellArray>::New();
  std::set<std::array<vtkIdType, 3>> seen;
  auto it = vtk::TakeSmartPointer(full->GetPolys()->NewIterator());
  vtkIdType c = 0;
  for (it->GoToFirstCell(); !it->IsDoneWithTraversal(); it->GoToNextCell(), ++c) {
    vtkIdType size;
    const vtkIdType* v;
    it->GetCurrentCell(size, v);
    if (size != 3) continue;
    std::array<vtkIdType, 3> roots = {clusters.root(v[0]), clusters.root(v[1]), clusters.root(v[2])};
    std::array<vtkIdType, 3> key = roots;
    std::sort(key.begin(), key.end());
    if (key[0] == key[1] || key[1] == key[2] || !seen.insert(key).second) continue;
    const vtkIdType t[3] = {coarseVertex(roots[0]), coarseVertex(roots[1]), coarseVertex(roots[2])};
    triangles->InsertNextCell(3, t);
    if (coarseLabels) coarseLabels->InsertNextTuple1(labels->GetTuple1(c));
  }
  auto coarse = vtkSmartPointer<vtkPolyData>::New();
  coarse->SetPoints(points);
  coarse->SetPolys(triangles);
  if (coarseLabels) coarse->GetCellData()->SetScalars(coarseLabels);
  return coarse;
}

}  // namespace repose
