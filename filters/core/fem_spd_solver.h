#pragma once
// The corotational FEM's linear solves (internal to corotational_fem): each Newton step's or outer
// iteration's SPD system over the free nodes, by the solver CorotationalOptions::preconditioner picks.
#include <Eigen/CholmodSupport>
#include <Eigen/Sparse>
#include <vector>

#include "block_sparse_cg.h"
#include "corotational_fem.h"
#include "tet_mesh.h"
#include "two_level_preconditioner.h"

namespace repose {
namespace fem {

using SpMat = Eigen::SparseMatrix<double>;

/// Solves the SPD system A x = b (x in: the guess) with the chosen method; for CHOLMOD the symbolic
/// analysis of the fixed pattern is done once and reused by later calls.
class SpdSolver {
 public:
  explicit SpdSolver(const CorotationalOptions& o) : options_(o) {}

  /// The nodes behind the unknowns (TwoLevel's aggregates and rigid modes): rest and current
  /// positions of all nodes (current may change between solves) and the free node of each block row.
  void setNodes(const Points& rest, const Points& current, const std::vector<int>& freeNodes) {
    rest_ = &rest;
    current_ = &current;
    freeNodes_ = &freeNodes;
  }
  /// A low-rank term added to the matrices given to solve() (BlockJacobi and TwoLevel only).
  void setLowRank(const LowRankTerm3* lowRank) { lowRank_ = lowRank; }

  /// Block CG on float blocks (BlockJacobi and TwoLevel), the residual of the guess in H's own
  /// precision (exact when x = 0, as in Newton's solves).
  void solve(BlockSparseMatrix3f& H, const Eigen::VectorXd& b, Eigen::VectorXd& x, double tolerance, int& iterations,
             double& residual);
  /// CHOLMOD, incomplete-Cholesky CG or Jacobi CG on A with both triangles stored.
  void solve(const SpMat& A, const Eigen::VectorXd& b, Eigen::VectorXd& x, double tolerance, int& iterations,
             double& residual);
  /// x += the block CG's solution of H dx = r0 (r0 = b - A x, e.g. summed in double by the caller),
  /// to tolerance relative to |b|.
  void solveCorrection(const BlockSparseMatrix3f& H, const Eigen::VectorXd& b, const Eigen::VectorXd& r0,
                       Eigen::VectorXd& x, double tolerance, int& iterations, double& residual);

 private:
  void solveCholmod(const SpMat& A, const Eigen::VectorXd& b, Eigen::VectorXd& x, int& iterations, double& residual);
  void solveIncompleteCholesky(const SpMat& A, const Eigen::VectorXd& b, Eigen::VectorXd& x, double tolerance,
                               int& iterations, double& residual);
  Points freePositions(const Points& all) const;
  /// Aggregates from the rest pose once (the pattern is fixed), the coarse matrix per solve.
  void prepareTwoLevel(const BlockSparseMatrix3f& H);

  const CorotationalOptions& options_;
  Eigen::CholmodSupernodalLLT<SpMat, Eigen::Lower> cholmod_;
  bool analyzed_ = false;
  TwoLevelPreconditioner twoLevel_;
  int solvesOnCoarse_ = 0;  // solves that have used twoLevel_'s coarse level (see coarseRefreshInterval)
  const Points* rest_ = nullptr;
  const Points* current_ = nullptr;
  const std::vector<int>* freeNodes_ = nullptr;
  const LowRankTerm3* lowRank_ = nullptr;
};

}  // namespace fem
}  // namespace repose
