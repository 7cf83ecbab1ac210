// Stiffness matrix and harmonic bone weights on procedurally built tet meshes.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <numeric>
#include <random>
#include <stdexcept>
#include <string>

#include "harmonic_weights.h"
#include "tet_laplacian.h"
#include "box_tet_mesh.h"
#include "tet_mesh.h"

namespace {

using repose::TetMesh;

// Box of nx*ny*nz cubes of size h cut into Kuhn tets (dihedral angles <= 90 degrees, so the maximum
// principle holds); jitter moves interior nodes randomly by up to jitter*h.
TetMesh gridMesh(int nx, int ny, int nz, double h = 1.0, double jitter = 0.0, unsigned seed = 1) {
  TetMesh m;
  kuhnBoxMesh(Eigen::Vector3d::Zero(), h * Eigen::Vector3d(nx, ny, nz), {nx, ny, nz}, m.nodes, m.tets, jitter, seed);
  m.fixedBone.assign(m.nodes.rows(), -1);
  m.tetLabel.assign(m.tets.rows(), 0);
  return m;
}

Eigen::MatrixXd dense(const Eigen::SparseMatrix<double>& K) { return Eigen::MatrixXd(K); }

// Cotangent formula for one tet: K_ij = -1/6 * l_kl * cot(theta_kl), where kl is the edge opposite
// ij and theta_kl the dihedral angle at it.
double cotangentEntry(const Eigen::Vector3d x[4], int i, int j) {
  int o[2], n = 0;
  for (int a = 0; a < 4; ++a)
    if (a != i && a != j) o[n++] = a;
  const Eigen::Vector3d e = (x[o[1]] - x[o[0]]).normalized();
  // Dihedral angle at edge (o0,o1) between faces (o0,o1,i) and (o0,o1,j).
  Eigen::Vector3d ui = x[i] - x[o[0]], uj = x[j] - x[o[0]];
  ui -= ui.dot(e) * e;
  uj -= uj.dot(e) * e;
  const double theta = std::acos(ui.normalized().dot(uj.normalized()));
  return -(x[o[1]] - x[o[0]]).norm() / (6.0 * std::tan(theta));
}

}  // namespace

TEST(TetLaplacian, RegularTetMatchesCotangentFormula) {
  const double a = 2.0;
  repose::Points V(4, 3);
  V << 1, 1, 1, 1, -1, -1, -1, 1, -1, -1, -1, 1;  // edge length 2*sqrt(2)
  V *= a / (2.0 * std::sqrt(2.0));                 // edge length a
  repose::Tets T(1, 4);
  T << 0, 1, 2, 3;
  if (repose::tetVolume(V.row(0), V.row(1), V.row(2), V.row(3)) < 0) std::swap(T(0, 2), T(0, 3));
  const Eigen::MatrixXd K = dense(repose::tetStiffnessMatrix(V, T));
  // Dihedral angle acos(1/3): cot = 1/(2 sqrt 2), so K_ij = -a / (12 sqrt 2).
  const double off = -a / (12.0 * std::sqrt(2.0));
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) EXPECT_NEAR(K(i, j), i == j ? -3 * off : off, 1e-14);
}

TEST(TetLaplacian, GeneralTetMatchesCotangentFormula) {
  repose::Points V(4, 3);
  V << 0.1, 0.2, -0.3, 2.0, 0.1, 0.3, 0.4, 1.7, 0.2, 0.5, 0.6, 1.9;
  repose::Tets T(1, 4);
  T << 0, 1, 2, 3;
  ASSERT_GT(repose::tetVolume(V.row(0), V.row(1), V.row(2), V.row(3)), 0);
  const Eigen::MatrixXd K = dense(repose::tetStiffnessMatrix(V, T));
  Eigen::Vector3d x[4];
  for (int i = 0; i < 4; ++i) x[i] = V.row(i);
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      if (i != j) EXPECT_NEAR(K(i, j), cotangentEntry(x, i, j), 1e-12) << i << "," << j;
}

TEST(TetLaplacian, RowsSumToZeroSymmetricPSD) {
  const TetMesh m = gridMesh(3, 2, 2, 1.5, 0.2, 7);
  const Eigen::MatrixXd K = dense(repose::tetStiffnessMatrix(m.nodes, m.tets));
  EXPECT_LT(K.rowwise().sum().cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((K - K.transpose()).cwiseAbs().maxCoeff(), 1e-14);
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(K);
  EXPECT_GT(es.eigenvalues().minCoeff(), -1e-10);
  // Exactly one zero eigenvalue (constants) for a connected mesh.
  EXPECT_GT(es.eigenvalues()(1), 1e-6);
  // Linear functions have zero "Laplacian" at interior nodes: (K x)_i = 0 away from the boundary.
  const Eigen::VectorXd Kx = K * m.nodes.col(0);
  const int interior = 1 + 4 * (1 + 3 * 1);  // node (1,1,1) of a 4x3x3-node grid
  EXPECT_NEAR(Kx(interior), 0.0, 1e-12);
}

// Assembled in place, K holds the bits of the triplet-list assembly it replaced: the same pattern
// (every node pair sharing a tet, rows sorted) and each entry the sum of its tets' terms in tet order.
TEST(TetLaplacian, SameBitsAsTripletAssembly) {
  const TetMesh m = gridMesh(5, 4, 3, 1.3, 0.3, 11);
  std::vector<Eigen::Triplet<double>> triplets;
  for (Eigen::Index t = 0; t < m.tets.rows(); ++t) {
    repose::Tets one(1, 4);
    one << 0, 1, 2, 3;
    repose::Points corners(4, 3);
    for (int c = 0; c < 4; ++c) corners.row(c) = m.nodes.row(m.tets(t, c));
    const Eigen::MatrixXd Ke = dense(repose::tetStiffnessMatrix(corners, one));
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b) triplets.emplace_back(m.tets(t, a), m.tets(t, b), Ke(a, b));
  }
  Eigen::SparseMatrix<double> reference(m.nodes.rows(), m.nodes.rows());
  reference.setFromTriplets(triplets.begin(), triplets.end());
  const Eigen::SparseMatrix<double> K = repose::tetStiffnessMatrix(m.nodes, m.tets);
  ASSERT_TRUE(K.isCompressed());
  ASSERT_EQ(K.nonZeros(), reference.nonZeros());
  EXPECT_TRUE(std::equal(K.outerIndexPtr(), K.outerIndexPtr() + K.cols() + 1, reference.outerIndexPtr()));
  EXPECT_TRUE(std::equal(K.innerIndexPtr(), K.innerIndexPtr() + K.nonZeros(), reference.innerIndexPtr()));
  EXPECT_EQ(std::memcmp(K.valuePtr(), reference.valuePtr(), sizeof(double) * std::size_t(K.nonZeros())), 0);
}

TEST(TetLaplacian, BadInputThrows) {
  repose::Points V(4, 3);
  V << 0, 0, 0, 1, 0, 0, 0, 1, 0, 2, 3, 0;  // flat
  repose::Tets T(1, 4);
  T << 0, 1, 2, 3;
  EXPECT_THROW(repose::tetStiffnessMatrix(V, T), std::invalid_argument);
  T << 0, 1, 2, 4;
  EXPECT_THROW(repose::tetStiffnessMatrix(V, T), std::invalid_argument);
}

// A long bar, bone 0 fixed at x=0 and bone 1 at x=L: the harmonic solution is w1 = x/L.
TEST(HarmonicWeights, BarGivesLinearSolutionWithBothSolvers) {
  TetMesh m = gridMesh(12, 2, 2, 2.5);
  const double L = 12 * 2.5;
  for (Eigen::Index i = 0; i < m.nodes.rows(); ++i) {
    if (m.nodes(i, 0) == 0) m.fixedBone[i] = 0;
    if (m.nodes(i, 0) == L) m.fixedBone[i] = 1;
  }
  for (auto solver : {repose::HarmonicSolver::CholmodSupernodal,
                      repose::HarmonicSolver::EigenSimplicialLDLT}) {
    repose::HarmonicWeightsOptions opt;
    opt.boneCount = 2;
    opt.solver = solver;
    repose::HarmonicWeightsReport rep;
    const std::vector<double> W = repose::harmonicWeightsDense(m, opt, &rep);
    ASSERT_EQ(W.size(), std::size_t(m.nodes.rows()) * 2);
    for (Eigen::Index i = 0; i < m.nodes.rows(); ++i) {
      EXPECT_NEAR(W[2 * i + 1], m.nodes(i, 0) / L, 1e-9) << rep.solver << " node " << i;
      EXPECT_NEAR(W[2 * i + 0], 1 - m.nodes(i, 0) / L, 1e-9) << rep.solver << " node " << i;
    }
    EXPECT_LT(rep.maxSumError, 1e-9);
    EXPECT_EQ(rep.fixedNodes, 2 * 9);
    EXPECT_EQ(rep.freeNodes, int(m.nodes.rows()) - 18);

    // The sparse (k=4) weights of the same problem, as floats.
    opt.maxInfluences = 4;
    const repose::SparseWeights sw = repose::harmonicWeights(m, opt);
    ASSERT_EQ(sw.nodeCount(), std::size_t(m.nodes.rows()));
    for (Eigen::Index i = 0; i < m.nodes.rows(); ++i) {
      double w1 = 0;
      for (int s = 0; s < 4; ++s)
        if (sw.bone[4 * i + s] == 1) w1 += sw.weight[4 * i + s];
      EXPECT_NEAR(w1, m.nodes(i, 0) / L, 1e-6);
    }
  }
}

TEST(HarmonicWeights, PartitionOfUnityAndBoundsOnIrregularMesh) {
  // Jittered grid with four bones as small clusters of nodes.
  TetMesh m = gridMesh(6, 5, 4, 1.0, 0.25, 3);
  const Eigen::RowVector3d seeds[4] = {{0, 0, 0}, {6, 5, 4}, {6, 0, 2}, {0, 5, 4}};
  for (Eigen::Index i = 0; i < m.nodes.rows(); ++i)
    for (int b = 0; b < 4; ++b)
      if ((m.nodes.row(i) - seeds[b]).norm() < 1.6) m.fixedBone[i] = b;
  repose::HarmonicWeightsOptions opt;
  opt.boneCount = 4;
  opt.maxInfluences = 3;
  repose::HarmonicWeightsReport rep;
  const std::vector<double> W = repose::harmonicWeightsDense(m, opt, &rep);
  double maxErr = 0;
  for (Eigen::Index i = 0; i < m.nodes.rows(); ++i) {
    double s = 0;
    for (int b = 0; b < 4; ++b) s += W[4 * i + b];
    maxErr = std::max(maxErr, std::abs(s - 1));
  }
  EXPECT_LT(maxErr, 1e-9);
  EXPECT_LT(rep.maxSumError, 1e-9);
  EXPECT_NEAR(rep.maxSumError, maxErr, 1e-12);
  EXPECT_LE(rep.maxRawWeight, 1 + 1e-9);
  EXPECT_GT(rep.minRawWeight, -0.05);  // jitter may break the maximum principle only slightly

  const repose::SparseWeights sw = repose::harmonicWeights(m, opt, &rep);
  EXPECT_EQ(sw.k, 3);
  for (Eigen::Index i = 0; i < m.nodes.rows(); ++i) {
    float s = 0;
    for (int k = 0; k < 3; ++k) {
      const float w = sw.weight[3 * i + k];
      EXPECT_GE(w, 0.0f);
      EXPECT_LT(sw.bone[3 * i + k], 4);
      if (k > 0) EXPECT_LE(w, sw.weight[3 * i + k - 1]);  // sorted, largest first
      s += w;
    }
    EXPECT_NEAR(s, 1.0f, 1e-6f);
    if (m.fixedBone[i] >= 0) {
      EXPECT_EQ(sw.weight[3 * i], 1.0f);
      EXPECT_EQ(int(sw.bone[3 * i]), m.fixedBone[i]);
    } else {
      // The largest kept weight is the node's largest raw weight.
      const double* row = &W[4 * i];
      EXPECT_EQ(int(sw.bone[3 * i]), int(std::max_element(row, row + 4) - row));
    }
  }
}

TEST(HarmonicWeights, RegularGridObeysMaximumPrinciple) {
  TetMesh m = gridMesh(5, 5, 5);
  m.fixedBone[0] = 0;
  m.fixedBone[m.nodes.rows() - 1] = 1;
  m.fixedBone[5] = 2;
  repose::HarmonicWeightsOptions opt;  // boneCount 0: inferred from fixedBone
  repose::HarmonicWeightsReport rep;
  const std::vector<double> W = repose::harmonicWeightsDense(m, opt, &rep);
  EXPECT_EQ(W.size(), std::size_t(m.nodes.rows()) * 3);
  EXPECT_GE(*std::min_element(W.begin(), W.end()), -1e-12);
  EXPECT_GE(rep.minRawWeight, -1e-12);
  EXPECT_LE(rep.maxRawWeight, 1.0);
  EXPECT_GE(rep.factorSeconds, 0.0);
  EXPECT_FALSE(rep.solver.empty());
}

TEST(HarmonicWeights, UnconnectedFreeNodeThrows) {
  TetMesh m = gridMesh(2, 2, 2);
  m.fixedBone[0] = 0;
  m.fixedBone[m.nodes.rows() - 1] = 1;
  m.nodes.conservativeResize(m.nodes.rows() + 1, 3);
  m.nodes.row(m.nodes.rows() - 1) << 10, 10, 10;  // referenced by no tet
  m.fixedBone.push_back(-1);
  repose::HarmonicWeightsOptions opt;
  opt.boneCount = 2;
  try {
    repose::harmonicWeights(m, opt);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("1 free mesh node"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("not connected"), std::string::npos) << e.what();
  }
}

TEST(HarmonicWeights, DisconnectedComponentThrows) {
  TetMesh a = gridMesh(2, 1, 1);
  TetMesh m = a;  // second copy shifted, with no fixed node
  const Eigen::Index n = a.nodes.rows();
  m.nodes.conservativeResize(2 * n, 3);
  m.nodes.bottomRows(n) = a.nodes.rowwise() + Eigen::RowVector3d(10, 0, 0);
  m.tets.conservativeResize(2 * a.tets.rows(), 4);
  m.tets.bottomRows(a.tets.rows()) = a.tets.array() + int(n);
  m.fixedBone.assign(2 * n, -1);
  m.fixedBone[0] = 0;
  m.fixedBone[n - 1] = 1;
  repose::HarmonicWeightsOptions opt;
  opt.boneCount = 2;
  try {
    repose::harmonicWeights(m, opt);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(std::to_string(n) + " free mesh node"), std::string::npos)
        << e.what();
  }
}

TEST(HarmonicWeights, BoneWithoutNodesThrows) {
  TetMesh m = gridMesh(2, 2, 2);
  m.fixedBone[0] = 0;
  m.fixedBone[m.nodes.rows() - 1] = 2;
  repose::HarmonicWeightsOptions opt;
  opt.boneCount = 3;
  try {
    repose::harmonicWeights(m, opt);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("bone 1 has no mesh node"), std::string::npos) << e.what();
  }
  opt.boneCount = 2;  // fixedBone 2 out of range
  EXPECT_THROW(repose::harmonicWeights(m, opt), std::invalid_argument);
  m.fixedBone.pop_back();  // size mismatch
  EXPECT_THROW(repose::harmonicWeights(m, opt), std::invalid_argument);
}

// Timing of the solvers with 20 bones: CHOLMOD on a 60^3-node grid (~216k nodes, 1.2M tets), both
// solvers on a 30^3-node grid (SimplicialLDLT takes many minutes at 60^3). Run with
// --gtest_also_run_disabled_tests --gtest_filter=*Benchmark*.
TEST(HarmonicWeights, DISABLED_BenchmarkSolvers) {
  struct Case {
    int nodesPerSide;
    repose::HarmonicSolver solver;
  };
  for (const Case c : {Case{30, repose::HarmonicSolver::CholmodSupernodal},
                       Case{30, repose::HarmonicSolver::EigenSimplicialLDLT},
                       Case{60, repose::HarmonicSolver::CholmodSupernodal}}) {
    const int cells = c.nodesPerSide - 1;
    TetMesh m = gridMesh(cells, cells, cells, 1.0);
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(0.1 * cells, 0.9 * cells);
    for (int b = 0; b < 20; ++b) {
      const Eigen::RowVector3d center(u(rng), u(rng), u(rng));
      for (Eigen::Index i = 0; i < m.nodes.rows(); ++i)
        if (m.fixedBone[i] < 0 && (m.nodes.row(i) - center).norm() < 0.05 * cells + 0.5)
          m.fixedBone[i] = b;
    }
    repose::HarmonicWeightsOptions opt;
    opt.boneCount = 20;
    opt.solver = c.solver;
    repose::HarmonicWeightsReport rep;
    const auto t0 = std::chrono::steady_clock::now();
    const std::clock_t c0 = std::clock();
    const repose::SparseWeights w = repose::harmonicWeights(m, opt, &rep);
    const double total =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const double cpu = double(std::clock() - c0) / CLOCKS_PER_SEC;  // all threads
    std::printf("%ld nodes, %ld tets, %s: assemble %.2f s  factor %.2f s  solve %.2f s  top-k %.3f s  "
                "total %.2f s (CPU %.2f s)  raw [%.3g, %.3g]  max|sum-1| %.2g\n",
                long(m.nodes.rows()), long(m.tets.rows()), rep.solver.c_str(), rep.assembleSeconds,
                rep.factorSeconds, rep.solveSeconds, rep.selectSeconds, total, cpu, rep.minRawWeight,
                rep.maxRawWeight, rep.maxSumError);
    std::fflush(stdout);
    EXPECT_LT(rep.maxSumError, 1e-8);
  }
}
