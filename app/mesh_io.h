#pragma once
// Surface meshes in and out in the formats anatomy and character meshes come in: OBJ, STL, PLY,
// VTK XML (.vtp) and legacy VTK (.vtk). The format follows the file's extension.
#include <string>

#include <vtkSmartPointer.h>

class vtkPointSet;
class vtkPolyData;

namespace repose {

/// True when the extension names a surface format read and written here.
bool isSurfaceMeshPath(const std::string& path);
/// Checks what a reader cannot: every coordinate finite, every cell's point ids in range. Throws
/// std::runtime_error with a short reason (no file name).
void checkMeshContents(vtkPointSet* mesh);
/// Reads a mesh keeping what it has: vertices, lines (polylines), polygons, strips, point and cell
/// data; a point set without cells is accepted. Throws std::runtime_error "FILE: problem" (missing,
/// unknown extension, unreadable, counts the file cannot hold, truncated, no points, non-finite
/// coordinates, cells naming missing points); see checkMeshFileClaims.
vtkSmartPointer<vtkPolyData> readPolyData(const std::string& path);
/// Reads a surface mesh (polygons are triangulated; points without polygons are an error).
/// Throws std::runtime_error "FILE: problem" (missing, unknown extension, unreadable, no polygons).
vtkSmartPointer<vtkPolyData> readSurfaceMesh(const std::string& path);
/// Writes a surface mesh in the format of the extension. Throws std::runtime_error naming the file.
/// OBJ and STL keep geometry only; PLY, VTP and VTK keep point and cell data too.
void writeSurfaceMesh(vtkPolyData* mesh, const std::string& path);

}  // namespace repose
