#pragma once
// The fill-reducing ordering of CHOLMOD's sparse Cholesky, for the harmonic weights' Laplacian and
// the FEM's direct solver: one rule for both, from what CHOLMOD's AMD analysis predicts.
//
// Why not always METIS: on these tet-mesh matrices METIS's nested dissection saves about half of
// AMD's factorization flops but costs 4-8 times AMD's ordering (about 12 us per row against 2), so
// it pays only once the factorization is large beside the matrix, i.e. on large meshes or when one
// analysis serves many factorizations (scripts/benchmark.py --orderings). CHOLMOD's own default
// (AMD, then METIS too when AMD's fill is high) tries METIS on meshes where it does not pay.
#include <Eigen/Core>

struct cholmod_common_struct;  // cholmod.h, included only where CHOLMOD is called

namespace repose {

enum class FillOrdering {
  Automatic,       ///< AMD, or METIS where metisPays says so after AMD's analysis
  Amd,             ///< approximate minimum degree only
  Metis,           ///< METIS nested dissection only
  CholmodDefault,  ///< CHOLMOD's default strategy: AMD, then METIS too if AMD's fill is high
};

/// What CHOLMOD's last analysis chose and predicts for the factorization.
struct FillAnalysis {
  const char* ordering = "none";  ///< "AMD", "METIS", "NESDIS", "natural", ...
  double flops = 0;               ///< of a simplicial LL' factorization with that ordering
  double factorNonzeros = 0;      ///< nnz(L)
};
FillAnalysis lastFillAnalysis(const cholmod_common_struct& common);

/// Whether METIS's extra ordering time is repaid, given AMD's flop count on a matrix of `rows` rows
/// and the number of numeric factorizations one analysis serves.
bool metisPays(double amdFlops, long rows, double factorizations);

/// Sets the orderings CHOLMOD tries in its next analysis (not Automatic: see analyzeWithFillOrdering).
void setFillOrdering(cholmod_common_struct& common, FillOrdering ordering);

/// solver.analyzePattern(A) with the ordering. Automatic analyzes with AMD and again with METIS when
/// metisPays(AMD's flops, rows, factorizations). With CHOLMOD built without METIS, METIS falls back to
/// CHOLMOD's default orderings. Check solver.info() afterwards as after analyzePattern.
template <class Solver, class Matrix>
void analyzeWithFillOrdering(Solver& solver, const Matrix& A, FillOrdering ordering, double factorizations = 1) {
  if (ordering == FillOrdering::Automatic) {
    setFillOrdering(solver.cholmod(), FillOrdering::Amd);
    solver.analyzePattern(A);
    if (solver.info() != Eigen::Success ||
        !metisPays(lastFillAnalysis(solver.cholmod()).flops, long(A.rows()), factorizations))
      return;
    ordering = FillOrdering::Metis;
  }
  setFillOrdering(solver.cholmod(), ordering);
  solver.analyzePattern(A);
  if (solver.info() != Eigen::Success && ordering == FillOrdering::Metis) {
    setFillOrdering(solver.cholmod(), FillOrdering::CholmodDefault);
    solver.analyzePattern(A);
  }
}

}  // namespace repose
