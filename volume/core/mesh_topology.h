#pragma once
// Triangle soups as they come from files: are they closed, and which separate pieces do they hold?
#include <Eigen/Core>
#include <cstddef>
#include <vector>

namespace repose {

/// V  #V by 3 vertex positions (row-major, one vertex a row).
using MeshVertices = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
/// F  #F by 3 vertex indices of triangles, 0-based.
using MeshTriangles = Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor>;

struct TriangleMesh {
  MeshVertices V;
  MeshTriangles F;
};

struct MeshTopology {
  std::size_t vertices = 0, triangles = 0;
  std::size_t boundaryEdges = 0;        ///< edges of one triangle only: the rims of holes
  std::size_t nonManifoldEdges = 0;     ///< edges shared by three or more triangles
  std::size_t degenerateTriangles = 0;  ///< triangles repeating a vertex index
  std::size_t components = 0;           ///< pieces connected through shared vertices
  /// |signed volume| by the divergence theorem about the vertex centroid: the enclosed volume of a
  /// closed, consistently oriented surface; only an estimate when the surface has holes.
  double enclosedVolume = 0;
  bool closed() const { return boundaryEdges == 0 && nonManifoldEdges == 0; }
};

/// Throws std::invalid_argument naming the first triangle whose vertex index is out of range.
void checkTriangleIndices(const MeshVertices& V, const MeshTriangles& F);

/// Edge and component statistics of a triangle soup. Coincident vertices (same coordinates) count
/// as one, so a soup that repeats its vertices per triangle (STL) is analysed as a connected surface.
/// Throws std::invalid_argument on an index out of range.
MeshTopology analyzeMeshTopology(const MeshVertices& V, const MeshTriangles& F);

/// Splits a triangle soup into its connected pieces (triangles connected through shared, or
/// coincident, vertices). Each piece keeps only the vertices it uses. Order: by each piece's first
/// triangle in F, so the result follows the file. Degenerate-only pieces are kept.
/// Throws std::invalid_argument on an index out of range.
std::vector<TriangleMesh> splitConnectedComponents(const MeshVertices& V, const MeshTriangles& F);

}  // namespace repose
