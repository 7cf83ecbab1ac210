#pragma once
// Posing arbitrary meshes (organs, vessels, nerves, a catheter path) with a prepared case: each
// vertex is bound once to the rest tet mesh by vtkReposeSurfaceBinding (the containing tet, or the
// nearest tet's barycentric extrapolation outside the body) and then moves with the posed tet mesh
// through vtkReposeSurfaceDeformer. Bindings are cached on disk, keyed by the mesh's vertex
// coordinates, so posing the same mesh again skips the binding.
#include <memory>
#include <string>
#include <vector>

#include <vtkSmartPointer.h>

#include "barycentric_binding.h"

class vtkPolyData;
class vtkUnstructuredGrid;

namespace repose {

/// "dir/liver.obj" -> "posed_liver.obj": the output keeps the input's file name and format.
std::string posedMeshName(const std::string& path);

struct PoseableMesh {
  std::string path;            ///< input file
  vtkSmartPointer<vtkPolyData> rest;
  vtkSmartPointer<vtkPolyData> bound;  ///< `rest` with the binding: BoundTet, BoundWeights (vtkReposeSurfaceBinding)
  std::size_t outside = 0;     ///< vertices outside the body (nearest-tet extrapolation)
  bool fromCache = false;      ///< binding read from the cache rather than computed
  double bindSeconds = 0;      ///< time to bind, or to read the cached binding
  std::string cachePath;       ///< the cache file ("" without a cache folder)
  std::string cacheWarning;    ///< why the binding could not be cached ("" when it was)
};

/// Binds meshes to one rest tet mesh and poses them with the posed tet mesh.
class MeshPoser {
public:
  /// `restMesh`: the case's rest tet mesh (every cell a 4-node tet). Throws std::runtime_error otherwise.
  explicit MeshPoser(vtkUnstructuredGrid* restMesh);
  ~MeshPoser();
  MeshPoser(const MeshPoser&) = delete;
  MeshPoser& operator=(const MeshPoser&) = delete;

  /// Reads `path` (readPolyData in mesh_io.h) and binds it, through the cache folder `cacheDir` ("" = no
  /// cache): the cache file is `cacheDir/<file stem>-<hash of the vertex coordinates>.bin`, holding
  /// the rest mesh's fingerprint too, so a changed mesh or a re-prepared case is bound again. A
  /// folder that cannot be written only costs the cache (cacheWarning says why).
  const PoseableMesh& add(const std::string& path, const std::string& cacheDir);
  const std::vector<PoseableMesh>& meshes() const { return meshes_; }

  /// Mesh `i` with its vertices moved by `posedMesh` (the rest mesh's nodes posed, same node order);
  /// cells, point and cell data are kept, normals recomputed for polygon meshes that had them.
  vtkSmartPointer<vtkPolyData> pose(std::size_t i, vtkUnstructuredGrid* posedMesh) const;

private:
  struct Rest;
  std::unique_ptr<Rest> rest_;
  std::vector<PoseableMesh> meshes_;
};

}  // namespace repose
