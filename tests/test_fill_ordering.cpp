// The fill-reducing orderings of CHOLMOD's Cholesky: each gives the same harmonic weights, the report
// names the one used, and Automatic turns to METIS exactly where metisPays says it is repaid.
#include <gtest/gtest.h>

#include <Eigen/CholmodSupport>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "box_tet_mesh.h"
#include "fill_ordering.h"
#include "harmonic_weights.h"
#include "tet_laplacian.h"

namespace {

using repose::FillOrdering;

// A jittered 14^3-cube box with two bones, one at each end.
repose::TetMesh twoBoneBox() {
  repose::TetMesh m;
  kuhnBoxMesh(Eigen::Vector3d::Zero(), Eigen::Vector3d(14, 14, 14), {14, 14, 14}, m.nodes, m.tets, 0.15, 5);
  m.fixedBone.assign(m.nodes.rows(), -1);
  m.tetLabel.assign(m.tets.rows(), 0);
  for (Eigen::Index i = 0; i < m.nodes.rows(); ++i) {
    if (m.nodes(i, 0) == 0) m.fixedBone[i] = 0;
    if (m.nodes(i, 0) == 14) m.fixedBone[i] = 1;
  }
  return m;
}

}  // namespace

TEST(FillOrdering, EveryOrderingGivesTheSameWeightsAndIsReported) {
  const repose::TetMesh m = twoBoneBox();
  repose::HarmonicWeightsOptions options;
  options.boneCount = 2;
  options.ordering = FillOrdering::Amd;
  repose::HarmonicWeightsReport amd;
  const std::vector<double> reference = repose::harmonicWeightsDense(m, options, &amd);
  EXPECT_EQ(amd.ordering, "AMD");
  EXPECT_GT(amd.factorFlops, 0);
  EXPECT_GT(amd.factorNonzeros, 0);

  const struct {
    FillOrdering ordering;
    const char* used;
  } cases[] = {{FillOrdering::Metis, "METIS"}, {FillOrdering::CholmodDefault, "AMD"},  // low fill: AMD kept
               {FillOrdering::Automatic, "AMD"}};  // a small mesh: METIS would not pay
  for (const auto& c : cases) {
    options.ordering = c.ordering;
    repose::HarmonicWeightsReport report;
    const std::vector<double> W = repose::harmonicWeightsDense(m, options, &report);
    EXPECT_EQ(report.ordering, c.used);
    double maxDifference = 0;
    for (std::size_t i = 0; i < W.size(); ++i) maxDifference = std::max(maxDifference, std::abs(W[i] - reference[i]));
    EXPECT_LT(maxDifference, 1e-12) << report.ordering;
    EXPECT_LT(report.maxSumError, 1e-12) << report.ordering;
    if (c.ordering == FillOrdering::Metis) EXPECT_LT(report.factorFlops, amd.factorFlops);  // nested dissection
  }
}

TEST(FillOrdering, MetisPaysOnlyForLargeFactorizationsPerRow) {
  EXPECT_FALSE(repose::metisPays(1e4 * 1000, 1000, 1));  // a small mesh's flops per row
  EXPECT_TRUE(repose::metisPays(1e6 * 1000, 1000, 1));   // a large mesh's
  EXPECT_TRUE(repose::metisPays(1e4 * 1000, 1000, 100)); // one analysis for many factorizations
  EXPECT_FALSE(repose::metisPays(0, 1000, 1e9));
}

TEST(FillOrdering, AutomaticAnalyzesAgainWithMetisWhereItPays) {
  repose::TetMesh m;
  kuhnBoxMesh(Eigen::Vector3d::Zero(), Eigen::Vector3d(1, 1, 1), {12, 12, 12}, m.nodes, m.tets);
  Eigen::SparseMatrix<double> K = repose::tetStiffnessMatrix(m.nodes, m.tets);
  for (Eigen::Index i = 0; i < K.rows(); ++i) K.coeffRef(i, i) += 1.0;  // SPD: a mass-like shift
  for (const double factorizations : {1.0, 1e9}) {
    Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower> solver;
    repose::analyzeWithFillOrdering(solver, K, FillOrdering::Automatic, factorizations);
    ASSERT_EQ(solver.info(), Eigen::Success);
    EXPECT_STREQ(repose::lastFillAnalysis(solver.cholmod()).ordering, factorizations > 1 ? "METIS" : "AMD");
    solver.factorize(K);
    ASSERT_EQ(solver.info(), Eigen::Success);
    const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(K.rows(), -1, 1);
    EXPECT_LT((K * solver.solve(b) - b).norm(), 1e-10 * b.norm());
  }
}
