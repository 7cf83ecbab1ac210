#pragma once
// A prepared case folder's files read back with every claim checked (manifest, mesh, surfaces, the
// labels' grid against the mesh), so a damaged or mismatched case is one error naming the file.
#include <string>

#include <json/json.h>
#include <vtkSmartPointer.h>

#include "skeleton.h"

class vtkImageData;
class vtkPointSet;
class vtkPolyData;
class vtkUnstructuredGrid;

namespace repose {

/// manifest.json's "version" this build writes and reads.
constexpr int kCaseVersion = 1;

/// A JSON value as a short one-line text for messages.
std::string brief(const Json::Value& value);
/// A file named by the case manifest: a plain name inside the case folder, never a path leaving it.
std::string caseFile(const std::string& caseDir, const Json::Value& manifest, const char* key,
                     const std::string& manifestPath);
/// mesh.vtu: the manifest's node and tet counts, tets only, Weights/BoneIds/FixedBone in range.
vtkSmartPointer<vtkUnstructuredGrid> readCaseMesh(const std::string& path, const Json::Value& manifest,
                                                  const std::string& manifestPath, const Skeleton& skeleton);
/// surfaces.vtp: BoundTet (int32, a tet of the mesh) and BoundWeights (4 float32) on every point.
vtkSmartPointer<vtkPolyData> readCaseSurfaces(const std::string& path, vtkIdType tets);
/// The tet mesh was made from the label volume: its nodes lie within the volume's box, give or take
/// the meshing grid's coarser voxels (a quarter of the box, and three voxels, of margin). A case
/// whose labels lie elsewhere than its mesh (another scan's, or a moved grid) is refused.
void checkMeshOnGrid(vtkPointSet* mesh, const std::string& meshPath, vtkImageData* labels,
                     const std::string& labelsPath);

}  // namespace repose
