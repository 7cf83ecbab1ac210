#pragma once
// Bone weights as harmonic functions: for each bone j, ΔW_j = 0 with W_j = 1 on bone j's nodes and
// 0 on every other bone's nodes. One factorization of the free-free block, every bone a right-hand side.
#include <string>
#include <vector>

#include "fill_ordering.h"
#include "sparse_weights.h"
#include "tet_mesh.h"

namespace repose {

/// Sparse Cholesky used for the free-free block (both factor once and solve every bone at once).
enum class HarmonicSolver {
  CholmodSupernodal,    ///< SuiteSparse CHOLMOD supernodal LLT (BLAS-backed; fastest, default)
  EigenSimplicialLDLT   ///< Eigen's SimplicialLDLT (no external dependency at run time)
};

struct HarmonicWeightsOptions {
  int maxInfluences = 4;     ///< k largest weights kept per node
  int boneCount = 0;         ///< number of bones (joints); fixedBone values lie in [0, boneCount)
  HarmonicSolver solver = HarmonicSolver::CholmodSupernodal;
  FillOrdering ordering = FillOrdering::Automatic;  ///< CHOLMOD's fill-reducing ordering
};

struct HarmonicWeightsReport {
  double minRawWeight = 0;   ///< smallest weight before clamping (negative if the mesh violates the maximum principle)
  double maxRawWeight = 0;
  double maxSumError = 0;    ///< max_i |Σ_j w_ij - 1| of the full (dense) solution
  int freeNodes = 0;
  int fixedNodes = 0;
  std::string solver;        ///< e.g. "CHOLMOD supernodal LLT"
  std::string ordering;      ///< the fill-reducing ordering used, e.g. "AMD"
  double factorFlops = 0;    ///< CHOLMOD's count for that ordering (0 for Eigen's solver)
  double factorNonzeros = 0; ///< nnz(L), likewise
  double assembleSeconds = 0;  ///< stiffness matrix, free-free block and right-hand sides
  double analyzeSeconds = 0;   ///< ordering and symbolic analysis
  double factorSeconds = 0;    ///< analysis and numeric factorization
  double solveSeconds = 0;     ///< every bone's right-hand side
  double selectSeconds = 0;    ///< top-k extraction and renormalisation
};

/// Raw harmonic solution, for tests and diagnostics: #V by boneCount, row-major, fixed nodes hold
/// their indicator rows. Same checks and solver as harmonicWeights.
std::vector<double> harmonicWeightsDense(const TetMesh& mesh, const HarmonicWeightsOptions& options,
                                         HarmonicWeightsReport* report = nullptr);

/// mesh.fixedBone gives the Dirichlet nodes. Throws std::invalid_argument if a bone has no node,
/// or a free node is not connected to any fixed node (the system would be singular).
SparseWeights harmonicWeights(const TetMesh& mesh, const HarmonicWeightsOptions& options,
                              HarmonicWeightsReport* report = nullptr);

}  // namespace repose
