#include "case_files.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include <vtkCellType.h>
#include <vtkDataArray.h>
#include <vtkFloatArray.h>
#include <vtkImageData.h>
#include <vtkIntArray.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLPolyDataReader.h>
#include <vtkXMLUnstructuredGridReader.h>

#include "array_names.h"
#include "filter_errors.h"
#include "mesh_file_claims.h"
#include "mesh_io.h"
#include "scan_files.h"

namespace repose {
namespace {

/// Reads a VTK XML file, its claims checked first; errors name the file on one line.
template <class Reader>
vtkSmartPointer<vtkPointSet> readXmlMesh(const std::string& path) {
  try {
    checkMeshFileClaims(path);
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(path + ": " + e.what());
  }
  auto reader = vtkSmartPointer<Reader>::New();
  reader->SetFileName(path.c_str());
  auto errors = captureErrors(reader);
  reader->Update();
  vtkPointSet* out = vtkPointSet::SafeDownCast(reader->GetOutputDataObject(0));
  if (!errors->last.empty() || !out || out->GetNumberOfPoints() == 0)
    throw std::runtime_error(path + ": cannot read (" + (errors->last.empty() ? "no points" : errors->last) + ")");
  try {
    checkMeshContents(out);
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(path + ": " + e.what());
  }
  vtkSmartPointer<vtkPointSet> copy;
  copy.TakeReference(out->NewInstance());
  copy->ShallowCopy(out);
  return copy;
}

/// The array `name` of `data` with `components` components and `tuples` tuples, or an error.
vtkDataArray* caseArray(vtkFieldData* data, const char* name, int components, vtkIdType tuples,
                        const std::string& path) {
  vtkDataArray* a = vtkDataArray::SafeDownCast(data->GetAbstractArray(name));
  if (!a || a->GetNumberOfComponents() != components || a->GetNumberOfTuples() != tuples)
    throw std::runtime_error(path + ": array " + name + " is missing or not " + std::to_string(tuples) + " x " +
                             std::to_string(components) + " (not a prepared case file, or a damaged one)");
  return a;
}

std::string shortNumber(double v) {
  std::ostringstream text;
  text << v;
  return text.str();
}

/// Every value of `a` finite and, when lo <= hi, within [lo, hi].
void requireValues(vtkDataArray* a, double lo, double hi, const std::string& path) {
  for (vtkIdType i = 0, n = a->GetNumberOfTuples(); i < n; ++i)
    for (int c = 0; c < a->GetNumberOfComponents(); ++c) {
      const double v = a->GetComponent(i, c);
      if (!std::isfinite(v) || (lo <= hi && (v < lo || v > hi)))
        throw std::runtime_error(path + ": array " + a->GetName() + " holds " + shortNumber(v) + " at tuple " +
                                 std::to_string(i) + (lo <= hi ? " (expected " + std::to_string(int(lo)) + ".." +
                                                                     std::to_string(int(hi)) + ")"
                                                               : std::string(" (not finite)")));
    }
}

}  // namespace

std::string brief(const Json::Value& value) {
  Json::StreamWriterBuilder builder;
  builder["indentation"] = "";
  const std::string text = Json::writeString(builder, value);
  return text.size() > 40 ? text.substr(0, 40) + "..." : text;
}

std::string caseFile(const std::string& caseDir, const Json::Value& manifest, const char* key,
                     const std::string& manifestPath) {
  const Json::Value& name = manifest[key];
  const std::string text = name.isString() ? name.asString() : std::string();
  if (text.empty() || text == "." || text == ".." || text.find_first_of("/\\") != std::string::npos)
    throw std::runtime_error(manifestPath + ": \"" + key + "\" must name a file inside the case folder, not '" +
                             (name.isString() ? text : brief(name)) + "'");
  return caseDir + "/" + text;
}

vtkSmartPointer<vtkUnstructuredGrid> readCaseMesh(const std::string& path, const Json::Value& manifest,
                                                  const std::string& manifestPath, const Skeleton& skeleton) {
  auto mesh = vtkSmartPointer<vtkUnstructuredGrid>::New();
  mesh->ShallowCopy(readXmlMesh<vtkXMLUnstructuredGridReader>(path));
  if (!manifest["nodes"].isIntegral() || manifest["nodes"].asLargestInt() != mesh->GetNumberOfPoints() ||
      !manifest["tets"].isIntegral() || manifest["tets"].asLargestInt() != mesh->GetNumberOfCells())
    throw std::runtime_error(manifestPath + ": says " + brief(manifest["nodes"]) +
                             " nodes and " + brief(manifest["tets"]) + " tets, " + path +
                             " has " + std::to_string(mesh->GetNumberOfPoints()) + " and " +
                             std::to_string(mesh->GetNumberOfCells()));
  for (vtkIdType c = 0, n = mesh->GetNumberOfCells(); c < n; ++c)
    if (mesh->GetCellType(c) != VTK_TETRA)
      throw std::runtime_error(path + ": cell " + std::to_string(c) + " is not a tetrahedron");
  const vtkIdType nodes = mesh->GetNumberOfPoints();
  vtkDataArray* weights = vtkDataArray::SafeDownCast(mesh->GetPointData()->GetAbstractArray(repose::arrays::kWeights));
  const int influences = weights ? weights->GetNumberOfComponents() : 1;
  requireValues(caseArray(mesh->GetPointData(), repose::arrays::kWeights, influences, nodes, path), 0, -1, path);
  const double lastBone = double(skeleton.joints.size()) - 1;
  requireValues(caseArray(mesh->GetPointData(), repose::arrays::kBoneIds, influences, nodes, path), 0, lastBone, path);
  requireValues(caseArray(mesh->GetPointData(), repose::arrays::kFixedBone, 1, nodes, path), -1, lastBone, path);
  return mesh;
}

vtkSmartPointer<vtkPolyData> readCaseSurfaces(const std::string& path, vtkIdType tets) {
  auto surfaces = vtkSmartPointer<vtkPolyData>::New();
  surfaces->ShallowCopy(readXmlMesh<vtkXMLPolyDataReader>(path));
  const vtkIdType n = surfaces->GetNumberOfPoints();
  requireValues(caseArray(surfaces->GetPointData(), repose::arrays::kBoundTet, 1, n, path), 0, double(tets) - 1, path);
  requireValues(caseArray(surfaces->GetPointData(), repose::arrays::kBoundWeights, 4, n, path), 0, -1, path);
  if (!vtkIntArray::SafeDownCast(surfaces->GetPointData()->GetArray(repose::arrays::kBoundTet)) ||
      !vtkFloatArray::SafeDownCast(surfaces->GetPointData()->GetArray(repose::arrays::kBoundWeights)))
    throw std::runtime_error(path + ": BoundTet must be int32 and BoundWeights float32");
  return surfaces;
}

void checkMeshOnGrid(vtkPointSet* mesh, const std::string& meshPath, vtkImageData* labels,
                     const std::string& labelsPath) {
  int dims[3];
  double spacing[3];
  labels->GetDimensions(dims);
  labels->GetSpacing(spacing);
  double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
  for (int corner = 0; corner < 8; ++corner) {
    const double ijk[3] = {corner & 1 ? dims[0] - 1.0 : 0.0, corner & 2 ? dims[1] - 1.0 : 0.0,
                           corner & 4 ? dims[2] - 1.0 : 0.0};
    double xyz[3];
    labels->TransformContinuousIndexToPhysicalPoint(ijk, xyz);
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], xyz[a]), hi[a] = std::max(hi[a], xyz[a]);
  }
  const double margin = 0.25 * std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]}) +
                        3 * std::max({spacing[0], spacing[1], spacing[2]});
  double b[6];
  mesh->GetBounds(b);
  for (int a = 0; a < 3; ++a)
    if (b[2 * a] < lo[a] - margin || b[2 * a + 1] > hi[a] + margin)
      throw std::runtime_error(labelsPath + ": its grid (" + describeGrid(labels) + ") does not hold " + meshPath +
                               " (the case's labels and mesh come from different scans)");
}

}  // namespace repose
