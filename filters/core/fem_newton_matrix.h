#pragma once
// The corotational FEM's system over the free nodes (internal to corotational_fem): which nodes are
// unknowns, which tets touch each, and the sparse matrix of 3x3 blocks that every Newton step or
// outer iteration refills in place (its pattern is fixed for a solve).
#include <Eigen/Sparse>
#include <cstdint>
#include <vector>

#include "block_sparse_cg.h"
#include "tet_mesh.h"

namespace repose {
namespace fem {

/// The unknowns: the free nodes (fixedBone < 0) that belong to at least one tet (a node in no tet
/// has no stiffness), in node order. nV: the node count.
std::vector<int> unknownNodes(const Tets& tets, const std::vector<int>& fixedBone, Eigen::Index nV);

/// FreeNodeSystem::incColumn's mark for a block the matrix does not store (below the diagonal of an
/// upper one).
constexpr std::uint16_t kNotStored = 0xFFFF;

/// The Newton matrix over the free nodes, block row i for free node i. For the block CG (BlockJacobi,
/// TwoLevel) float 3x3 blocks of the upper triangle, assembled in place: no double matrix to fill and
/// convert, half the blocks to compute, half the traffic per CG product. For CHOLMOD, incomplete
/// Cholesky and Eigen's CG, scalar double CSR with both triangles (symmetric, so column 3i + c holds
/// row 3i + c: block row i's blocks in column order, 3 scalars each).
struct NewtonMatrix {
  bool blocked = false;
  BlockSparseMatrix3f blocks;
  Eigen::SparseMatrix<double> scalar;

  int rowLength(std::size_t i) const {
    return blocked ? blocks.rowStart[i + 1] - blocks.rowStart[i]
                   : (scalar.outerIndexPtr()[3 * i + 1] - scalar.outerIndexPtr()[3 * i]) / 3;
  }
  /// Block row i from rowBlocks: rowLength(i) blocks of 9 doubles (row-major), in column order.
  void setRow(std::size_t i, const double* rowBlocks);
};

/// The free nodes' incident tets and the matrix they fill, for freeNodes = unknownNodes(...).
struct FreeNodeSystem {
  std::vector<int> freeNodes;            ///< #free: the node of each unknown
  std::vector<int> incStart;             ///< #free + 1: free node i's incidences are incStart[i] .. incStart[i + 1]
  std::vector<int> incTet;               ///< per incidence: 4 t + a, the node is corner a of tet t
  std::vector<std::uint16_t> incColumn;  ///< per incidence, 4: where block (a, b) of tet t goes in row i (or kNotStored)
  NewtonMatrix A;                        ///< its values zero until assembled
};

/// Builds the incidences and A's pattern (row i: its free neighbours and itself, sorted; blocked: an
/// upper float matrix). Throws std::invalid_argument if a node has 65535 or more neighbours.
FreeNodeSystem freeNodeSystem(const Tets& tets, const std::vector<int>& fixedBone, std::vector<int> freeNodes,
                              bool blocked);

}  // namespace fem
}  // namespace repose
