#include "mesh_io.h"
#include "checked_write.h"

#include "mesh_file_claims.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <stdexcept>

#include <vtkCellArray.h>
#include <vtkDataArray.h>
#include <vtkIdList.h>
#include <vtkPoints.h>
#include <vtkOBJReader.h>
#include <vtkOBJWriter.h>
#include <vtkPLYReader.h>
#include <vtkPLYWriter.h>
#include <vtkPolyData.h>
#include <vtkPolyDataReader.h>
#include <vtkPolyDataWriter.h>
#include <vtkSTLReader.h>
#include <vtkSTLWriter.h>
#include <vtkTriangleFilter.h>
#include <vtkXMLPolyDataReader.h>
#include <vtkXMLPolyDataWriter.h>

namespace repose {
namespace {

std::string lowerExtension(const std::string& path) {
  const auto slash = path.find_last_of('/');
  const auto dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  std::string ext = path.substr(dot);
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

// VTK's readers print errors and return an empty mesh rather than failing: the caller checks the
// result, so a truncated or foreign file gets one message of its own.
template <class Reader>
vtkSmartPointer<vtkPolyData> runReader(const std::string& path) {
  auto reader = vtkSmartPointer<Reader>::New();
  reader->SetFileName(path.c_str());
  // Silenced while it reads, then restored: the flag is global, and the filters' errors after it must
  // still reach their observers (updateOrThrow's one-line messages).
  const int display = vtkObject::GetGlobalWarningDisplay();
  vtkObject::GlobalWarningDisplayOff();
  reader->Update();
  vtkObject::SetGlobalWarningDisplay(display);
  auto mesh = vtkSmartPointer<vtkPolyData>::New();
  if (reader->GetOutput()) mesh->ShallowCopy(reader->GetOutput());
  return mesh;
}

}  // namespace

void checkMeshContents(vtkPointSet* mesh) {
  // An array's range skips NaN: look at every coordinate.
  vtkDataArray* points = mesh->GetPoints()->GetData();
  const vtkIdType n = mesh->GetNumberOfPoints();
  for (vtkIdType i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c)
      if (!std::isfinite(points->GetComponent(i, c)))
        throw std::runtime_error("vertex " + std::to_string(i) + " has a non-finite coordinate");
  auto ids = vtkSmartPointer<vtkIdList>::New();
  for (vtkIdType c = 0, cells = mesh->GetNumberOfCells(); c < cells; ++c) {
    mesh->GetCellPoints(c, ids);
    for (vtkIdType k = 0; k < ids->GetNumberOfIds(); ++k)
      if (ids->GetId(k) < 0 || ids->GetId(k) >= n)
        throw std::runtime_error("cell " + std::to_string(c) + " names point " + std::to_string(ids->GetId(k)) +
                                 ", the mesh has " + std::to_string(n));
  }
}

bool isSurfaceMeshPath(const std::string& path) {
  const std::string ext = lowerExtension(path);
  return ext == ".obj" || ext == ".stl" || ext == ".ply" || ext == ".vtp" || ext == ".vtk";
}

vtkSmartPointer<vtkPolyData> readPolyData(const std::string& path) {
  const std::string ext = lowerExtension(path);
  if (!isSurfaceMeshPath(path))
    throw std::runtime_error(path + ": unknown mesh format '" + ext + "' (expected .obj, .stl, .ply, .vtp or .vtk)");
  if (!std::ifstream(path).good()) throw std::runtime_error(path + ": no such file");
  try {
    checkMeshFileClaims(path);
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(path + ": " + e.what());
  }
  vtkSmartPointer<vtkPolyData> mesh;
  if (ext == ".obj")
    mesh = runReader<vtkOBJReader>(path);
  else if (ext == ".stl")
    mesh = runReader<vtkSTLReader>(path);
  else if (ext == ".ply")
    mesh = runReader<vtkPLYReader>(path);
  else if (ext == ".vtp")
    mesh = runReader<vtkXMLPolyDataReader>(path);
  else
    mesh = runReader<vtkPolyDataReader>(path);
  if (mesh->GetNumberOfPoints() == 0) throw std::runtime_error(path + ": cannot read a mesh (no points)");
  try {
    checkMeshContents(mesh);
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(path + ": " + e.what());
  }
  return mesh;
}

vtkSmartPointer<vtkPolyData> readSurfaceMesh(const std::string& path) {
  vtkSmartPointer<vtkPolyData> mesh = readPolyData(path);
  if (mesh->GetNumberOfPolys() + mesh->GetNumberOfStrips() == 0)
    throw std::runtime_error(path + ": has no polygons (a surface mesh is needed)");
  auto triangles = vtkSmartPointer<vtkTriangleFilter>::New();
  triangles->SetInputData(mesh);
  triangles->PassVertsOff();
  triangles->PassLinesOff();
  triangles->Update();
  auto out = vtkSmartPointer<vtkPolyData>::New();
  out->ShallowCopy(triangles->GetOutput());
  return out;
}

void writeSurfaceMesh(vtkPolyData* mesh, const std::string& path) {
  const std::string ext = lowerExtension(path);
  if (ext == ".obj") {
    auto w = vtkSmartPointer<vtkOBJWriter>::New();
    w->SetFileName(path.c_str());
    w->SetInputData(mesh);
    writeChecked(w.Get(), path, "");
  } else if (ext == ".stl") {
    auto w = vtkSmartPointer<vtkSTLWriter>::New();
    w->SetFileName(path.c_str());
    w->SetInputData(mesh);
    w->SetFileTypeToBinary();
    writeChecked(w.Get(), path, "");
  } else if (ext == ".ply") {
    auto w = vtkSmartPointer<vtkPLYWriter>::New();
    w->SetFileName(path.c_str());
    w->SetInputData(mesh);
    w->SetFileTypeToBinary();
    writeChecked(w.Get(), path, "");
  } else if (ext == ".vtp") {
    writeVtkXml<vtkXMLPolyDataWriter>(mesh, path);
  } else if (ext == ".vtk") {
    auto w = vtkSmartPointer<vtkPolyDataWriter>::New();
    w->SetFileName(path.c_str());
    w->SetInputData(mesh);
    w->SetFileTypeToBinary();
    writeChecked(w.Get(), path, "");
  } else {
    throw std::runtime_error(path + ": unknown surface format (expected .obj, .stl, .ply, .vtp or .vtk)");
  }
}

}  // namespace repose
