#pragma once
// Two-level preconditioner for the block CG of elasticity systems, additive:
//   M^-1 = D^-1 + P Ac^-1 P^T,   Ac = P^T A P,
// block Jacobi D^-1 on the fine level plus an exact solve on a coarse space P of rigid-body modes
// (3 translations + 3 infinitesimal rotations) of node aggregates. Block Jacobi alone damps only
// local error; the smooth, nearly rigid error of large regions is what makes its CG need hundreds
// of iterations, and the coarse space removes it. (A symmetric V-cycle, damped block-Jacobi pre- and
// post-smoothing around the coarse correction, halves the iterations but costs three products with
// A per iteration instead of one: slower overall.)
// A low-rank term of the matrix (BlockSparseMatrix3f::lowRank) joins D exactly, by Woodbury's
// identity: M^-1 = (D + G K G^T)^-1 + P Ac^-1 P^T. Its few large eigenvalues (a region's volume
// stiffness acts on its whole surface at once) would otherwise each cost CG iterations.
#include <Eigen/Core>
#include <memory>
#include <vector>

#include "block_sparse_cg.h"
#include "tet_mesh.h"

namespace repose {

class TwoLevelPreconditioner : public BlockPreconditioner {
 public:
  TwoLevelPreconditioner();
  ~TwoLevelPreconditioner() override;

  /// Groups the matrix's block rows (nodes, at positions: one row per block row) into aggregates:
  /// the connected parts (in A's pattern) of the cells of a regular grid whose cell size gives about
  /// targetSize nodes per aggregate; aggregates of less than an eighth of that join their most
  /// connected neighbour. Depends on the pattern only, so it is done once for a fixed pattern.
  /// The matrix may be upper-stored (BlockSparseMatrix3f::upper); update() then takes the same kind.
  void aggregate(const BlockSparseMatrix3f& pattern, const Points& positions, int targetSize);
  bool aggregated() const;
  int aggregates() const;
  int coarseSize() const;  ///< rows of the coarse matrix

  /// Prepares for A (same pattern as given to aggregate): block-Jacobi inverses, the rigid modes
  /// about the aggregates' centroids at positions (the current pose: modes of the rotated aggregate),
  /// Ac = P^T A P and its Cholesky factorization (the symbolic analysis is kept for later calls).
  /// A singular Ac (A only semi-definite) is factorized with a small diagonal shift instead. If even
  /// a shift of 1e-2 of Ac's mean diagonal does not factorize, the coarse level is left out until the
  /// next update (coarseUsed() false): M^-1 = D^-1 alone.
  void update(const BlockSparseMatrix3f& A, const Points& positions);
  /// The diagonal shift of the last update's coarse factorization (0: none was needed).
  double coarseShift() const;
  /// Whether the last update's preconditioner has its coarse level (false after updateFine()).
  bool coarseUsed() const;
  /// Prepares for A without the coarse level: M^-1 = D^-1 alone (block Jacobi).
  void updateFine(const BlockSparseMatrix3f& A);
  /// Prepares for A's fine level (block-Jacobi inverses, low-rank term) and keeps the coarse level
  /// of the last update(), the rigid modes and factorized Ac of the matrix given there. M^-1 stays
  /// symmetric positive definite, so CG still converges to its tolerance; the coarse correction is
  /// only as good as that matrix is close to A (consecutive Newton matrices differ little). Without
  /// a coarse level (coarseUsed() false), the same as updateFine().
  void updateFineKeepingCoarse(const BlockSparseMatrix3f& A);

  double apply(const Eigen::VectorXd& r, Eigen::VectorXd& z) const override;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace repose
