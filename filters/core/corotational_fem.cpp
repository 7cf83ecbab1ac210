#include "corotational_fem.h"

#include <Eigen/CholmodSupport>
#include <Eigen/Geometry>
#include <Eigen/IterativeLinearSolvers>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/SVD>
#include <Eigen/Sparse>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <mutex>
#include <stdexcept>
#include <string>

#include "parallel_for.h"

namespace repose {
namespace {

double seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

using Mat3 = Eigen::Matrix3d;
using Vec3 = Eigen::Vector3d;
using SpMat = Eigen::SparseMatrix<double>;

Vec3 node(const Points& P, int i) { return P.row(i).transpose(); }

/// Rotation of F's polar decomposition, det = +1 even for inverted or degenerate F: the sign goes
/// to the smallest singular value (Irving et al. 2004), so an inverted tet is pushed back, not flipped.
Mat3 robustRotation(const Mat3& F) {
  Eigen::JacobiSVD<Mat3> svd(F, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat3 U = svd.matrixU();
  Mat3 V = svd.matrixV();
  if (U.determinant() < 0) U.col(2) *= -1.0;  // singular values are sorted: column 2 is the smallest
  if (V.determinant() < 0) V.col(2) *= -1.0;
  return U * V.transpose();
}

int countInverted(const Points& P, const Tets& tets) {
  std::atomic<int> count{0};
  parallelFor(std::size_t(tets.rows()), [&](std::size_t b, std::size_t e) {
    int local = 0;
    for (std::size_t t = b; t < e; ++t) {
      const auto T = tets.row(Eigen::Index(t));
      if (tetVolume(node(P, T[0]), node(P, T[1]), node(P, T[2]), node(P, T[3])) <= 0.0) ++local;
    }
    count += local;
  });
  return count.load();
}

/// Per-tet rest data. Row k of DmInv is the gradient of shape function N_{k+1}; N_0's is minus
/// their sum (gradients are recomputed rather than stored: memory is the limit on large meshes).
struct RestTet {
  Mat3 DmInv;
  double volume;
};

/// Shape-function gradients of a tet: row a is grad N_a.
Eigen::Matrix<double, 4, 3> gradients(const RestTet& rt) {
  Eigen::Matrix<double, 4, 3> g;
  g.bottomRows<3>() = rt.DmInv;
  g.row(0) = -rt.DmInv.colwise().sum();
  return g;
}

/// Solves the SPD system A x = b (x in: the guess) with the chosen method; for CHOLMOD the symbolic
/// analysis of the fixed pattern is done once and reused by later calls.
class SpdSolver {
 public:
  explicit SpdSolver(const CorotationalOptions& o) : options_(o) {}

  void solve(const SpMat& A, const Eigen::VectorXd& b, Eigen::VectorXd& x, double tolerance, int& iterations,
             double& residual) {
    if (options_.preconditioner == CorotationalOptions::Cholmod) {
      if (!analyzed_) {
        // METIS nested dissection (as for the harmonic weights); CHOLMOD's defaults without METIS.
        cholmod_.cholmod().nmethods = 1;
        cholmod_.cholmod().method[0].ordering = CHOLMOD_METIS;
        cholmod_.analyzePattern(A);
        if (cholmod_.info() != Eigen::Success) {
          cholmod_.cholmod().nmethods = 0;
          cholmod_.cholmod().method[0].ordering = CHOLMOD_GIVEN;
          cholmod_.analyzePattern(A);
        }
        analyzed_ = true;
      }
      cholmod_.factorize(A);
      if (cholmod_.info() != Eigen::Success)
        throw std::runtime_error("relaxCorotational: CHOLMOD factorization failed (matrix not positive definite?)");
      x = cholmod_.solve(b);
      iterations = 0;
      const double bn = b.norm();
      residual = bn > 0 ? (A * x - b).norm() / bn : 0.0;
    } else if (options_.preconditioner == CorotationalOptions::IncompleteCholesky) {
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
    } else {
      // Eigen's serial CG: measured faster than a parallelFor-threaded CG (its column-major
      // scatter product beats a threaded gather on 2 cores).
      Eigen::ConjugateGradient<SpMat, Eigen::Lower | Eigen::Upper, Eigen::DiagonalPreconditioner<double>> cg;
      cg.setTolerance(tolerance);
      cg.setMaxIterations(options_.maxCgIterations);
      cg.compute(A);
      x = cg.solveWithGuess(b, x);
      iterations = int(cg.iterations());
      residual = cg.error();
    }
  }

 private:
  const CorotationalOptions& options_;
  Eigen::CholmodSupernodalLLT<SpMat, Eigen::Lower> cholmod_;
  bool analyzed_ = false;
};

/// Per-tet state of the fixed-corotated energy at a pose: Irving's signed SVD F = U diag(sigma) V^T
/// (det U = det V = +1, an inverted tet has sigma(2) < 0). Stress, cofactor and Hessian follow from it.
struct TetState {
  Mat3 U, V;
  Vec3 sigma;
};

/// Gauss-Newton minimization of the fixed-corotated energy over the free nodes (see the header).
void relaxFixedCorotated(const Tets& tets, Points& posed, const CorotationalOptions& options,
                         CorotationalReport& rep, const std::vector<RestTet>& restTets,
                         const std::vector<int>& fixedBone, const std::vector<int>& dof,
                         const std::vector<int>& freeNodes, const std::vector<int>& incStart,
                         const std::vector<int>& incTet, SpMat& A, SpdSolver& solver, double lambda, double mu) {
  const std::size_t nT = std::size_t(tets.rows()), nFree = freeNodes.size();
  const Eigen::Index n = Eigen::Index(3 * nFree);
  double edgeSum = 0;  // mean rest edge length: the scale of the step tolerance
  for (const RestTet& rt : restTets) {
    const Mat3 Dm = rt.DmInv.inverse();
    edgeSum += Dm.colwise().norm().sum() + (Dm.col(1) - Dm.col(0)).norm() + (Dm.col(2) - Dm.col(0)).norm() +
               (Dm.col(2) - Dm.col(1)).norm();
  }
  const double stepLimit = options.stepTolerance * edgeSum / (6.0 * double(std::max<std::size_t>(nT, 1)));

  std::vector<TetState> state(nT);
  // Energy and inverted-tet count of a pose; always refreshes the per-tet state (a rejected trial's
  // state is overwritten by the next trial, an accepted one's is the state of the new iterate).
  auto evaluate = [&](const Points& x, int& inverted) {
    std::mutex lock;
    double energy = 0;
    int count = 0;
    parallelFor(nT, [&](std::size_t b, std::size_t e) {
      double localEnergy = 0;
      int localCount = 0;
      for (std::size_t t = b; t < e; ++t) {
        const auto T = tets.row(Eigen::Index(t));
        const RestTet& rt = restTets[t];
        Mat3 Ds;
        const Vec3 x0 = node(x, T[0]);
        for (int k = 0; k < 3; ++k) Ds.col(k) = node(x, T[k + 1]) - x0;
        const Mat3 F = Ds * rt.DmInv;
        Eigen::JacobiSVD<Mat3> svd(F, Eigen::ComputeFullU | Eigen::ComputeFullV);
        Mat3 U = svd.matrixU(), V = svd.matrixV();
        Vec3 sigma = svd.singularValues();
        // Irving's signed SVD: det U = det V = +1, an inverted tet gets a negative smallest stretch.
        if (U.determinant() < 0) U.col(2) *= -1.0, sigma(2) = -sigma(2);
        if (V.determinant() < 0) V.col(2) *= -1.0, sigma(2) = -sigma(2);
        const double J = sigma.prod();
        if (J <= 0.0) ++localCount;
        localEnergy += rt.volume * (mu * (sigma - Vec3::Ones()).squaredNorm() + 0.5 * lambda * (J - 1.0) * (J - 1.0));
        state[t] = TetState{U, V, sigma};
      }
      std::lock_guard<std::mutex> guard(lock);
      energy += localEnergy;
      count += localCount;
    }, 512);
    inverted = count;
    return energy;
  };

  // Gradient and projected Hessian, row-wise over the free nodes (no write conflicts).
  Eigen::VectorXd grad(n);
  auto assemble = [&]() {
    double* values = A.valuePtr();
    const int* inner = A.innerIndexPtr();
    const int* outerIdx = A.outerIndexPtr();
    parallelFor(nFree, [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i) {
        const int rowLen = (outerIdx[3 * i + 1] - outerIdx[3 * i]) / 3;
        const int* cols = inner + outerIdx[3 * i];
        double* v0 = values + outerIdx[3 * i];
        std::fill(v0, v0 + 9 * rowLen, 0.0);
        Vec3 gi = Vec3::Zero();
        for (int k = incStart[i]; k < incStart[i + 1]; ++k) {
          const int t = incTet[std::size_t(k)] / 4, a = incTet[std::size_t(k)] % 4;
          const RestTet& rt = restTets[std::size_t(t)];
          const TetState& st = state[std::size_t(t)];
          const Vec3& s = st.sigma;
          const double J = s.prod();
          const double pressure = lambda * (J - 1.0);
          const Vec3 cofS(s(1) * s(2), s(0) * s(2), s(0) * s(1));  // cof F = U diag(cofS) V^T
          // Projected Newton (Smith et al. 2019): the Hessian of psi in F is diagonal in the modes
          // U M V^T: twist / flip of each pair (i, j) (third index l) with eigenvalues
          // mu (2 - 4 / (s_i + s_j)) + p s_l and 2 mu - p s_l, and a 3x3 block on the scalings,
          // 2 mu I + lambda cofS cofS^T + p d2J/ds2; negative eigenvalues are clamped to 0.
          static const int pairI[3] = {0, 1, 0}, pairJ[3] = {1, 2, 2}, pairL[3] = {2, 0, 1};
          double twist[3], flip[3];
          for (int m = 0; m < 3; ++m) {
            const double sum = s(pairI[m]) + s(pairJ[m]);
            const double arap = std::abs(sum) > 1e-12 ? mu * (2.0 - 4.0 / sum) : 0.0;
            twist[m] = std::max(0.0, arap + pressure * s(pairL[m]));
            flip[m] = std::max(0.0, 2.0 * mu - pressure * s(pairL[m]));
          }
          Mat3 S = 2.0 * mu * Mat3::Identity() + lambda * cofS * cofS.transpose();
          S(0, 1) += pressure * s(2), S(1, 0) += pressure * s(2);
          S(1, 2) += pressure * s(0), S(2, 1) += pressure * s(0);
          S(0, 2) += pressure * s(1), S(2, 0) += pressure * s(1);
          Eigen::SelfAdjointEigenSolver<Mat3> eig;
          eig.computeDirect(S);
          const Vec3 scaleValues = eig.eigenvalues().cwiseMax(0.0);
          const Mat3& E = eig.eigenvectors();
          const Eigen::Matrix<double, 4, 3> g = gradients(rt);
          // Each mode applied to each node's gradient (w = V^T g_b), scaled by sqrt(eigenvalue).
          Eigen::Matrix<double, 3, 4> tv[3], fv[3], sv[3];
          for (int bb = 0; bb < 4; ++bb) {
            const Vec3 w = st.V.transpose() * g.row(bb).transpose();
            for (int m = 0; m < 3; ++m) {
              Vec3 tw = Vec3::Zero(), fl = Vec3::Zero();
              tw(pairI[m]) = -w(pairJ[m]);
              tw(pairJ[m]) = w(pairI[m]);
              fl(pairI[m]) = w(pairJ[m]);
              fl(pairJ[m]) = w(pairI[m]);
              tv[m].col(bb) = st.U * tw * std::sqrt(0.5 * twist[m]);
              fv[m].col(bb) = st.U * fl * std::sqrt(0.5 * flip[m]);
              sv[m].col(bb) = st.U * E.col(m).cwiseProduct(w) * std::sqrt(scaleValues(m));
            }
          }
          const Vec3 wa = st.V.transpose() * g.row(a).transpose();
          // Force: P g_a with P = U diag(2 mu (s - 1) + p cofS) V^T, times the volume.
          gi += rt.volume * (st.U * (2.0 * mu * (s - Vec3::Ones()) + pressure * cofS).cwiseProduct(wa));
          for (int bb = 0; bb < 4; ++bb) {
            const int v = tets(t, bb);
            if (fixedBone[std::size_t(v)] >= 0) continue;  // Dirichlet: no increment
            Mat3 block = Mat3::Zero();
            for (int m = 0; m < 3; ++m)
              block += tv[m].col(a) * tv[m].col(bb).transpose() + fv[m].col(a) * fv[m].col(bb).transpose() +
                       sv[m].col(a) * sv[m].col(bb).transpose();
            block *= rt.volume;
            const int col = 3 * dof[std::size_t(v)];
            const std::size_t off = std::size_t(std::lower_bound(cols, cols + 3 * rowLen, col) - cols);
            for (int cc = 0; cc < 3; ++cc) {
              double* vc = v0 + 3 * cc * rowLen + off;
              for (int d = 0; d < 3; ++d) vc[d] += block(cc, d);
            }
          }
        }
        grad.segment<3>(Eigen::Index(3 * i)) = gi;
      }
    }, 256);
  };

  int inverted = 0;
  double energy = evaluate(posed, inverted);
  rep.energyBefore = energy;
  Points trial = posed;
  Eigen::VectorXd step(n);
  double firstNorm = -1.0;
  for (int it = 0; it < options.maxNewtonIterations; ++it) {
    const auto assemblyStart = std::chrono::steady_clock::now();
    assemble();
    rep.assemblySeconds += seconds(assemblyStart);
    const double gradNorm = grad.norm();
    if (firstNorm < 0) firstNorm = gradNorm;
    if (!(gradNorm > 0.0)) {
      rep.converged = true;
      break;
    }
    // Inexact Newton: the CG tolerance tightens as the gradient falls.
    const double eta = std::clamp(gradNorm / firstNorm, options.tolerance, 0.1);
    const auto solveStart = std::chrono::steady_clock::now();
    step.setZero();
    int iterations = 0;
    double residual = 0.0;
    solver.solve(A, -grad, step, eta, iterations, residual);
    rep.solveSeconds += seconds(solveStart);
    rep.cgIterations.push_back(iterations);
    rep.relativeResidual.push_back(residual);
    rep.newtonIterations = rep.outerIterations = it + 1;

    double maxMove = 0;
    for (std::size_t i = 0; i < nFree; ++i) maxMove = std::max(maxMove, step.segment<3>(Eigen::Index(3 * i)).norm());
    const double slope = grad.dot(step);
    double alpha = 1.0;
    bool accepted = false, smallDecrease = false;
    for (int halving = 0; halving < 40 && alpha * maxMove > 1e-3 * stepLimit; ++halving, alpha *= 0.5) {
      for (std::size_t i = 0; i < nFree; ++i)
        trial.row(freeNodes[i]) = posed.row(freeNodes[i]) + alpha * step.segment<3>(Eigen::Index(3 * i)).transpose();
      int trialInverted = 0;
      const double trialEnergy = evaluate(trial, trialInverted);
      if (trialInverted <= inverted && trialEnergy <= energy + 1e-4 * alpha * std::min(slope, 0.0)) {
        smallDecrease = energy - trialEnergy < options.energyTolerance * energy;
        energy = trialEnergy;
        inverted = trialInverted;
        accepted = true;
        break;
      }
    }
    if (!accepted) {  // no descent left at this precision: at the minimum
      rep.converged = maxMove < stepLimit;
      break;
    }
    for (std::size_t i = 0; i < nFree; ++i) posed.row(freeNodes[i]) = trial.row(freeNodes[i]);
    if (alpha * maxMove < stepLimit || smallDecrease) {
      rep.converged = true;
      break;
    }
  }
  rep.energyAfter = energy;
}

}  // namespace

void relaxCorotational(const Points& rest, const Tets& tets, const std::vector<int>& fixedBone,
                       Points& posed, const CorotationalOptions& options, CorotationalReport* report) {
  const auto start = std::chrono::steady_clock::now();
  const Eigen::Index nV = rest.rows();
  const Eigen::Index nT = tets.rows();
  if (posed.rows() != nV)
    throw std::invalid_argument("relaxCorotational: posed has " + std::to_string(posed.rows()) +
                                " nodes but rest has " + std::to_string(nV));
  if (Eigen::Index(fixedBone.size()) != nV)
    throw std::invalid_argument("relaxCorotational: fixedBone has " + std::to_string(fixedBone.size()) +
                                " entries but the mesh has " + std::to_string(nV) + " nodes");
  if (!(options.poisson > -1.0 && options.poisson < 0.5))
    throw std::invalid_argument("relaxCorotational: Poisson's ratio must be in (-1, 0.5), got " +
                                std::to_string(options.poisson));
  if (!(options.young > 0.0) || !std::isfinite(options.young))
    throw std::invalid_argument("relaxCorotational: Young's modulus must be positive");
  if (options.outerIterations < 1)
    throw std::invalid_argument("relaxCorotational: outerIterations must be >= 1");
  if (!(options.tolerance > 0.0))
    throw std::invalid_argument("relaxCorotational: tolerance must be positive");
  if (options.maxCgIterations < 1)
    throw std::invalid_argument("relaxCorotational: maxCgIterations must be >= 1");
  if (options.maxNewtonIterations < 1)
    throw std::invalid_argument("relaxCorotational: maxNewtonIterations must be >= 1");
  if (!(options.stepTolerance > 0.0))
    throw std::invalid_argument("relaxCorotational: stepTolerance must be positive");
  if (!(options.energyTolerance >= 0.0))
    throw std::invalid_argument("relaxCorotational: energyTolerance must be >= 0");
  for (Eigen::Index t = 0; t < nT; ++t)
    for (int a = 0; a < 4; ++a)
      if (tets(t, a) < 0 || tets(t, a) >= nV)
        throw std::invalid_argument("relaxCorotational: tet " + std::to_string(t) +
                                    " has node index " + std::to_string(tets(t, a)) +
                                    " outside [0, " + std::to_string(nV) + ")");
  const bool anyFixed = std::any_of(fixedBone.begin(), fixedBone.end(), [](int b) { return b >= 0; });
  if (nV > 0 && !anyFixed)
    throw std::invalid_argument(
        "relaxCorotational: no node is fixed; the elastic system is singular (mark bone nodes "
        "with fixedBone >= 0)");

  CorotationalReport local;
  CorotationalReport& rep = report ? *report : local;
  rep = CorotationalReport{};
  rep.invertedBefore = countInverted(posed, tets);

  // Unknowns: free nodes that belong to at least one tet (a node in no tet has no stiffness).
  std::vector<int> dof(std::size_t(nV), -1);
  for (Eigen::Index t = 0; t < nT; ++t)
    for (int a = 0; a < 4; ++a)
      if (fixedBone[std::size_t(tets(t, a))] < 0) dof[std::size_t(tets(t, a))] = 0;
  std::vector<int> freeNodes;
  for (Eigen::Index i = 0; i < nV; ++i)
    if (dof[std::size_t(i)] == 0) {
      dof[std::size_t(i)] = int(freeNodes.size());
      freeNodes.push_back(int(i));
    }
  const std::size_t nFree = freeNodes.size();

  // Rest data per tet (shape-function gradients and volume); rest tets must be positive.
  std::vector<RestTet> restTets(static_cast<std::size_t>(nT));
  std::atomic<long long> badTet{-1};
  parallelFor(std::size_t(nT), [&](std::size_t b, std::size_t e) {
    for (std::size_t t = b; t < e; ++t) {
      const auto T = tets.row(Eigen::Index(t));
      Mat3 Dm;
      const Vec3 x0 = node(rest, T[0]);
      for (int k = 0; k < 3; ++k) Dm.col(k) = node(rest, T[k + 1]) - x0;
      const double det = Dm.determinant();
      RestTet& r = restTets[t];
      r.volume = det / 6.0;
      const double scale = Dm.colwise().norm().maxCoeff();
      if (!(det > 1e-12 * scale * scale * scale)) {
        badTet = (long long)t;
        continue;
      }
      r.DmInv = Dm.inverse();
    }
  });
  if (badTet >= 0)
    throw std::invalid_argument("relaxCorotational: rest tet " + std::to_string(badTet.load()) +
                                " is degenerate or inverted (rest volume must be > 0)");

  if (nFree == 0) {
    rep.invertedAfter = rep.invertedBefore;
    rep.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return;
  }

  // Node -> incident (tet, local index) lists, for free nodes only (CSR).
  std::vector<int> incStart(nFree + 1, 0);
  for (Eigen::Index t = 0; t < nT; ++t)
    for (int a = 0; a < 4; ++a) {
      const int d = dof[std::size_t(tets(t, a))];
      if (d >= 0 && fixedBone[std::size_t(tets(t, a))] < 0) ++incStart[std::size_t(d) + 1];
    }
  for (std::size_t i = 0; i < nFree; ++i) incStart[i + 1] += incStart[i];
  std::vector<int> incTet(static_cast<std::size_t>(incStart[nFree]));
  {
    std::vector<int> fill(incStart);  // next write position per free node
    for (Eigen::Index t = 0; t < nT; ++t)
      for (int a = 0; a < 4; ++a) {
        const int v = tets(t, a);
        if (fixedBone[std::size_t(v)] < 0) incTet[std::size_t(fill[std::size_t(dof[std::size_t(v)])]++)] = int(t) * 4 + a;
      }
  }

  // Block sparsity pattern: row i holds its free neighbours (and itself), sorted.
  std::vector<int> rowStart(nFree + 1, 0);
  std::vector<std::vector<int>> rowCols;
  rowCols.resize(nFree);
  parallelFor(nFree, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      std::vector<int>& cols = rowCols[i];
      for (int k = incStart[i]; k < incStart[i + 1]; ++k) {
        const int t = incTet[std::size_t(k)] / 4;
        for (int c = 0; c < 4; ++c) {
          const int v = tets(t, c);
          if (fixedBone[std::size_t(v)] < 0) cols.push_back(dof[std::size_t(v)]);
        }
      }
      std::sort(cols.begin(), cols.end());
      cols.erase(std::unique(cols.begin(), cols.end()), cols.end());
    }
  });
  for (std::size_t i = 0; i < nFree; ++i) rowStart[i + 1] = rowStart[i] + int(rowCols[i].size());
  const Eigen::Index n = Eigen::Index(3 * nFree);
  // Symmetric, so the column-major arrays are filled row by row: column 3i+c holds row 3i+c.
  SpMat A(n, n);
  A.resizeNonZeros(Eigen::Index(9) * rowStart[nFree]);
  for (std::size_t i = 0; i < nFree; ++i)
    for (int c = 0; c < 3; ++c) A.outerIndexPtr()[3 * i + c] = 9 * rowStart[i] + 3 * c * int(rowCols[i].size());
  A.outerIndexPtr()[n] = 9 * rowStart[nFree];
  parallelFor(nFree, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      const std::vector<int>& cols = rowCols[i];
      for (int c = 0; c < 3; ++c) {
        int* inner = A.innerIndexPtr() + A.outerIndexPtr()[3 * i + c];
        for (std::size_t k = 0; k < cols.size(); ++k)
          for (int d = 0; d < 3; ++d) inner[3 * k + std::size_t(d)] = 3 * cols[k] + d;
      }
    }
  });
  rowCols.clear();
  rowCols.shrink_to_fit();

  const double nu = options.poisson, E = options.young;
  const double lambda = E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
  const double mu = E / (2.0 * (1.0 + nu));

  SpdSolver solver(options);
  if (options.model == CorotationalOptions::FixedCorotated) {
    relaxFixedCorotated(tets, posed, options, rep, restTets, fixedBone, dof, freeNodes, incStart, incTet, A, solver,
                        lambda, mu);
    rep.invertedAfter = countInverted(posed, tets);
    rep.seconds = seconds(start);
    return;
  }
  std::vector<Mat3> rotation(static_cast<std::size_t>(nT));
  Eigen::VectorXd rhs(n), x(n);
  for (int outer = 0; outer < options.outerIterations; ++outer) {
    const auto assemblyStart = std::chrono::steady_clock::now();
    // Element rotations from the current pose.
    parallelFor(std::size_t(nT), [&](std::size_t b, std::size_t e) {
      for (std::size_t t = b; t < e; ++t) {
        const auto T = tets.row(Eigen::Index(t));
        Mat3 Ds;
        const Vec3 x0 = node(posed, T[0]);
        for (int k = 0; k < 3; ++k) Ds.col(k) = node(posed, T[k + 1]) - x0;
        rotation[t] = robustRotation(Ds * restTets[t].DmInv);
      }
    });
    // Row-wise assembly (no write conflicts): for free node i = local a of tet t, the blocks
    // K'_ab = R K_ab R^T with K_ab = V (lambda g_a g_b^T + mu g_b g_a^T + mu (g_a.g_b) I), and
    // rhs_i = sum_t R sum_b K_ab x0_b  -  sum_{b fixed} K'_ab x_b.
    double* values = A.valuePtr();
    const int* inner = A.innerIndexPtr();
    const int* outerIdx = A.outerIndexPtr();
    parallelFor(nFree, [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i) {
        const int rowLen = (outerIdx[3 * i + 1] - outerIdx[3 * i]) / 3;  // blocks in the row
        const int* cols = inner + outerIdx[3 * i];                       // scalar columns of row 3i
        double* v0 = values + outerIdx[3 * i];
        std::fill(v0, v0 + 9 * rowLen, 0.0);
        Vec3 r = Vec3::Zero();
        for (int k = incStart[i]; k < incStart[i + 1]; ++k) {
          const int t = incTet[std::size_t(k)] / 4, a = incTet[std::size_t(k)] % 4;
          const RestTet& rt = restTets[std::size_t(t)];
          const Mat3& R = rotation[std::size_t(t)];
          Eigen::Matrix<double, 4, 3> g;
          g.bottomRows<3>() = rt.DmInv;
          g.row(0) = -rt.DmInv.colwise().sum();
          const Vec3 ga = g.row(a).transpose();
          const Vec3 xr0 = node(rest, tets(t, 0));
          Vec3 restForce = Vec3::Zero();
          for (int bb = 0; bb < 4; ++bb) {
            const Vec3 gb = g.row(bb).transpose();
            const Mat3 Kab = rt.volume * (lambda * ga * gb.transpose() + mu * gb * ga.transpose() +
                                          mu * ga.dot(gb) * Mat3::Identity());
            restForce += Kab * (node(rest, tets(t, bb)) - xr0);  // K annihilates translations
            const Mat3 block = R * Kab * R.transpose();
            const int v = tets(t, bb);
            if (fixedBone[std::size_t(v)] >= 0) {
              r -= block * node(posed, v);
            } else {
              const int col = 3 * dof[std::size_t(v)];
              const int* pos = std::lower_bound(cols, cols + 3 * rowLen, col);
              const std::size_t off = std::size_t(pos - cols);
              for (int c = 0; c < 3; ++c) {
                double* vc = v0 + 3 * c * rowLen + off;
                for (int d = 0; d < 3; ++d) vc[d] += block(c, d);
              }
            }
          }
          r += R * restForce;
        }
        rhs.segment<3>(Eigen::Index(3 * i)) = r;
        x.segment<3>(Eigen::Index(3 * i)) = node(posed, freeNodes[i]);
      }
    }, 256);

    rep.assemblySeconds += seconds(assemblyStart);
    const auto solveStart = std::chrono::steady_clock::now();
    int iterations = 0;
    double residual = 0.0;
    solver.solve(A, rhs, x, options.tolerance, iterations, residual);
    rep.solveSeconds += seconds(solveStart);
    for (std::size_t i = 0; i < nFree; ++i)
      posed.row(freeNodes[i]) = x.segment<3>(Eigen::Index(3 * i)).transpose();
    rep.cgIterations.push_back(iterations);
    rep.relativeResidual.push_back(residual);
    rep.outerIterations = outer + 1;
  }
  rep.invertedAfter = countInverted(posed, tets);
  rep.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace repose
