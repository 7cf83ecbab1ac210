#pragma once
// The coarse copy of a surface drawn while the user drags a bone (software OpenGL draws about 1-2 M
// triangles per second per core). Its vertices are a subset of the full surface's, so posing it is a
// gather of the posed full vertices.
#include <vector>

#include <vtkSmartPointer.h>
#include <vtkType.h>

class vtkPolyData;

namespace repose {

/// Vertex clustering on a grid of `divisions` cells along the bounding box's longest side that keeps
/// input vertices; `ids` receives the full-surface vertex of every coarse vertex; cell data (the
/// label) is kept per triangle. A cluster is a piece of surface connected inside its grid cell:
/// vertices of separate parts that share a cell (two thighs, a bone and the skin) are never merged,
/// so no coarse triangle spans between parts, however far apart a pose takes them. (Clustering by
/// cell alone, as vtkQuadricClustering does, joined the inner thighs of the small phantom: a 16 mm
/// edge became 640 mm with the hip flexed.)
vtkSmartPointer<vtkPolyData> decimateKeepingVertices(vtkPolyData* full, int divisions, std::vector<vtkIdType>& ids);

}  // namespace repose
