// The two-level preconditioner of the block CG: against dense solves and block Jacobi.
#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "block_sparse_cg.h"
#include "block_test_systems.h"
#include "corotational_test_meshes.h"
#include "two_level_preconditioner.h"

namespace {

using repose::Points;

TEST(TwoLevelPreconditioner, SolvesAnElasticitySystemLikeADenseSolver) {
  const Box b = makeBox(8, 4, 4, 1.0);
  Points positions;
  const repose::BlockSparseMatrix3f A = clampedBoxStiffness(b, 5.0, 1.0, positions);
  const int n = A.rows();
  const Eigen::VectorXd rhs = gaussianVector(3 * n, 5);
  const Eigen::VectorXd exact = denseOperator(A).ldlt().solve(rhs);
  repose::TwoLevelPreconditioner M;
  M.aggregate(A, positions, 20);
  EXPECT_GT(M.aggregates(), 4);
  EXPECT_LT(M.aggregates(), n / 5);
  M.update(A, positions);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(3 * n);
  const repose::BlockCgResult r = repose::preconditionedBlockCg(A, rhs, x, 1e-10, 1000, M);
  EXPECT_LE(r.relativeResidual, 1e-10);
  EXPECT_GT(r.iterations, 0);
  EXPECT_LT((x - exact).norm(), 1e-7 * exact.norm());
  // A warm start at the solution needs no iteration.
  Eigen::VectorXd warm = exact;
  EXPECT_EQ(repose::preconditionedBlockCg(A, rhs, warm, 1e-6, 1000, M).iterations, 0);
}

// An upper-stored matrix gives the same aggregates, the same coarse matrix (P^T A P from the stored
// blocks and their transposes) and so the same preconditioner and CG.
TEST(TwoLevelPreconditioner, UpperStorageGivesTheSamePreconditioner) {
  const Box b = makeBox(12, 4, 4, 1.0);
  Points positions;
  const repose::BlockSparseMatrix3f A = clampedBoxStiffness(b, 5.0, 1.0, positions);
  const repose::BlockSparseMatrix3f U = upperPart(A);
  const int n = A.rows();
  repose::TwoLevelPreconditioner full, upper;
  full.aggregate(A, positions, 20);
  upper.aggregate(U, positions, 20);
  ASSERT_EQ(upper.aggregates(), full.aggregates());
  ASSERT_EQ(upper.coarseSize(), full.coarseSize());
  EXPECT_GT(full.aggregates(), 4);
  full.update(A, positions);
  upper.update(U, positions);
  std::mt19937 rng(9);
  std::normal_distribution<double> g;
  Eigen::VectorXd r(3 * n), zFull, zUpper;
  for (int i = 0; i < 3 * n; ++i) r(i) = g(rng);
  const double rzFull = full.apply(r, zFull), rzUpper = upper.apply(r, zUpper);
  EXPECT_LT((zUpper - zFull).norm(), 1e-9 * zFull.norm());
  EXPECT_NEAR(rzUpper, rzFull, 1e-9 * std::abs(rzFull));
  Eigen::VectorXd xFull = Eigen::VectorXd::Zero(3 * n), xUpper = xFull;
  const repose::BlockCgResult cgFull = repose::preconditionedBlockCg(A, r, xFull, 1e-10, 1000, full);
  const repose::BlockCgResult cgUpper = repose::preconditionedBlockCg(U, r, xUpper, 1e-10, 1000, upper);
  EXPECT_LE(cgUpper.relativeResidual, 1e-10);
  EXPECT_LE(std::abs(cgUpper.iterations - cgFull.iterations), 1);
  EXPECT_LT((xUpper - xFull).norm(), 1e-8 * xFull.norm());
}

// A block-diagonal matrix plus a low-rank term: the fine level, which takes the term in by
// Woodbury's identity, is then the exact inverse, and CG converges in one iteration.
TEST(TwoLevelPreconditioner, LowRankTermJoinsTheFineLevelExactly) {
  const int n = 50;
  std::mt19937 rng(3);
  std::normal_distribution<double> g;
  repose::BlockSparseMatrix3f A;
  Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(3 * n, 3 * n);
  Points positions(n, 3);
  A.rowStart.push_back(0);
  for (int i = 0; i < n; ++i) {
    Eigen::Matrix3d B;
    for (int k = 0; k < 9; ++k) B(k / 3, k % 3) = g(rng);
    const Eigen::Matrix3d D = B * B.transpose() + Eigen::Matrix3d::Identity();
    A.column.push_back(i);
    for (int k = 0; k < 9; ++k) A.values.push_back(float(D(k / 3, k % 3)));
    dense.block<3, 3>(3 * i, 3 * i) = D.cast<float>().cast<double>();
    A.rowStart.push_back(i + 1);
    positions.row(i) << i, 0.5 * i, 0;
  }
  repose::LowRankTerm3 L;
  L.weight = {1e4, 30.0, 0.0};  // a stiff term, a soft one and an unused one
  Eigen::MatrixXd G = Eigen::MatrixXd::Zero(3 * n, 3);
  L.rowStart.push_back(0);
  for (int i = 0; i < n; ++i) {
    for (int r = 0; r < 3; ++r) {
      if ((r == 0 && i % 2) || (r == 1 && i < n / 3)) continue;
      L.term.push_back(r);
      for (int c = 0; c < 3; ++c) {
        L.vector.push_back(g(rng));
        G(3 * i + c, r) = L.vector.back();
      }
    }
    L.rowStart.push_back(int(L.term.size()));
  }
  dense += G * Eigen::Vector3d(1e4, 30.0, 0.0).asDiagonal() * G.transpose();
  A.lowRank = &L;
  repose::TwoLevelPreconditioner M;
  M.aggregate(A, positions, 10);
  M.updateFine(A);
  Eigen::VectorXd b(3 * n);
  for (int i = 0; i < 3 * n; ++i) b(i) = g(rng);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(3 * n);
  const repose::BlockCgResult r = repose::preconditionedBlockCg(A, b, x, 1e-9, 100, M);
  EXPECT_LE(r.iterations, 2);
  EXPECT_LT((x - dense.ldlt().solve(b)).norm(), 1e-7 * x.norm());
}

// A projected Newton Hessian is only semi-definite. With every block touching a slab of nodes
// zeroed, the slab's aggregates have rigid modes of zero energy and the coarse matrix is singular:
// it is factorized with a small shift, the preconditioner stays positive definite, and CG still
// solves a system with a right-hand side in the matrix's range.
TEST(TwoLevelPreconditioner, SingularCoarseMatrixIsShiftedNotRefused) {
  const Box b = makeBox(12, 4, 4, 1.0);
  Points positions;
  repose::BlockSparseMatrix3f A = clampedBoxStiffness(b, 5.0, 1.0, positions);
  const int n = A.rows();
  std::vector<char> slab(std::size_t(n), 0);
  for (int i = 0; i < n; ++i) slab[std::size_t(i)] = positions(i, 0) > 8.5;
  int zeroed = 0;
  for (int i = 0; i < n; ++i)
    for (int k = A.rowStart[std::size_t(i)]; k < A.rowStart[std::size_t(i) + 1]; ++k)
      if (slab[std::size_t(i)] || slab[std::size_t(A.column[std::size_t(k)])]) {
        std::fill_n(A.values.begin() + 9 * std::ptrdiff_t(k), 9, 0.0f);
        ++zeroed;
      }
  ASSERT_GT(zeroed, 0);
  repose::TwoLevelPreconditioner M;
  M.aggregate(A, positions, 20);
  ASSERT_NO_THROW(M.update(A, positions));
  EXPECT_TRUE(M.coarseUsed());
  EXPECT_GT(M.coarseShift(), 0.0);
  std::mt19937 rng(3);
  std::normal_distribution<double> g;
  Eigen::VectorXd r(3 * n), z;
  for (int trial = 0; trial < 5; ++trial) {
    for (int i = 0; i < 3 * n; ++i) r(i) = g(rng);
    M.apply(r, z);
    EXPECT_GT(r.dot(z), 0.0);
  }
  // A right-hand side in A's range (zero on the slab): CG reaches it.
  Eigen::VectorXd truth(3 * n), rhs;
  for (int i = 0; i < 3 * n; ++i) truth(i) = slab[std::size_t(i / 3)] ? 0.0 : g(rng);
  A.multiply(truth, rhs);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(3 * n), Ax;
  const repose::BlockCgResult result = repose::preconditionedBlockCg(A, rhs, x, 1e-8, 2000, M);
  EXPECT_LE(result.relativeResidual, 1e-8);
  A.multiply(x, Ax);
  EXPECT_LT((Ax - rhs).norm(), 1e-6 * rhs.norm());
  // The unchanged matrix needs no shift (it is reset on every update).
  const repose::BlockSparseMatrix3f K = clampedBoxStiffness(b, 5.0, 1.0, positions);
  M.update(K, positions);
  EXPECT_EQ(M.coarseShift(), 0.0);
}

// The coarse level of one matrix beside the block Jacobi of another (the next Newton matrix): an
// SPD preconditioner still, so CG reaches the new matrix's solution; and the old coarse correction
// still takes the smooth error that block Jacobi alone is slow on.
TEST(TwoLevelPreconditioner, KeptCoarseLevelServesTheNextMatrix) {
  const Box b = makeBox(20, 5, 5, 1.0);
  Points positions;
  const repose::BlockSparseMatrix3f first = clampedBoxStiffness(b, 5.0, 1.0, positions);
  const repose::BlockSparseMatrix3f next = clampedBoxStiffness(b, 8.0, 1.3, positions);
  const int n = next.rows();
  const Eigen::VectorXd rhs = gaussianVector(3 * n, 11);
  const Eigen::VectorXd exact = denseOperator(next).ldlt().solve(rhs);

  repose::TwoLevelPreconditioner fresh, kept;
  fresh.aggregate(next, positions, 30);
  fresh.update(next, positions);
  kept.aggregate(first, positions, 30);
  kept.update(first, positions);
  kept.updateFineKeepingCoarse(next);
  EXPECT_TRUE(kept.coarseUsed());
  Eigen::VectorXd z;
  for (unsigned trial = 0; trial < 5; ++trial) EXPECT_GT(kept.apply(gaussianVector(3 * n, 20 + trial), z), 0.0);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(3 * n);
  const repose::BlockCgResult withKept = repose::preconditionedBlockCg(next, rhs, x, 1e-10, 2000, kept);
  EXPECT_LE(withKept.relativeResidual, 1e-10);
  EXPECT_LT((x - exact).norm(), 1e-7 * exact.norm());
  x.setZero();
  const int withFresh = repose::preconditionedBlockCg(next, rhs, x, 1e-10, 2000, fresh).iterations;
  x.setZero();
  const int jacobi = repose::blockJacobiCg(next, rhs, x, 1e-10, 10000).iterations;
  std::printf("CG iterations: fresh coarse level %d, kept %d, block Jacobi %d\n", withFresh, withKept.iterations, jacobi);
  EXPECT_LT(withKept.iterations, jacobi / 2);
  // After updateFine() there is no coarse level to keep: block Jacobi alone.
  kept.updateFine(first);
  kept.updateFineKeepingCoarse(next);
  EXPECT_FALSE(kept.coarseUsed());
}

TEST(TwoLevelPreconditioner, IndefiniteCoarseMatrixFallsBackToBlockJacobi) {
  // A negated stiffness: Ac is negative definite, which no shift up to 1e-2 of its mean diagonal
  // repairs. The preconditioner is then block Jacobi alone instead of an error.
  const Box b = makeBox(12, 4, 4, 1.0);
  Points positions;
  repose::BlockSparseMatrix3f A = clampedBoxStiffness(b, 5.0, 1.0, positions);
  const int n = A.rows();
  for (float& v : A.values) v = -v;
  repose::TwoLevelPreconditioner M, jacobi;
  M.aggregate(A, positions, 20);
  jacobi.aggregate(A, positions, 20);
  ASSERT_NO_THROW(M.update(A, positions));
  EXPECT_FALSE(M.coarseUsed());
  jacobi.updateFine(A);
  std::mt19937 rng(5);
  std::normal_distribution<double> g;
  Eigen::VectorXd r(3 * n), z, zJacobi;
  for (int i = 0; i < 3 * n; ++i) r(i) = g(rng);
  EXPECT_EQ(M.apply(r, z), jacobi.apply(r, zJacobi));
  EXPECT_EQ((z - zJacobi).norm(), 0.0);
  // The next update with a definite matrix has its coarse level again.
  const repose::BlockSparseMatrix3f K = clampedBoxStiffness(b, 5.0, 1.0, positions);
  M.update(K, positions);
  EXPECT_TRUE(M.coarseUsed());
  M.apply(r, z);
  jacobi.updateFine(K);
  jacobi.apply(r, zJacobi);
  EXPECT_GT((z - zJacobi).norm(), 1e-6 * z.norm());
}

// The coarse space takes the smooth error that block Jacobi is slow on: far fewer iterations on a
// long clamped bar.
TEST(TwoLevelPreconditioner, NeedsFewerIterationsThanBlockJacobi) {
  const Box b = makeBox(40, 8, 8, 1.0);
  Points positions;
  const repose::BlockSparseMatrix3f A = clampedBoxStiffness(b, 10.0, 1.0, positions);
  const int n = A.rows();
  std::mt19937 rng(7);
  std::normal_distribution<double> g;
  Eigen::VectorXd rhs(3 * n);
  for (int i = 0; i < 3 * n; ++i) rhs(i) = g(rng);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(3 * n);
  const int jacobi = repose::blockJacobiCg(A, rhs, x, 1e-8, 10000).iterations;
  repose::TwoLevelPreconditioner M;
  M.aggregate(A, positions, 60);
  M.update(A, positions);
  x.setZero();
  const repose::BlockCgResult r = repose::preconditionedBlockCg(A, rhs, x, 1e-8, 10000, M);
  EXPECT_LE(r.relativeResidual, 1e-8);
  std::printf("CG iterations: block Jacobi %d, two-level %d (%d aggregates)\n", jacobi, r.iterations, M.aggregates());
  EXPECT_LT(r.iterations, jacobi / 4);
}

}  // namespace
