#pragma once
// Elasticity systems as float 3x3 blocks for the block CG and two-level preconditioner tests.
#include <Eigen/Core>
#include <random>

#include "block_sparse_cg.h"
#include "corotational_test_meshes.h"

// Linear elasticity stiffness (Lame lambda, mu) of a box mesh, restricted to the nodes off its x = 0
// face (which is clamped), as float blocks; positions gets those nodes' positions.
inline repose::BlockSparseMatrix3f clampedBoxStiffness(const Box& b, double lambda, double mu, repose::Points& positions) {
  std::vector<int> dof(std::size_t(b.nodes.rows()), -1);
  int n = 0;
  for (Eigen::Index i = 0; i < b.nodes.rows(); ++i)
    if (b.nodes(i, 0) > 1e-9) dof[std::size_t(i)] = n++;
  positions.resize(n, 3);
  for (Eigen::Index i = 0; i < b.nodes.rows(); ++i)
    if (dof[std::size_t(i)] >= 0) positions.row(dof[std::size_t(i)]) = b.nodes.row(i);
  std::vector<std::map<int, Eigen::Matrix3d>> rows(static_cast<std::size_t>(n));
  for (Eigen::Index t = 0; t < b.tets.rows(); ++t) {
    Eigen::Matrix3d Dm;
    for (int k = 0; k < 3; ++k) Dm.col(k) = (b.nodes.row(b.tets(t, k + 1)) - b.nodes.row(b.tets(t, 0))).transpose();
    const double volume = Dm.determinant() / 6;
    Eigen::Matrix<double, 4, 3> g;
    g.bottomRows<3>() = Dm.inverse();
    g.row(0) = -g.bottomRows<3>().colwise().sum();
    for (int a = 0; a < 4; ++a)
      for (int c = 0; c < 4; ++c) {
        const int i = dof[std::size_t(b.tets(t, a))], j = dof[std::size_t(b.tets(t, c))];
        if (i < 0 || j < 0) continue;
        const Eigen::Vector3d ga = g.row(a).transpose(), gc = g.row(c).transpose();
        const Eigen::Matrix3d K = volume * (lambda * ga * gc.transpose() + mu * gc * ga.transpose() +
                                            mu * ga.dot(gc) * Eigen::Matrix3d::Identity());
        auto it = rows[std::size_t(i)].emplace(j, Eigen::Matrix3d::Zero()).first;
        it->second += K;
      }
  }
  repose::BlockSparseMatrix3f A;
  A.rowStart.push_back(0);
  for (const auto& row : rows) {
    for (const auto& [j, K] : row) {
      A.column.push_back(j);
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) A.values.push_back(float(K(r, c)));
    }
    A.rowStart.push_back(int(A.column.size()));
  }
  return A;
}

// The blocks of a symmetric matrix on and above the diagonal, as an upper-stored matrix.
inline repose::BlockSparseMatrix3f upperPart(const repose::BlockSparseMatrix3f& full) {
  repose::BlockSparseMatrix3f U;
  U.upper = true;
  U.rowStart.push_back(0);
  for (int i = 0; i < full.rows(); ++i) {
    for (int k = full.rowStart[std::size_t(i)]; k < full.rowStart[std::size_t(i) + 1]; ++k) {
      if (full.column[std::size_t(k)] < i) continue;
      U.column.push_back(full.column[std::size_t(k)]);
      U.values.insert(U.values.end(), full.values.begin() + 9 * k, full.values.begin() + 9 * (k + 1));
    }
    U.rowStart.push_back(int(U.column.size()));
  }
  return U;
}

/// size independent standard normal numbers.
inline Eigen::VectorXd gaussianVector(int size, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g;
  Eigen::VectorXd v(size);
  for (int i = 0; i < size; ++i) v(i) = g(rng);
  return v;
}

/// The operator CG sees (float blocks, full storage) as a dense double matrix.
inline Eigen::MatrixXd denseOperator(const repose::BlockSparseMatrix3f& A) {
  const int n = A.rows();
  Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(3 * n, 3 * n);
  for (int i = 0; i < n; ++i)
    for (int k = A.rowStart[std::size_t(i)]; k < A.rowStart[std::size_t(i) + 1]; ++k)
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c)
          dense(3 * i + r, 3 * A.column[std::size_t(k)] + c) = double(A.values[9 * std::size_t(k) + 3 * std::size_t(r) + c]);
  return dense;
}
