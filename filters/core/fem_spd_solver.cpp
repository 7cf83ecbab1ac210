#include "fem_spd_solver.h"

#include <Eigen/IterativeLinearSolvers>
#include <stdexcept>

#include "fill_ordering.h"

namespace repose {
namespace fem {

namespace {
using RowSpMat = Eigen::SparseMatrix<double, Eigen::RowMajor>;
}  // namespace

void SpdSolver::solve(BlockSparseMatrix3f& H, const Eigen::VectorXd& b, Eigen::VectorXd& x, double tolerance,
                      int& iterations, double& residual) {
  H.lowRank = lowRank_;
  Eigen::VectorXd r0 = b;
  if (!(x.array() == 0.0).all()) {
    Eigen::VectorXd hx;
    H.multiply(x, hx);
    r0 -= hx;
  }
  solveCorrection(H, b, r0, x, tolerance, iterations, residual);
}

void SpdSolver::solve(const SpMat& A, const Eigen::VectorXd& b, Eigen::VectorXd& x, double tolerance, int& iterations,
                      double& residual) {
  if (options_.preconditioner == CorotationalOptions::BlockJacobi ||
      options_.preconditioner == CorotationalOptions::TwoLevel) {
    // Their matrices are assembled as float blocks (NewtonMatrix), solved by the overloads above.
    throw std::logic_error("SpdSolver: the block CG takes a BlockSparseMatrix3f");
  } else if (options_.preconditioner == CorotationalOptions::Cholmod) {
    solveCholmod(A, b, x, iterations, residual);
  } else if (options_.preconditioner == CorotationalOptions::IncompleteCholesky) {
    solveIncompleteCholesky(A, b, x, tolerance, iterations, residual);
  } else {
    // A is symmetric with both triangles stored, so its column-major arrays are also its row-major
    // ones: seen row-major, Eigen's CG gathers its matrix-vector products row by row. (Single-
    // threaded: the core is built without OpenMP, so Eigen starts no threads of its own.)
    const Eigen::Map<const RowSpMat> rows(A.rows(), A.cols(), A.nonZeros(), A.outerIndexPtr(), A.innerIndexPtr(),
                                          A.valuePtr());
    Eigen::ConjugateGradient<RowSpMat, Eigen::Lower | Eigen::Upper, Eigen::DiagonalPreconditioner<double>> cg;
    cg.setTolerance(tolerance);
    cg.setMaxIterations(options_.maxCgIterations);
    cg.compute(rows);
    x = cg.solveWithGuess(b, x);
    iterations = int(cg.iterations());
    residual = cg.error();
  }
}

// Supernodal Cholesky: the symbolic analysis once (the pattern is fixed), the numeric factorization per call.
void SpdSolver::solveCholmod(const SpMat& A, const Eigen::VectorXd& b, Eigen::VectorXd& x, int& iterations,
                             double& residual) {
  if (!analyzed_) {
    cholmod_.cholmod().print = 0;  // failures are handled (and reported) here, not printed by CHOLMOD
    // One analysis serves every factorization of the relaxation: the linear model's outer iterations
    // or the nonlinear model's Newton steps (23 and 8 more in the strained region on the tiny phantom's
    // 45-degree pose; 10 counted), so METIS pays on smaller meshes than for the weights.
    const double factorizations = options_.model == CorotationalOptions::Linear ? options_.outerIterations : 10;
    analyzeWithFillOrdering(cholmod_, A, FillOrdering::Automatic, factorizations);
    analyzed_ = true;
  }
  cholmod_.setShift(0.0);
  cholmod_.factorize(A);
  if (cholmod_.info() != Eigen::Success) {
    // The projected Hessian is only semi-definite: a node whose tets have all been crushed flat
    // has no stiffness left. A shift of 1e-8 of the mean diagonal (a Levenberg step) restores
    // definiteness and changes the step by as little.
    cholmod_.setShift(1e-8 * A.diagonal().cwiseAbs().mean());
    cholmod_.factorize(A);
  }
  if (cholmod_.info() != Eigen::Success)
    throw std::runtime_error("relaxCorotational: CHOLMOD factorization failed (matrix not positive definite?)");
  x = cholmod_.solve(b);
  iterations = 0;
  const double bn = b.norm();
  residual = bn > 0 ? (A * x - b).norm() / bn : 0.0;
}

void SpdSolver::solveIncompleteCholesky(const SpMat& A, const Eigen::VectorXd& b, Eigen::VectorXd& x, double tolerance,
                                        int& iterations, double& residual) {
  Eigen::ConjugateGradient<SpMat, Eigen::Lower | Eigen::Upper,
                           Eigen::IncompleteCholesky<double, Eigen::Lower, Eigen::AMDOrdering<int>>>
      cg;
  cg.setTolerance(tolerance);
  cg.setMaxIterations(options_.maxCgIterations);
  cg.compute(A);
  if (cg.preconditioner().info() != Eigen::Success)
    throw std::runtime_error("relaxCorotational: incomplete Cholesky factorization failed");
  x = cg.solveWithGuess(b, x);
  iterations = int(cg.iterations());
  residual = cg.error();
}

void SpdSolver::solveCorrection(const BlockSparseMatrix3f& H, const Eigen::VectorXd& b, const Eigen::VectorXd& r0,
                                Eigen::VectorXd& x, double tolerance, int& iterations, double& residual) {
  const double bn = b.norm(), rn = r0.norm();
  iterations = 0;
  residual = bn > 0 ? rn / bn : 0.0;
  if (!(rn > tolerance * bn)) return;
  Eigen::VectorXd dx = Eigen::VectorXd::Zero(x.size());
  BlockCgResult r;
  if (options_.preconditioner == CorotationalOptions::TwoLevel && tolerance < options_.twoLevelBelowTolerance) {
    prepareTwoLevel(H);
    r = preconditionedBlockCg(H, r0, dx, tolerance * bn / rn, options_.maxCgIterations, twoLevel_);
  } else if (lowRank_ && !lowRank_->empty()) {  // block Jacobi with the low-rank term (Woodbury)
    if (!twoLevel_.aggregated()) twoLevel_.aggregate(H, freePositions(*rest_), options_.coarseAggregateSize);
    twoLevel_.updateFine(H);
    r = preconditionedBlockCg(H, r0, dx, tolerance * bn / rn, options_.maxCgIterations, twoLevel_);
  } else {
    r = blockJacobiCg(H, r0, dx, tolerance * bn / rn, options_.maxCgIterations);
  }
  x += dx;
  iterations = r.iterations;
  residual = r.relativeResidual * rn / bn;
}

Points SpdSolver::freePositions(const Points& all) const {
  Points p(Eigen::Index(freeNodes_->size()), 3);
  for (std::size_t i = 0; i < freeNodes_->size(); ++i) p.row(Eigen::Index(i)) = all.row((*freeNodes_)[i]);
  return p;
}

void SpdSolver::prepareTwoLevel(const BlockSparseMatrix3f& H) {
  if (!rest_) throw std::logic_error("SpdSolver: setNodes() is needed for the two-level preconditioner");
  if (!twoLevel_.aggregated()) twoLevel_.aggregate(H, freePositions(*rest_), options_.coarseAggregateSize);
  if (solvesOnCoarse_ > 0 && solvesOnCoarse_ < options_.coarseRefreshInterval && twoLevel_.coarseUsed()) {
    twoLevel_.updateFineKeepingCoarse(H);
    ++solvesOnCoarse_;
    return;
  }
  twoLevel_.update(H, freePositions(*current_));
  solvesOnCoarse_ = 1;
}

}  // namespace fem
}  // namespace repose
