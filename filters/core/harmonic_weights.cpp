#include "harmonic_weights.h"

#include <Eigen/CholmodSupport>
#include <Eigen/Dense>
#include <Eigen/SparseCholesky>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <mutex>
#include <stdexcept>
#include <string>

#include "blas_threads.h"
#include "fill_ordering.h"
#include "parallel_for.h"
#include "tet_laplacian.h"

namespace repose {
namespace {

using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// Result of the Dirichlet solve on the free nodes.
struct HarmonicSolution {
  int boneCount = 0;
  std::vector<int> freeIndex;  // #V: row in W for free nodes, -1 for fixed nodes
  // #free by #bones, row-major so one node's weights are contiguous.
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> W;
};

int checkInputs(const TetMesh& mesh, const HarmonicWeightsOptions& options) {
  const Eigen::Index nv = mesh.nodes.rows();
  if (Eigen::Index(mesh.fixedBone.size()) != nv)
    throw std::invalid_argument("harmonicWeights: fixedBone has " +
                                std::to_string(mesh.fixedBone.size()) + " entries for " +
                                std::to_string(nv) + " mesh nodes");
  if (options.maxInfluences < 1)
    throw std::invalid_argument("harmonicWeights: maxInfluences must be >= 1");
  int boneCount = options.boneCount;
  if (boneCount <= 0)  // not given: the largest bone index used
    for (int b : mesh.fixedBone) boneCount = std::max(boneCount, b + 1);
  if (boneCount <= 0)
    throw std::invalid_argument("harmonicWeights: no mesh node is fixed to a bone (FixedBone is -1 "
                                "everywhere); tag the bone nodes first");
  if (boneCount > 65535)
    throw std::invalid_argument("harmonicWeights: more than 65535 bones");
  std::vector<int> nodesOfBone(boneCount, 0);
  for (Eigen::Index i = 0; i < nv; ++i) {
    const int b = mesh.fixedBone[i];
    if (b < -1 || b >= boneCount)
      throw std::invalid_argument("harmonicWeights: node " + std::to_string(i) + " is fixed to bone " +
                                  std::to_string(b) + ", outside [0, " + std::to_string(boneCount) +
                                  ") (or -1 for free)");
    if (b >= 0) ++nodesOfBone[b];
  }
  for (int b = 0; b < boneCount; ++b)
    if (nodesOfBone[b] == 0)
      throw std::invalid_argument("harmonicWeights: bone " + std::to_string(b) +
                                  " has no mesh node; its labels are missing from the mesh or the "
                                  "bone is too thin for the mesh resolution");
  return boneCount;
}

// Every free node must reach a fixed node through tet edges (the pattern of K), or K_ff is singular.
void checkConnectivity(const Eigen::SparseMatrix<double>& K, const std::vector<int>& fixedBone) {
  const Eigen::Index nv = K.cols();
  std::vector<char> reached(nv, 0);
  std::vector<int> queue;
  queue.reserve(nv);
  for (Eigen::Index i = 0; i < nv; ++i)
    if (fixedBone[i] >= 0) {
      reached[i] = 1;
      queue.push_back(int(i));
    }
  for (std::size_t q = 0; q < queue.size(); ++q)
    for (Eigen::SparseMatrix<double>::InnerIterator it(K, queue[q]); it; ++it)
      if (!reached[it.row()]) {
        reached[it.row()] = 1;
        queue.push_back(int(it.row()));
      }
  const Eigen::Index isolated = nv - Eigen::Index(queue.size());
  if (isolated > 0) {
    Eigen::Index first = 0;
    while (reached[first]) ++first;
    throw std::invalid_argument("harmonicWeights: " + std::to_string(isolated) +
                                " free mesh node(s) (e.g. node " + std::to_string(first) +
                                ") are not connected to any bone node through the tets; remove "
                                "unreferenced nodes and disconnected mesh parts, or tag a bone in them");
  }
}

// Factorizes (after the caller's analyzePattern) and solves every bone at once.
template <typename Solver>
Eigen::MatrixXd factorAndSolve(Solver& solver, const Eigen::SparseMatrix<double>& Kff,
                               const Eigen::MatrixXd& B, Clock::time_point analyzeStart,
                               HarmonicWeightsReport& report) {
  if (solver.info() == Eigen::Success) solver.factorize(Kff);
  report.factorSeconds = secondsSince(analyzeStart);
  if (solver.info() != Eigen::Success)
    throw std::invalid_argument("harmonicWeights: factorization of the free-node stiffness matrix "
                                "failed (" + report.solver + "); the mesh may have inverted or "
                                "degenerate tets");
  const auto t0 = Clock::now();
  Eigen::MatrixXd X = solver.solve(B);
  report.solveSeconds = secondsSince(t0);
  if (solver.info() != Eigen::Success || !X.allFinite())
    throw std::invalid_argument("harmonicWeights: solve failed (" + report.solver + ")");
  return X;
}

HarmonicSolution solveHarmonic(const TetMesh& mesh, const HarmonicWeightsOptions& options,
                               HarmonicWeightsReport& report) {
  HarmonicSolution sol;
  sol.boneCount = checkInputs(mesh, options);
  const int nb = sol.boneCount;
  const Eigen::Index nv = mesh.nodes.rows();

  auto t0 = Clock::now();
  const Eigen::SparseMatrix<double> K = tetStiffnessMatrix(mesh.nodes, mesh.tets);
  checkConnectivity(K, mesh.fixedBone);

  sol.freeIndex.assign(nv, -1);
  int nfree = 0;
  for (Eigen::Index i = 0; i < nv; ++i)
    if (mesh.fixedBone[i] < 0) sol.freeIndex[i] = nfree++;
  report.freeNodes = nfree;
  report.fixedNodes = int(nv) - nfree;

  // K_ff in compressed form straight from K (the free renumbering is monotonic, so row order
  // is kept), and B = -K_fb W_b with W_b the bone indicators (K symmetric: K_fb(j,i) = K(i,j)).
  Eigen::SparseMatrix<double> Kff(nfree, nfree);
  Eigen::MatrixXd B = Eigen::MatrixXd::Zero(nfree, nb);
  {
    std::vector<int> outer(nfree + 1, 0);
    std::vector<int> inner;
    std::vector<double> values;
    inner.reserve(K.nonZeros());
    values.reserve(K.nonZeros());
    for (Eigen::Index j = 0; j < nv; ++j) {
      const int fj = sol.freeIndex[j];
      if (fj < 0) continue;
      for (Eigen::SparseMatrix<double>::InnerIterator it(K, j); it; ++it) {
        const int fi = sol.freeIndex[it.row()];
        if (fi >= 0) {
          inner.push_back(fi);
          values.push_back(it.value());
        } else {
          B(fj, mesh.fixedBone[it.row()]) -= it.value();
        }
      }
      outer[fj + 1] = int(inner.size());
    }
    Kff = Eigen::Map<const Eigen::SparseMatrix<double>>(nfree, nfree, Eigen::Index(inner.size()),
                                                         outer.data(), inner.data(), values.data());
  }
  report.assembleSeconds = secondsSince(t0);

  Eigen::MatrixXd X;
  if (nfree > 0) {
    // BLAS on this thread only: the same bits on any machine, and no spinning BLAS threads that a
    // busy core (another job, a batch worker beside this one) stalls (scripts/benchmark_busy_neighbour.py:
    // two OpenBLAS threads made the small phantom's solve 8.6x slower beside one spinning process).
    const SingleThreadedBlas blasOnThisThread;
    const auto analyzeStart = Clock::now();
    if (options.solver == HarmonicSolver::CholmodSupernodal) {
      report.solver = "CHOLMOD supernodal LLT";
      Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower> solver;
      analyzeWithFillOrdering(solver, Kff, options.ordering);  // one factorization serves every bone
      const FillAnalysis fill = lastFillAnalysis(solver.cholmod());
      report.ordering = fill.ordering;
      report.factorFlops = fill.flops;
      report.factorNonzeros = fill.factorNonzeros;
      report.analyzeSeconds = secondsSince(analyzeStart);
      X = factorAndSolve(solver, Kff, B, analyzeStart, report);
    } else {
      report.solver = "Eigen SimplicialLDLT";
      Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower> solver;
      solver.analyzePattern(Kff);
      report.ordering = "AMD";  // Eigen's default for SimplicialLDLT
      report.analyzeSeconds = secondsSince(analyzeStart);
      X = factorAndSolve(solver, Kff, B, analyzeStart, report);
    }
  } else {
    report.solver = "none (every node fixed)";
  }
  sol.W = X;  // column-major -> row-major
  return sol;
}

// Raw statistics over the free nodes (fixed nodes are exact indicators).
void rawStatistics(const HarmonicSolution& sol, HarmonicWeightsReport& report) {
  double mn = std::numeric_limits<double>::infinity(), mx = -mn, sumErr = 0;
  std::mutex m;
  parallelFor(std::size_t(sol.W.rows()), [&](std::size_t b, std::size_t e) {
    double lmn = std::numeric_limits<double>::infinity(), lmx = -lmn, lerr = 0;
    for (std::size_t i = b; i < e; ++i) {
      const auto row = sol.W.row(Eigen::Index(i));
      lmn = std::min(lmn, row.minCoeff());
      lmx = std::max(lmx, row.maxCoeff());
      lerr = std::max(lerr, std::abs(row.sum() - 1.0));
    }
    std::lock_guard<std::mutex> lock(m);
    mn = std::min(mn, lmn);
    mx = std::max(mx, lmx);
    sumErr = std::max(sumErr, lerr);
  });
  if (report.fixedNodes > 0) {
    mn = std::min(mn, sol.boneCount > 1 ? 0.0 : 1.0);
    mx = std::max(mx, 1.0);
  }
  report.minRawWeight = std::isfinite(mn) ? mn : 0;
  report.maxRawWeight = std::isfinite(mx) ? mx : 0;
  report.maxSumError = sumErr;
}

}  // namespace

std::vector<double> harmonicWeightsDense(const TetMesh& mesh, const HarmonicWeightsOptions& options,
                                         HarmonicWeightsReport* report) {
  HarmonicWeightsReport local;
  HarmonicWeightsReport& rep = report ? *report : local;
  rep = HarmonicWeightsReport{};
  const HarmonicSolution sol = solveHarmonic(mesh, options, rep);
  rawStatistics(sol, rep);
  const std::size_t nv = mesh.fixedBone.size(), nb = std::size_t(sol.boneCount);
  std::vector<double> W(nv * nb, 0.0);
  for (std::size_t i = 0; i < nv; ++i) {
    const int f = sol.freeIndex[i];
    if (f < 0)
      W[i * nb + std::size_t(mesh.fixedBone[i])] = 1.0;
    else
      for (std::size_t j = 0; j < nb; ++j) W[i * nb + j] = sol.W(f, Eigen::Index(j));
  }
  return W;
}

SparseWeights harmonicWeights(const TetMesh& mesh, const HarmonicWeightsOptions& options,
                              HarmonicWeightsReport* report) {
  HarmonicWeightsReport local;
  HarmonicWeightsReport& rep = report ? *report : local;
  rep = HarmonicWeightsReport{};
  const HarmonicSolution sol = solveHarmonic(mesh, options, rep);
  rawStatistics(sol, rep);

  const auto t0 = Clock::now();
  const int k = options.maxInfluences, nb = sol.boneCount;
  const std::size_t nv = mesh.fixedBone.size();
  SparseWeights out;
  out.k = k;
  out.weight.assign(nv * std::size_t(k), 0.0f);
  out.bone.assign(nv * std::size_t(k), 0);
  parallelFor(nv, [&](std::size_t begin, std::size_t end) {
    std::vector<double> topW(k);
    std::vector<int> topB(k);
    for (std::size_t i = begin; i < end; ++i) {
      float* w = &out.weight[i * std::size_t(k)];
      std::uint16_t* bo = &out.bone[i * std::size_t(k)];
      const int f = sol.freeIndex[i];
      if (f < 0) {
        w[0] = 1.0f;
        bo[0] = std::uint16_t(mesh.fixedBone[i]);
        continue;
      }
      // k largest, sorted descending (insertion into a k-slot list).
      int count = 0;
      const double* row = sol.W.data() + std::size_t(f) * std::size_t(nb);
      for (int j = 0; j < nb; ++j) {
        const double v = row[j];
        if (count == k && v <= topW[k - 1]) continue;
        int pos = count < k ? count++ : k - 1;
        while (pos > 0 && topW[pos - 1] < v) {
          topW[pos] = topW[pos - 1];
          topB[pos] = topB[pos - 1];
          --pos;
        }
        topW[pos] = v;
        topB[pos] = j;
      }
      double sum = 0;
      for (int s = 0; s < count; ++s) sum += std::max(0.0, topW[s]);
      if (!(sum > 0)) {  // cannot happen for a harmonic solution, but never divide by zero
        w[0] = 1.0f;
        bo[0] = std::uint16_t(topB[0]);
        continue;
      }
      for (int s = 0; s < count; ++s) {
        w[s] = float(std::max(0.0, topW[s]) / sum);
        bo[s] = std::uint16_t(topB[s]);
      }
    }
  }, 4096);
  rep.selectSeconds = secondsSince(t0);
  return out;
}

}  // namespace repose
