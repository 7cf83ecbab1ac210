#pragma once
// Binding of arbitrary points (surface vertices) to the rest tet mesh, and moving them with it.
#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "tet_mesh.h"

namespace repose {

class TetLocator;

using BarycentricCoords = Eigen::Matrix<float, Eigen::Dynamic, 4, Eigen::RowMajor>;  ///< #P by 4

struct Binding {
  std::vector<int> tet;           ///< #P tet index
  BarycentricCoords bary;         ///< #P by 4, sums to 1; negative entries for points outside the mesh
  std::size_t outsideCount = 0;   ///< points not inside any tet (bound to the nearest tet, extrapolated)
};

/// Binds each point to the rest tet containing it, or to the nearest tet (barycentric
/// extrapolation) when it is outside the mesh. Uses a uniform-grid spatial hash; threaded.
Binding bindPoints(const Points& restNodes, const Tets& tets, const Points& points);
/// Same with a locator built once over the rest mesh (binding several point sets to one mesh).
Binding bindPoints(const TetLocator& locator, const Points& points);

/// posedPoints(p) = Σ_a bary(p,a) * posedNodes(tets(tet(p), a)). Threaded. posedPoints is resized.
void applyBinding(const Binding& binding, const Tets& tets, const Points& posedNodes, Points& posedPoints);

/// A binding resolved to node ids, for moving points every pose without touching the tets.
struct NodeBinding {
  std::vector<int> node;    ///< #P*4 node ids of each point's tet
  std::vector<float> bary;  ///< #P*4 barycentric weights
  int maxNode = -1;         ///< largest node id (checked against the posed node count per pose)
  std::size_t pointCount() const { return node.size() / 4; }
};

/// Resolves binding.tet through tets. Throws std::invalid_argument on an invalid tet or node id.
NodeBinding makeNodeBinding(const Binding& binding, const Tets& tets);

/// Float fast path of applyBinding: posedPoints (#P*3 floats, caller-allocated) from posedNodes
/// (nodeCount*3 floats or doubles, x y z per node). Threaded. Throws std::invalid_argument when the
/// binding uses a node >= nodeCount.
void applyBinding(const NodeBinding& binding, const float* posedNodes, std::size_t nodeCount,
                  float* posedPoints);
void applyBinding(const NodeBinding& binding, const double* posedNodes, std::size_t nodeCount,
                  float* posedPoints);

/// Binding cache file I/O (little-endian binary: header with counts and hashes, then #P int32 tet
/// ids and #P by 4 float weights). Writing goes through a temporary name and a rename.
void writeBindingCache(const std::string& path, const Binding& binding, std::uint64_t pointsHash,
                       std::uint64_t meshHash, std::size_t nodeCount, std::size_t tetCount);
/// False (and `binding` untouched) when the file is missing, truncated or made for other points/mesh.
bool readBindingCache(const std::string& path, std::uint64_t pointsHash, std::uint64_t meshHash,
                      std::size_t pointCount, std::size_t nodeCount, std::size_t tetCount, Binding& binding);
/// 64-bit content hash of a buffer (not cryptographic).
std::uint64_t contentHash(const void* data, std::size_t bytes, std::uint64_t seed = 0);

}  // namespace repose
