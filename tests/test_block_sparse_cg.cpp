// The block CG on float 3x3 blocks: solutions, low-rank terms, upper storage, thread-count independence.
#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <thread>
#include <vector>

#include "block_sparse_cg.h"
#include "block_test_systems.h"
#include "corotational_test_meshes.h"
#include "parallel_for.h"
#include "two_level_preconditioner.h"

namespace {

using repose::Points;

// A random SPD matrix of 3x3 blocks: block (i, i + d) for each offset d (and its transpose), and a
// diagonal of diagonal + |N(0, 1)| (diagonally dominant). dense gets the matrix; the result holds
// its nonzero blocks in float, both triangles.
repose::BlockSparseMatrix3f randomSpdBlocks(int n, std::initializer_list<int> offsets, double diagonal,
                                            std::mt19937& rng, Eigen::MatrixXd& dense) {
  std::normal_distribution<double> g;
  dense = Eigen::MatrixXd::Zero(3 * n, 3 * n);
  for (int i = 0; i < n; ++i)
    for (int d : offsets)
      if (i + d < n) {
        Eigen::Matrix3d B;
        for (int k = 0; k < 9; ++k) B(k / 3, k % 3) = 0.3 * g(rng);
        dense.block<3, 3>(3 * i, 3 * (i + d)) = B;
        dense.block<3, 3>(3 * (i + d), 3 * i) = B.transpose();
      }
  for (int i = 0; i < 3 * n; ++i) dense(i, i) = diagonal + std::abs(g(rng));
  repose::BlockSparseMatrix3f A;
  A.rowStart.push_back(0);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j)
      if (dense.block<3, 3>(3 * i, 3 * j).cwiseAbs().maxCoeff() > 0) {
        A.column.push_back(j);
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c) A.values.push_back(float(dense(3 * i + r, 3 * j + c)));
      }
    A.rowStart.push_back(int(A.column.size()));
  }
  return A;
}

TEST(BlockSparseCg, SolvesAnSpdBlockSystemLikeADenseSolver) {
  // A random SPD matrix of 3x3 blocks with a sparse block pattern (a chain with skips).
  const int n = 40;
  std::mt19937 rng(11);
  std::normal_distribution<double> g;
  Eigen::MatrixXd dense;
  const repose::BlockSparseMatrix3f A = randomSpdBlocks(n, {1, 3}, 4.0, rng, dense);
  Eigen::MatrixXd asFloat = dense.cast<float>().cast<double>();  // the operator CG actually sees
  Eigen::VectorXd b(3 * n);
  for (int i = 0; i < 3 * n; ++i) b(i) = g(rng);
  Eigen::VectorXd y;
  A.multiply(b, y);
  EXPECT_LT((y - asFloat * b).norm(), 1e-12 * b.norm());
  Eigen::VectorXd x = Eigen::VectorXd::Zero(3 * n);
  const repose::BlockCgResult r = repose::blockJacobiCg(A, b, x, 1e-10, 1000);
  EXPECT_LE(r.relativeResidual, 1e-10);
  EXPECT_GT(r.iterations, 0);
  const Eigen::VectorXd exact = asFloat.ldlt().solve(b);
  EXPECT_LT((x - exact).norm(), 1e-8 * exact.norm());
  // A warm start at the solution needs no iteration.
  Eigen::VectorXd warm = exact;
  EXPECT_EQ(repose::blockJacobiCg(A, b, warm, 1e-6, 1000).iterations, 0);
  Eigen::VectorXd wrong(5);
  EXPECT_THROW(repose::blockJacobiCg(A, b, wrong, 1e-6, 10), std::invalid_argument);
}

// A low-rank term sum_r w_r g_r g_r^T beside the blocks (the coupling of region volumes): part of
// the operator that multiply() and both CGs see.
TEST(BlockSparseCg, LowRankTermIsPartOfTheOperator) {
  const int n = 30;
  std::mt19937 rng(5);
  std::normal_distribution<double> g;
  Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(3 * n, 3 * n);
  repose::BlockSparseMatrix3f A;
  A.rowStart.push_back(0);
  for (int i = 0; i < n; ++i) {
    for (int j : {i - 1, i, i + 1}) {
      if (j < 0 || j >= n) continue;
      A.column.push_back(j);
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) {
          const double v = i == j ? (r == c ? 3.0 : 0.0) : (r == c ? -1.0 : 0.0);
          A.values.push_back(float(v));
          dense(3 * i + r, 3 * j + c) = v;
        }
    }
    A.rowStart.push_back(int(A.column.size()));
  }
  // Two terms: the first over rows 0..19, the second over rows 10..29 (rows 10..19 hold both).
  repose::LowRankTerm3 L;
  L.weight = {50.0, 7.0};
  Eigen::MatrixXd G = Eigen::MatrixXd::Zero(3 * n, 2);
  L.rowStart.push_back(0);
  for (int i = 0; i < n; ++i) {
    for (int r = 0; r < 2; ++r) {
      if ((r == 0 && i >= 20) || (r == 1 && i < 10)) continue;
      L.term.push_back(r);
      for (int c = 0; c < 3; ++c) {
        const double v = g(rng);
        L.vector.push_back(v);
        G(3 * i + c, r) = v;
      }
    }
    L.rowStart.push_back(int(L.term.size()));
  }
  dense += G * Eigen::Vector2d(50.0, 7.0).asDiagonal() * G.transpose();
  A.lowRank = &L;
  Eigen::VectorXd b(3 * n);
  for (int i = 0; i < 3 * n; ++i) b(i) = g(rng);
  Eigen::VectorXd y;
  A.multiply(b, y);
  EXPECT_LT((y - dense * b).norm(), 1e-10 * (dense * b).norm());
  const Eigen::VectorXd exact = dense.ldlt().solve(b);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(3 * n);
  EXPECT_LE(repose::blockJacobiCg(A, b, x, 1e-11, 1000).relativeResidual, 1e-11);
  EXPECT_LT((x - exact).norm(), 1e-8 * exact.norm());
  struct Identity : repose::BlockPreconditioner {
    double apply(const Eigen::VectorXd& r, Eigen::VectorXd& z) const override {
      z = r;
      return r.squaredNorm();
    }
  } identity;
  x.setZero();
  EXPECT_LE(repose::preconditionedBlockCg(A, b, x, 1e-11, 1000, identity).relativeResidual, 1e-11);
  EXPECT_LT((x - exact).norm(), 1e-8 * exact.norm());
}

// Upper storage (the FEM's Newton matrices): the same operator from about half the blocks, also
// with couplings that reach across the threads' row ranges (j = i + n/2) and rows with no block.
TEST(BlockSparseCg, UpperStorageIsTheSameOperator) {
  const int n = 400;
  std::mt19937 rng(17);
  std::normal_distribution<double> g;
  Eigen::MatrixXd dense;
  const repose::BlockSparseMatrix3f A = randomSpdBlocks(n, {1, 7, n / 2}, 5.0, rng, dense);
  const repose::BlockSparseMatrix3f U = upperPart(A);
  EXPECT_TRUE(U.upper);
  EXPECT_LT(U.column.size(), 0.6 * double(A.column.size()));
  Eigen::VectorXd x(3 * n);
  for (int i = 0; i < 3 * n; ++i) x(i) = g(rng);
  Eigen::VectorXd yFull, yUpper;
  A.multiply(x, yFull);
  U.multiply(x, yUpper);
  EXPECT_LT((yUpper - yFull).norm(), 1e-12 * yFull.norm());
  const Eigen::MatrixXd asFloat = dense.cast<float>().cast<double>();
  EXPECT_LT((yUpper - asFloat * x).norm(), 1e-12 * yFull.norm());
  Eigen::VectorXd solution = Eigen::VectorXd::Zero(3 * n);
  EXPECT_LE(repose::blockJacobiCg(U, x, solution, 1e-10, 1000).relativeResidual, 1e-10);
  EXPECT_LT((solution - asFloat.ldlt().solve(x)).norm(), 1e-8 * solution.norm());
  // Empty rows (a node whose blocks all sit in earlier rows cannot exist, but the product must not
  // depend on it): the zero matrix of the same size gives zero.
  repose::BlockSparseMatrix3f empty;
  empty.upper = true;
  empty.rowStart.assign(std::size_t(n) + 1, 0);
  empty.multiply(x, yUpper);
  EXPECT_EQ(yUpper.size(), 3 * n);
  EXPECT_EQ(yUpper.cwiseAbs().maxCoeff(), 0.0);
}

// parallelFor() runners that split the work otherwise than the installed one: all of it in one call
// on this thread, or contiguous ranges on `workers` std::threads whatever the grain.
void serialRunner(std::size_t n, std::size_t, const repose::RangeBody& body) { body(0, n); }

repose::ParallelRunner threadRunner(std::size_t workers) {
  return [workers](std::size_t n, std::size_t, const repose::RangeBody& body) {
    const std::size_t chunk = (n + workers - 1) / workers;
    std::vector<std::thread> threads;
    for (std::size_t b = 0; b < n; b += chunk) threads.emplace_back([&body, b, e = std::min(n, b + chunk)] { body(b, e); });
    for (auto& t : threads) t.join();
  };
}

bool bitIdentical(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), sizeof(double) * std::size_t(a.size())) == 0;
}

// Every sum of the block CGs and the two-level preconditioner is taken over chunks fixed by the
// sizes and added in chunk order: the solutions are the same bits on one thread and on several.
TEST(BlockSparseCg, SolutionsAreBitIdenticalForAnyThreadCount) {
  const Box b = makeBox(40, 8, 8, 1.0);
  Points positions;
  repose::BlockSparseMatrix3f U = upperPart(clampedBoxStiffness(b, 10.0, 1.0, positions));
  const int n = U.rows();
  std::mt19937 rng(23);
  std::normal_distribution<double> g;
  repose::LowRankTerm3 L;  // a region-volume-like coupling: one term over the far half, one over all
  L.weight = {3.0, 0.5};
  L.rowStart.push_back(0);
  for (int i = 0; i < n; ++i) {
    for (int r = 0; r < 2; ++r) {
      if (r == 0 && positions(i, 0) < 20.0) continue;
      L.term.push_back(r);
      for (int c = 0; c < 3; ++c) L.vector.push_back(0.1 * g(rng));
    }
    L.rowStart.push_back(int(L.term.size()));
  }
  U.lowRank = &L;
  Eigen::VectorXd rhs(3 * n);
  for (int i = 0; i < 3 * n; ++i) rhs(i) = g(rng);
  struct Run {
    Eigen::VectorXd jacobi, twoLevel;
    repose::BlockCgResult jacobiCg, twoLevelCg;
  };
  auto solve = [&](const repose::ParallelRunner& runner) {
    repose::setParallelRunner(runner);
    Run run;
    run.jacobi = Eigen::VectorXd::Zero(3 * n);
    run.jacobiCg = repose::blockJacobiCg(U, rhs, run.jacobi, 1e-9, 300);  // far from converged: enough bits
    repose::TwoLevelPreconditioner M;
    M.aggregate(U, positions, 60);
    M.update(U, positions);
    run.twoLevel = Eigen::VectorXd::Zero(3 * n);
    run.twoLevelCg = repose::preconditionedBlockCg(U, rhs, run.twoLevel, 1e-9, 10000, M);
    repose::setParallelRunner(repose::ParallelRunner());
    return run;
  };
  const Run serial = solve(serialRunner);
  EXPECT_GT(U.column.size(), std::size_t(2 * 8192));  // several chunks of the upper product too
  EXPECT_EQ(serial.jacobiCg.iterations, 300);
  EXPECT_LT(serial.jacobiCg.relativeResidual, 0.1);
  EXPECT_LE(serial.twoLevelCg.relativeResidual, 1e-9);
  EXPECT_GT(serial.twoLevelCg.iterations, 5);
  Eigen::VectorXd product;
  U.multiply(serial.twoLevel, product);
  EXPECT_LT((product - rhs).norm(), 1e-8 * rhs.norm());
  std::vector<std::pair<const char*, repose::ParallelRunner>> runners = {
      {"1 thread", threadRunner(1)}, {"2 threads", threadRunner(2)}, {"3 threads", threadRunner(3)},
      {"7 threads", threadRunner(7)}, {"default runner", repose::ParallelRunner()}};
  for (const auto& [name, runner] : runners) {
    SCOPED_TRACE(name);
    const Run run = solve(runner);
    EXPECT_EQ(run.jacobiCg.iterations, serial.jacobiCg.iterations);
    EXPECT_EQ(run.jacobiCg.relativeResidual, serial.jacobiCg.relativeResidual);
    EXPECT_TRUE(bitIdentical(run.jacobi, serial.jacobi)) << (run.jacobi - serial.jacobi).cwiseAbs().maxCoeff();
    EXPECT_EQ(run.twoLevelCg.iterations, serial.twoLevelCg.iterations);
    EXPECT_EQ(run.twoLevelCg.relativeResidual, serial.twoLevelCg.relativeResidual);
    EXPECT_TRUE(bitIdentical(run.twoLevel, serial.twoLevel)) << (run.twoLevel - serial.twoLevel).cwiseAbs().maxCoeff();
  }
}

// The upper-stored product in several row chunks, also when couplings reach far (a stride through
// the rows, so the chunks are merged to bound the spill buffers): the product summed serially, and
// the same bits however the threads split the chunks.
TEST(BlockSparseCg, ChunkedUpperProductMatchesASerialSum) {
  const int n = 8000;
  std::mt19937 rng(29);
  std::normal_distribution<double> g;
  repose::BlockSparseMatrix3f U;
  U.upper = true;
  U.rowStart.push_back(0);
  for (int i = 0; i < n; ++i) {
    std::set<int> columns = {i};
    for (int d : {1, 2})
      if (i + d < n) columns.insert(i + d);
    if (const int far = int((long long)i * 7919 % n); far > i) columns.insert(far);
    for (int j : columns) {
      U.column.push_back(j);
      for (int k = 0; k < 9; ++k) U.values.push_back(float(g(rng)));
    }
    U.rowStart.push_back(int(U.column.size()));
  }
  Eigen::VectorXd x(3 * n);
  for (int i = 0; i < 3 * n; ++i) x(i) = g(rng);
  Eigen::VectorXd expected = Eigen::VectorXd::Zero(3 * n);
  for (int i = 0; i < n; ++i)
    for (int k = U.rowStart[std::size_t(i)]; k < U.rowStart[std::size_t(i) + 1]; ++k) {
      const int j = U.column[std::size_t(k)];
      const Eigen::Matrix3d A =
          Eigen::Map<const Eigen::Matrix<float, 3, 3, Eigen::RowMajor>>(U.values.data() + 9 * std::size_t(k)).cast<double>();
      expected.segment<3>(3 * i) += A * x.segment<3>(3 * j);
      if (j != i) expected.segment<3>(3 * j) += A.transpose() * x.segment<3>(3 * i);
    }
  EXPECT_GT(U.column.size(), std::size_t(2 * 8192));
  Eigen::VectorXd serial, threaded;
  repose::setParallelRunner(serialRunner);
  U.multiply(x, serial);
  repose::setParallelRunner(threadRunner(3));
  U.multiply(x, threaded);
  repose::setParallelRunner(repose::ParallelRunner());
  EXPECT_LT((serial - expected).norm(), 1e-12 * expected.norm());
  EXPECT_TRUE(bitIdentical(serial, threaded));
}

}  // namespace
