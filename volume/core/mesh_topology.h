#pragma once
// Triangle soups as they come from files: are they closed, and which separate pieces do they hold?
#include <Eigen/Core>
#include <array>
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
  std::size_t pieces = 0;               ///< pieces as stored (see meshPieces): overlapping parts count apart
  std::size_t holes = 0;                ///< loops of boundary edges (see boundaryLoops)
  double largestHole = 0;               ///< the widest hole: largest distance between two points of its rim
  /// |signed volume| by the divergence theorem: the enclosed volume of a closed, consistently
  /// oriented surface; with holes, of the surface closed by a fan over each hole (an estimate).
  /// Overlapping pieces count twice where they overlap.
  double enclosedVolume = 0;
  bool closed() const { return boundaryEdges == 0 && nonManifoldEdges == 0; }
};

/// Throws std::invalid_argument naming the first triangle whose vertex index is out of range.
void checkTriangleIndices(const MeshVertices& V, const MeshTriangles& F);

/// Edge and component statistics of a triangle soup. Coincident vertices (same coordinates) count
/// as one, so a soup that repeats its vertices per triangle (STL) is analysed as a connected surface.
/// Throws std::invalid_argument on an index out of range.
MeshTopology analyzeMeshTopology(const MeshVertices& V, const MeshTriangles& F);

/// Rims of the holes: loops of boundary edges, each the vertex indices in the order the triangles
/// orient them (coincident vertices merged: an index is the first vertex with those coordinates).
/// A rim that does not close (inconsistent orientation) is returned as the open chain it is.
/// Throws std::invalid_argument on an index out of range.
std::vector<std::vector<int>> boundaryLoops(const MeshVertices& V, const MeshTriangles& F);

/// The soup's boundary as a chain: directed edges {from, to} that the triangles leave uncancelled
/// (an edge run one way by m triangles and the other way by n is listed |m - n| times, in the
/// direction of the majority; coincident vertices merged, an index being the first vertex with those
/// coordinates). Empty for closed, consistently oriented surfaces, overlapping closed pieces
/// included; holes give their rims, orientation seams their edges twice. Returned as its connected
/// pieces (edges sharing a vertex), ordered by their smallest edge.
/// Throws std::invalid_argument on an index out of range.
std::vector<std::vector<std::array<int, 2>>> boundaryChain(const MeshVertices& V, const MeshTriangles& F);

/// Piece (0-based, numbered in file order) of every triangle, and the number of pieces in `count`.
/// Triangles are in one piece when they share an edge by vertex indices, or an edge (coincident
/// vertices merged) that only they two share. So closed parts stored apart that overlap and meet
/// along coincident edges (non-manifold there) stay apart, while a soup storing every corner apart
/// (STL) is still one piece. Throws std::invalid_argument on an index out of range.
std::vector<int> meshPieces(const MeshVertices& V, const MeshTriangles& F, std::size_t& count);

/// F with triangles turned where needed so that the two triangles of every manifold edge
/// (coincident vertices merged) run it in opposite directions, spreading from the first triangle of
/// each connected surface: an export with mixed windings becomes consistently oriented. `turned`
/// counts the triangles turned. A non-orientable surface keeps the orientation first reached.
/// Throws std::invalid_argument on an index out of range.
MeshTriangles consistentlyOriented(const MeshVertices& V, const MeshTriangles& F, std::size_t& turned);

/// Splits a triangle soup into its connected pieces (triangles connected through shared, or
/// coincident, vertices). Each piece keeps only the vertices it uses. Order: by each piece's first
/// triangle in F, so the result follows the file. Degenerate-only pieces are kept.
/// Throws std::invalid_argument on an index out of range.
std::vector<TriangleMesh> splitConnectedComponents(const MeshVertices& V, const MeshTriangles& F);

}  // namespace repose
