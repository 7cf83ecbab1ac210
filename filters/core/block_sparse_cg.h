#pragma once
// Conjugate gradients on a symmetric positive (semi-)definite matrix of 3x3 blocks, one block row
// per free node: the linear systems of the FEM relaxation. The matrix is stored in float with one
// column index per block, a third of the memory traffic of a scalar double CSR matrix, which bounds
// the matrix-vector product that dominates CG; vectors and sums stay in double.
#include <Eigen/Core>
#include <vector>

namespace repose {

/// A symmetric positive semi-definite term of low rank, sum_r weight[r] g_r g_r^T, with each g_r
/// sparse over the block rows: the coupling of a region-volume energy, which makes every node of a
/// region's surface interact with every other (dense as blocks, a handful of vectors as a sum).
struct LowRankTerm3 {
  std::vector<int> rowStart;   ///< #rows + 1: entries of block row i are [rowStart[i], rowStart[i + 1])
  std::vector<int> term;       ///< the r of each entry
  std::vector<double> vector;  ///< 3 per entry: the block row's part of g_r
  std::vector<double> weight;  ///< per term
  bool empty() const { return weight.empty(); }
  /// y += sum_r weight[r] g_r (g_r . x), threaded.
  void multiplyAdd(const Eigen::VectorXd& x, Eigen::VectorXd& y) const;
};

struct BlockSparseMatrix3f {
  std::vector<int> rowStart;   ///< #rows + 1: blocks of block row i are [rowStart[i], rowStart[i + 1])
  std::vector<int> column;     ///< block column of each block, ascending within a row
  std::vector<float> values;   ///< 9 per block, row-major
  /// Only the blocks with column >= row are stored (each row starts with its diagonal block) and
  /// the matrix is their symmetric completion: half the memory, and half the traffic of multiply().
  bool upper = false;
  /// Optional: added to the blocks by multiply() (not seen by the block-diagonal preconditioners).
  const LowRankTerm3* lowRank = nullptr;
  int rows() const { return rowStart.empty() ? 0 : int(rowStart.size()) - 1; }
  /// y = A x (x, y: 3 * rows()), threaded over block rows.
  void multiply(const Eigen::VectorXd& x, Eigen::VectorXd& y) const;

 private:
  void multiplyUpper(const Eigen::VectorXd& x, Eigen::VectorXd& y) const;
  mutable std::vector<double> spill_;  // multiplyUpper's per-chunk sums for later chunks' rows
};

struct BlockCgResult {
  int iterations = 0;
  double relativeResidual = 0.0;  ///< |b - A x| / |b| at exit (the recurrence's residual)
};

/// Inverses of the 3x3 diagonal blocks; a singular block falls back to the inverse of its diagonal.
std::vector<Eigen::Matrix3d> blockDiagonalInverses(const BlockSparseMatrix3f& A);

/// Preconditioned CG with the inverses of the 3x3 diagonal blocks (block Jacobi), warm-started from
/// x; stops when |r| <= tolerance |b| or after maxIterations. A singular diagonal block falls back
/// to the inverse of its diagonal.
BlockCgResult blockJacobiCg(const BlockSparseMatrix3f& A, const Eigen::VectorXd& b, Eigen::VectorXd& x,
                            double tolerance, int maxIterations);

/// z = M^-1 r for a symmetric positive definite M (e.g. two_level_preconditioner.h); returns r . z,
/// summed in the pass that writes z (one pass over the vectors less per CG iteration).
class BlockPreconditioner {
 public:
  virtual ~BlockPreconditioner() = default;
  virtual double apply(const Eigen::VectorXd& r, Eigen::VectorXd& z) const = 0;
};

/// The same CG with any preconditioner (the vector updates are threaded but not fused with it).
BlockCgResult preconditionedBlockCg(const BlockSparseMatrix3f& A, const Eigen::VectorXd& b, Eigen::VectorXd& x,
                                    double tolerance, int maxIterations, const BlockPreconditioner& M);

}  // namespace repose
