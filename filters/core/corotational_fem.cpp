#include "corotational_fem.h"

#include <Eigen/CholmodSupport>
#include <Eigen/Geometry>
#include <Eigen/IterativeLinearSolvers>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/Sparse>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <mutex>
#include <stdexcept>
#include <string>

#include "blas_threads.h"
#include "bone_path.h"
#include "continuation_stall.h"
#include "pinched_nodes.h"
#include "block_sparse_cg.h"
#include "parallel_for.h"
#include "signed_svd.h"
#include "tet_turning_point.h"
#include "tet_untangling.h"
#include "two_level_preconditioner.h"
#include "volume_term.h"

namespace repose {
namespace {

// The free nodes of centre and `rings` rings of free neighbours (nodes sharing a tet), as flags.
std::vector<char> grownNeighbourhood(const Tets& tets, const std::vector<int>& fixedBone, const std::vector<int>& centre,
                                     int rings);
// relaxNeighbourhood on the flagged unknowns, with the phase its checkpoint reports; returns their count.
int relaxPart(const Points& rest, const Tets& tets, const std::vector<int>& fixedBone, Points& posed,
              const std::vector<char>& active, const CorotationalOptions& options, RelaxationProgress::Phase phase,
              CorotationalReport* report);

// The strained region goes first only while it is at most this fraction of the free nodes. A pose that
// moves every joint strains most of the body (the CMU walk's first frame: 85 % on medium, where the part
// first takes 49 s in place of 58 s); all of the free nodes is the whole mesh twice (small, 45 degree
// pose: 14.0 s in place of 11.2 s).
constexpr double kStrainedRegionLargestPart = 0.9;

double seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

using Mat3 = Eigen::Matrix3d;
using Vec3 = Eigen::Vector3d;
using SpMat = Eigen::SparseMatrix<double>;
using RowSpMat = Eigen::SparseMatrix<double, Eigen::RowMajor>;

Vec3 node(const Points& P, int i) { return P.row(i).transpose(); }

/// Rotation of F's polar decomposition, det = +1 even for inverted or degenerate F: the sign goes
/// to the smallest singular value (Irving et al. 2004), so an inverted tet is pushed back, not flipped.
Mat3 robustRotation(const Mat3& F) {
  Mat3 U, V;
  Vec3 sigma;
  signedSvd(F, U, sigma, V);
  return U * V.transpose();
}

/// Whether tet t has a free node (one no bone holds).
bool hasFreeNode(const Tets& tets, const std::vector<int>& fixedBone, std::size_t t) {
  for (int a = 0; a < 4; ++a)
    if (fixedBone[std::size_t(tets(Eigen::Index(t), a))] < 0) return true;
  return false;
}

/// Tets with signed volume <= 0; with `only`, among the tets it flags.
int countInverted(const Points& P, const Tets& tets, const std::vector<char>* only = nullptr) {
  std::atomic<int> count{0};
  parallelFor(std::size_t(tets.rows()), [&](std::size_t b, std::size_t e) {
    int local = 0;
    for (std::size_t t = b; t < e; ++t) {
      if (only && !(*only)[t]) continue;
      const auto T = tets.row(Eigen::Index(t));
      if (tetVolume(node(P, T[0]), node(P, T[1]), node(P, T[2]), node(P, T[3])) <= 0.0) ++local;
    }
    count += local;
  });
  return count.load();
}

/// Whether some tet positive in `from` is flat or inverted in `to`.
bool turnsAPositiveTet(const Points& from, const Points& to, const Tets& tets) {
  std::atomic<bool> turned{false};
  parallelFor(std::size_t(tets.rows()), [&](std::size_t b, std::size_t e) {
    for (std::size_t t = b; t < e && !turned.load(std::memory_order_relaxed); ++t) {
      const auto T = tets.row(Eigen::Index(t));
      if (tetVolume(node(to, T[0]), node(to, T[1]), node(to, T[2]), node(to, T[3])) <= 0.0 &&
          tetVolume(node(from, T[0]), node(from, T[1]), node(from, T[2]), node(from, T[3])) > 0.0)
        turned = true;
    }
  });
  return turned.load();
}

/// Whether a line-search trial can be accepted at all, from the signs of the tet volumes alone (no
/// per-tet SVD): no more inverted tets than `inverted`, and no tet under the log barrier at det F <= 0,
/// where its energy is infinite. (The count alone lets a barrier tet flip while penalty tets unfold.)
bool trialAdmissible(const Points& P, const Tets& tets, const std::vector<char>& barrier, int inverted) {
  std::atomic<int> count{0};
  std::atomic<bool> barrierCrossed{false};
  parallelFor(std::size_t(tets.rows()), [&](std::size_t b, std::size_t e) {
    int local = 0;
    bool crossed = false;
    for (std::size_t t = b; t < e; ++t) {
      const auto T = tets.row(Eigen::Index(t));
      if (tetVolume(node(P, T[0]), node(P, T[1]), node(P, T[2]), node(P, T[3])) > 0.0) continue;
      ++local;
      crossed = crossed || barrier[t];
    }
    count += local;
    if (crossed) barrierCrossed = true;
  });
  return !barrierCrossed.load() && count.load() <= inverted;
}

/// Tells options.checkpoint where the solve is; throws RelaxationCancelled when it answers true.
void reachCheckpoint(const CorotationalOptions& options, const RelaxationProgress& progress) {
  if (options.checkpoint && options.checkpoint(progress)) throw RelaxationCancelled();
}

/// The report's inverted counts after relaxing: all of them, and those no free node can repair.
void countInvertedAfter(const Points& P, const Tets& tets, const std::vector<int>& fixedBone, CorotationalReport& rep) {
  rep.invertedAfter = rep.invertedRigid = 0;
  for (Eigen::Index t = 0; t < tets.rows(); ++t) {
    const auto T = tets.row(t);
    if (tetVolume(node(P, T[0]), node(P, T[1]), node(P, T[2]), node(P, T[3])) > 0.0) continue;
    ++rep.invertedAfter;
    bool rigid = true;
    for (int a = 0; a < 4; ++a) rigid = rigid && fixedBone[std::size_t(T[a])] >= 0;
    if (rigid) ++rep.invertedRigid;
  }
  rep.pinchedNodes = 0;
  rep.pinchedShortfall = 0.0;
  if (rep.invertedAfter == rep.invertedRigid) return;  // no fold a node could be pinched in
  for (const PinchedNode& p : findPinchedNodes(P, tets, fixedBone)) {
    ++rep.pinchedNodes;
    rep.pinchedShortfall = std::max(rep.pinchedShortfall, p.shortfall);
  }
}

/// Per-tet rest data. Row k of DmInv is the gradient of shape function N_{k+1}; N_0's is minus
/// their sum (gradients are recomputed rather than stored: memory is the limit on large meshes).
struct RestTet {
  Mat3 DmInv;
  double volume;
};

/// incColumn's mark for a block the Newton matrix does not store (below the diagonal of an upper one).
constexpr std::uint16_t kNotStored = 0xFFFF;

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

  /// The nodes behind the unknowns (TwoLevel's aggregates and rigid modes): rest and current
  /// positions of all nodes (current may change between solves) and the free node of each block row.
  void setNodes(const Points& rest, const Points& current, const std::vector<int>& freeNodes) {
    rest_ = &rest;
    current_ = &current;
    freeNodes_ = &freeNodes;
  }
  /// A low-rank term added to the matrices given to solve() (BlockJacobi and TwoLevel only).
  void setLowRank(const LowRankTerm3* lowRank) { lowRank_ = lowRank; }

  /// Block CG on float blocks (BlockJacobi and TwoLevel), the residual of the guess in H's own
  /// precision (exact when x = 0, as in Newton's solves).
  void solve(BlockSparseMatrix3f& H, const Eigen::VectorXd& b, Eigen::VectorXd& x, double tolerance, int& iterations,
             double& residual) {
    H.lowRank = lowRank_;
    Eigen::VectorXd r0 = b;
    if (!(x.array() == 0.0).all()) {
      Eigen::VectorXd hx;
      H.multiply(x, hx);
      r0 -= hx;
    }
    solveCorrection(H, b, r0, x, tolerance, iterations, residual);
  }

  void solve(const SpMat& A, const Eigen::VectorXd& b, Eigen::VectorXd& x, double tolerance, int& iterations,
             double& residual) {
    if (options_.preconditioner == CorotationalOptions::BlockJacobi ||
        options_.preconditioner == CorotationalOptions::TwoLevel) {
      // Their matrices are assembled as float blocks (NewtonMatrix), solved by the overloads above.
      throw std::logic_error("SpdSolver: the block CG takes a BlockSparseMatrix3f");
    } else if (options_.preconditioner == CorotationalOptions::Cholmod) {
      if (!analyzed_) {
        // METIS nested dissection (as for the harmonic weights); CHOLMOD's defaults without METIS.
        cholmod_.cholmod().print = 0;  // failures are handled (and reported) here, not printed by CHOLMOD
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

  /// x += the block CG's solution of H dx = r0 (r0 = b - A x, e.g. summed in double by the caller),
  /// to tolerance relative to |b|.
  void solveCorrection(const BlockSparseMatrix3f& H, const Eigen::VectorXd& b, const Eigen::VectorXd& r0,
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

 private:
  Points freePositions(const Points& all) const {
    Points p(Eigen::Index(freeNodes_->size()), 3);
    for (std::size_t i = 0; i < freeNodes_->size(); ++i) p.row(Eigen::Index(i)) = all.row((*freeNodes_)[i]);
    return p;
  }

  /// Aggregates from the rest pose once (the pattern is fixed), the coarse matrix per solve.
  void prepareTwoLevel(const BlockSparseMatrix3f& H) {
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

  const CorotationalOptions& options_;
  Eigen::CholmodSupernodalLLT<SpMat, Eigen::Lower> cholmod_;
  bool analyzed_ = false;
  TwoLevelPreconditioner twoLevel_;
  int solvesOnCoarse_ = 0;  // solves that have used twoLevel_'s coarse level (see coarseRefreshInterval)
  const Points* rest_ = nullptr;
  const Points* current_ = nullptr;
  const std::vector<int>* freeNodes_ = nullptr;
  const LowRankTerm3* lowRank_ = nullptr;
};

/// The Newton matrix over the free nodes, block row i for free node i. For the block CG (BlockJacobi,
/// TwoLevel) float 3x3 blocks of the upper triangle, assembled in place: no double matrix to fill and
/// convert, half the blocks to compute, half the traffic per CG product. For CHOLMOD, incomplete
/// Cholesky and Eigen's CG, scalar double CSR with both triangles (symmetric, so column 3i + c holds
/// row 3i + c: block row i's blocks in column order, 3 scalars each).
struct NewtonMatrix {
  bool blocked = false;
  BlockSparseMatrix3f blocks;
  SpMat scalar;

  int rowLength(std::size_t i) const {
    return blocked ? blocks.rowStart[i + 1] - blocks.rowStart[i]
                   : (scalar.outerIndexPtr()[3 * i + 1] - scalar.outerIndexPtr()[3 * i]) / 3;
  }
  /// Block row i from rowBlocks: rowLength(i) blocks of 9 doubles (row-major), in column order.
  void setRow(std::size_t i, const double* rowBlocks) {
    const int len = rowLength(i);
    if (blocked) {
      float* dst = blocks.values.data() + 9 * std::size_t(blocks.rowStart[i]);
      for (int k = 0; k < 9 * len; ++k) dst[k] = float(rowBlocks[k]);
      return;
    }
    double* v0 = scalar.valuePtr() + scalar.outerIndexPtr()[3 * i];
    for (int k = 0; k < len; ++k)
      for (int c = 0; c < 3; ++c)
        for (int d = 0; d < 3; ++d) v0[3 * c * len + 3 * k + d] = rowBlocks[9 * k + 3 * c + d];
  }
};

/// Per-tet state of the fixed-corotated energy at a pose: Irving's signed SVD F = U diag(sigma) V^T
/// (det U = det V = +1, an inverted tet has sigma(2) < 0). Stress, cofactor and Hessian follow from it.
struct TetState {
  Mat3 U, V;
  Vec3 sigma;
};

/// Gauss-Newton minimization of the fixed-corotated energy over the free nodes (see the header).
void relaxFixedCorotated(const Points& rest, const Tets& tets, Points& posed, const CorotationalOptions& options,
                         CorotationalReport& rep, const std::vector<RestTet>& restTets,
                         const std::vector<int>& fixedBone,
                         const std::vector<int>& freeNodes, const std::vector<int>& incStart,
                         const std::vector<int>& incTet, const std::vector<std::uint16_t>& incColumn, NewtonMatrix& A,
                         SpdSolver& solver, double lambda, double mu, const Points* skinned) {
  const VolumeTerm volumeTerm{lambda, options.inversionPenalty * lambda, options.inversionThreshold};
  const std::size_t nT = std::size_t(tets.rows()), nFree = freeNodes.size();
  const Eigen::Index n = Eigen::Index(3 * nFree);
  double edgeSum = 0;  // mean rest edge length: the scale of the step tolerance
  for (const RestTet& rt : restTets) {
    const Mat3 Dm = rt.DmInv.inverse();
    edgeSum += Dm.colwise().norm().sum() + (Dm.col(1) - Dm.col(0)).norm() + (Dm.col(2) - Dm.col(0)).norm() +
               (Dm.col(2) - Dm.col(1)).norm();
  }
  const double stepLimit = options.stepTolerance * edgeSum / (6.0 * double(std::max<std::size_t>(nT, 1)));

  // Volume regions (see CorotationalOptions::volumeRegions): tets with a free node only, the others
  // keep their volume anyway. The pressure of each region follows the last evaluated pose.
  // useRegions() sets them up (again: the continuation's path may use pathVolumeRegions), with the
  // multipliers at 0.
  int nRegions = 0;
  std::vector<int> region;
  std::vector<double> regionRest, regionVolume, regionPressure, regionMultiplier;
  LowRankTerm3 regionCoupling;
  const std::size_t sumBlock = 512, nSumBlocks = (nT + sumBlock - 1) / sumBlock;
  std::vector<double> blockSums;  // evaluate()'s per-block sums: energy, then each region's volume
  auto useRegions = [&](const std::vector<int>& ids) {
    nRegions = 0;
    for (int r : ids) nRegions = std::max(nRegions, r + 1);
    region.assign(nRegions > 0 ? nT : 0, -1);
    regionRest.assign(std::size_t(nRegions), 0.0);
    regionVolume.assign(std::size_t(nRegions), 0.0);
    regionPressure.assign(std::size_t(nRegions), 0.0);
    regionMultiplier.assign(std::size_t(nRegions), 0.0);
    regionCoupling = LowRankTerm3{};
    blockSums.assign(nSumBlocks * std::size_t(1 + nRegions), 0.0);
    solver.setLowRank(nRegions > 0 ? &regionCoupling : nullptr);
    if (nRegions == 0) return;
    for (std::size_t t = 0; t < nT; ++t) {
      if (!hasFreeNode(tets, fixedBone, t) || ids[t] < 0) continue;
      region[t] = ids[t];
      regionRest[std::size_t(region[t])] += restTets[t].volume;
    }
    regionCoupling.weight.resize(std::size_t(nRegions));
    for (int r = 0; r < nRegions; ++r)
      regionCoupling.weight[std::size_t(r)] =
          regionRest[std::size_t(r)] > 0 ? options.regionVolumeStiffness * lambda / regionRest[std::size_t(r)] : 0.0;
    // One entry per (free node, region of an incident tet); the gradients are filled by assemble().
    regionCoupling.rowStart.assign(nFree + 1, 0);
    for (std::size_t i = 0; i < nFree; ++i) {
      const std::size_t first = regionCoupling.term.size();
      for (int k = incStart[i]; k < incStart[i + 1]; ++k) {
        const int r = region[std::size_t(incTet[std::size_t(k)] / 4)];
        if (r >= 0 && std::find(regionCoupling.term.begin() + std::ptrdiff_t(first), regionCoupling.term.end(), r) ==
                          regionCoupling.term.end())
          regionCoupling.term.push_back(r);
      }
      regionCoupling.rowStart[i + 1] = int(regionCoupling.term.size());
    }
    regionCoupling.vector.assign(3 * regionCoupling.term.size(), 0.0);
  };
  useRegions(options.volumeRegions);
  // Set when the continuation's path regions give way to volumeRegions at its end: the new terms
  // start far from their targets (tiny phantom, tissues: 6e-3) while their energy is a tiny part of
  // the total, so from there on a small energy decrease ends Newton only with a small step too.
  bool regionsSwitched = false;

  std::vector<char> hasFree(nT, 0);  // per tet: some node of it is free
  for (std::size_t t = 0; t < nT; ++t) hasFree[t] = hasFreeNode(tets, fixedBone, t);
  std::vector<TetState> state(nT);
  std::vector<char> barrier(nT, 0);  // per tet: the log barrier (1) or the penalty (0) below det F = eps
  // Energy and inverted-tet count of a pose; always refreshes the per-tet state (a rejected trial's
  // state is overwritten by the next trial, an accepted one's is the state of the new iterate).
  // The sums are taken per fixed block of tets and then in block order, so that they do not depend
  // on how the threads split the work: a solve gives the same result every run (the line search's
  // accept / reject decisions, and through them the continuation's path, hang on the last digits).
  std::vector<int> blockCounts(nSumBlocks);
  auto evaluate = [&](const Points& x, int& inverted) {
    parallelFor(nSumBlocks, [&](std::size_t bb, std::size_t be) {
      for (std::size_t k = bb; k < be; ++k) {
        double* sums = blockSums.data() + k * std::size_t(1 + nRegions);
        std::fill(sums, sums + 1 + nRegions, 0.0);
        int localCount = 0;
        for (std::size_t t = k * sumBlock; t < std::min(nT, (k + 1) * sumBlock); ++t) {
          const auto T = tets.row(Eigen::Index(t));
          const RestTet& rt = restTets[t];
          Mat3 Ds;
          const Vec3 x0 = node(x, T[0]);
          for (int c = 0; c < 3; ++c) Ds.col(c) = node(x, T[c + 1]) - x0;
          const Mat3 F = Ds * rt.DmInv;
          Mat3 U, V;
          Vec3 sigma;
          signedSvd(F, U, sigma, V);  // det U = det V = +1: an inverted tet has sigma(2) < 0
          const double J = sigma.prod();
          if (J <= 0.0) ++localCount;
          double p, stiffness;
          sums[0] += rt.volume * (mu * (sigma - Vec3::Ones()).squaredNorm() + volumeTerm(J, barrier[t] != 0, p, stiffness));
          state[t] = TetState{U, V, sigma};
          if (nRegions > 0 && region[t] >= 0) sums[1 + region[t]] += rt.volume * J;
        }
        blockCounts[k] = localCount;
      }
    }, 1);
    double energy = 0;
    int count = 0;
    std::fill(regionVolume.begin(), regionVolume.end(), 0.0);
    for (std::size_t k = 0; k < nSumBlocks; ++k) {
      const double* sums = blockSums.data() + k * std::size_t(1 + nRegions);
      energy += sums[0];
      count += blockCounts[k];
      for (int r = 0; r < nRegions; ++r) regionVolume[std::size_t(r)] += sums[1 + r];
    }
    for (int r = 0; r < nRegions; ++r) {
      const double excess = regionVolume[std::size_t(r)] - regionRest[std::size_t(r)];
      const double penalty = regionCoupling.weight[std::size_t(r)] * excess;
      regionPressure[std::size_t(r)] = regionMultiplier[std::size_t(r)] + penalty;
      energy += (regionMultiplier[std::size_t(r)] + 0.5 * penalty) * excess;
    }
    inverted = count;
    return energy;
  };

  // The projected Hessian of psi in F, per tet (Smith et al. 2019): diagonal in the modes U M V^T.
  // Twist / flip of each pair (i, j) (third index l) have eigenvalues mu (2 - 4 / (s_i + s_j)) + p s_l
  // and 2 mu - p s_l; the scalings a 3x3 block 2 mu I + h'' cofS cofS^T + p d2J/ds2 (p = h'). Negative
  // eigenvalues are clamped to 0. Kept per tet in the frame of U and V (pair: c = (twist + flip) / 2,
  // d = (flip - twist) / 2; scalings: the clamped block), once per Newton iteration, so the row-wise
  // assembly below does not redo it for each of the tet's four nodes.
  struct TetHessian {
    float c[3], d[3];
    float S[3][3];
  };
  std::vector<TetHessian> hessian(nT);
  static const int pairI[3] = {0, 1, 0}, pairJ[3] = {1, 2, 2}, pairL[3] = {2, 0, 1};
  auto prepareHessians = [&]() {
    parallelFor(nT, [&](std::size_t b, std::size_t e) {
      for (std::size_t t = b; t < e; ++t) {
        const Vec3& s = state[t].sigma;
        double pressure, stiffness;
        volumeTerm(s.prod(), barrier[std::size_t(t)] != 0, pressure, stiffness);
        if (nRegions > 0 && region[t] >= 0) pressure += regionPressure[std::size_t(region[t])];
        const Vec3 cofS(s(1) * s(2), s(0) * s(2), s(0) * s(1));  // cof F = U diag(cofS) V^T
        TetHessian& h = hessian[t];
        for (int m = 0; m < 3; ++m) {
          const double sum = s(pairI[m]) + s(pairJ[m]);
          const double arap = std::abs(sum) > 1e-12 ? mu * (2.0 - 4.0 / sum) : 0.0;
          const double twist = std::max(0.0, arap + pressure * s(pairL[m]));
          const double flip = std::max(0.0, 2.0 * mu - pressure * s(pairL[m]));
          h.c[m] = float(0.5 * (twist + flip));
          h.d[m] = float(0.5 * (flip - twist));
        }
        Mat3 S = 2.0 * mu * Mat3::Identity() + stiffness * cofS * cofS.transpose();
        S(0, 1) += pressure * s(2), S(1, 0) += pressure * s(2);
        S(1, 2) += pressure * s(0), S(2, 1) += pressure * s(0);
        S(0, 2) += pressure * s(1), S(2, 0) += pressure * s(1);
        // Most tets are mildly deformed and S is positive definite (leading principal minors > 0):
        // then it is its own projection, and the eigensolve (the costliest step here) is skipped.
        Mat3 clamped = S;
        if (!(S(0, 0) > 0 && S(0, 0) * S(1, 1) - S(0, 1) * S(1, 0) > 0 && S.determinant() > 0)) {
          Eigen::SelfAdjointEigenSolver<Mat3> eig;
          eig.computeDirect(S);
          clamped = eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).asDiagonal() * eig.eigenvectors().transpose();
        }
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c) h.S[r][c] = float(clamped(r, c));
      }
    }, 1024);
  };

  // Gradient and projected Hessian, row-wise over the free nodes (no write conflicts). With a move of
  // the Dirichlet nodes (#V by 3, read at Dirichlet nodes only), also dirichletForce = H_fd move:
  // the first-order change of the free nodes' gradient when the Dirichlet nodes take that move.
  Eigen::VectorXd grad(n), dirichletForce;
  auto assemble = [&](const Points* dirichletMove) {
    if (dirichletMove) dirichletForce.setZero(n);
    prepareHessians();
    parallelFor(nFree, [&](std::size_t b, std::size_t e) {
      std::vector<double> row;  // the row's blocks, summed in double
      for (std::size_t i = b; i < e; ++i) {
        row.assign(9 * std::size_t(A.rowLength(i)), 0.0);
        Vec3 gi = Vec3::Zero(), fi = Vec3::Zero();
        const int couplingBegin = nRegions > 0 ? regionCoupling.rowStart[i] : 0;
        const int couplingEnd = nRegions > 0 ? regionCoupling.rowStart[i + 1] : 0;
        for (int q = couplingBegin; q < couplingEnd; ++q)
          for (int c = 0; c < 3; ++c) regionCoupling.vector[3 * std::size_t(q) + std::size_t(c)] = 0.0;
        for (int k = incStart[i]; k < incStart[i + 1]; ++k) {
          const int t = incTet[std::size_t(k)] / 4, a = incTet[std::size_t(k)] % 4;
          const RestTet& rt = restTets[std::size_t(t)];
          const TetState& st = state[std::size_t(t)];
          const TetHessian& h = hessian[std::size_t(t)];
          const Vec3& s = st.sigma;
          double pressure, stiffness;
          volumeTerm(s.prod(), barrier[std::size_t(t)] != 0, pressure, stiffness);
          const int r = nRegions > 0 ? region[std::size_t(t)] : -1;
          if (r >= 0) pressure += regionPressure[std::size_t(r)];
          const Vec3 cofS(s(1) * s(2), s(0) * s(2), s(0) * s(1));
          const Eigen::Matrix<double, 4, 3> g = gradients(rt);
          // Each node's gradient in the frame of V.
          const Eigen::Matrix<double, 3, 4> w = st.V.transpose() * g.transpose();
          const Vec3 wa = w.col(a);
          if (r >= 0) {  // this node's part of the gradient of the region's volume: V0 cof(F) g_a
            int q = couplingBegin;
            while (regionCoupling.term[std::size_t(q)] != r) ++q;
            const Vec3 dv = rt.volume * (st.U * cofS.cwiseProduct(wa));
            for (int c = 0; c < 3; ++c) regionCoupling.vector[3 * std::size_t(q) + std::size_t(c)] += dv(c);
          }
          // Force: P g_a with P = U diag(2 mu (s - 1) + p cofS) V^T, times the volume.
          gi += rt.volume * (st.U * (2.0 * mu * (s - Vec3::Ones()) + pressure * cofS).cwiseProduct(wa));
          for (int bb = 0; bb < 4; ++bb) {
            const int v = tets(t, bb);
            const bool dirichlet = fixedBone[std::size_t(v)] >= 0;
            if (dirichlet && !dirichletMove) continue;  // Dirichlet: no increment
            const std::uint16_t slot = incColumn[4 * std::size_t(k) + std::size_t(bb)];
            if (!dirichlet && slot == kNotStored) continue;  // below the diagonal of an upper matrix
            // Block (a, bb) in the frame of U: diag(wa) S diag(wb) plus the twist / flip pairs.
            const Vec3 wb = w.col(bb);
            Mat3 L;
            for (int r = 0; r < 3; ++r)
              for (int c = 0; c < 3; ++c) L(r, c) = wa(r) * double(h.S[r][c]) * wb(c);
            for (int m = 0; m < 3; ++m) {
              const int pi = pairI[m], pj = pairJ[m];
              L(pi, pi) += double(h.c[m]) * wa(pj) * wb(pj);
              L(pj, pj) += double(h.c[m]) * wa(pi) * wb(pi);
              L(pi, pj) += double(h.d[m]) * wa(pj) * wb(pi);
              L(pj, pi) += double(h.d[m]) * wa(pi) * wb(pj);
            }
            const Mat3 block = rt.volume * (st.U * L * st.U.transpose());
            if (dirichlet) {
              fi += block * node(*dirichletMove, v);
              continue;
            }
            double* dst = row.data() + 9 * std::size_t(slot);
            for (int cc = 0; cc < 3; ++cc)
              for (int d = 0; d < 3; ++d) dst[3 * cc + d] += block(cc, d);
          }
        }
        A.setRow(i, row.data());
        grad.segment<3>(Eigen::Index(3 * i)) = gi;
        if (dirichletMove) dirichletForce.segment<3>(Eigen::Index(3 * i)) = fi;
      }
    }, 256);
  };
  // A's own solve: float blocks in place, or the double matrix.
  auto solveNewton = [&](const Eigen::VectorXd& b, Eigen::VectorXd& x, double tolerance, int& iterations,
                         double& residual) {
    if (A.blocked)
      solver.solve(A.blocks, b, x, tolerance, iterations, residual);
    else
      solver.solve(A.scalar, b, x, tolerance, iterations, residual);
  };

  // Continuation: the path's progress, for the checkpoint (see CorotationalOptions::checkpoint).
  bool onPath = false;
  double pathS = 0.0;
  auto checkCancelled = [&](RelaxationProgress::Phase phase) {
    if (!options.checkpoint) return;
    RelaxationProgress p;
    p.phase = onPath ? RelaxationProgress::Continuation : phase;
    p.newtonIterations = rep.newtonIterations;
    p.continuationSteps = rep.continuationSteps;
    p.pathFraction = pathS;
    reachCheckpoint(options, p);
  };
  int inverted = 0;
  // The barrier flags of a pose, as newton() sets them, but on the signs of the tet volumes: set
  // before the first evaluation, newton() finds them unchanged and does not evaluate again.
  auto setBarrier = [&](const Points& x) {
    if (!(options.inversionBarrier && volumeTerm.kappa > 0)) return;
    parallelFor(nT, [&](std::size_t b, std::size_t e) {
      for (std::size_t t = b; t < e; ++t) {
        const auto T = tets.row(Eigen::Index(t));
        barrier[t] = hasFree[t] && tetVolume(node(x, T[0]), node(x, T[1]), node(x, T[2]), node(x, T[3])) > 0.0;
      }
    }, 4096);
  };
  // The input pose's energy (skinned: before the strained region was relaxed, when it was).
  setBarrier(skinned ? *skinned : posed);
  double energy = evaluate(skinned ? *skinned : posed, inverted);
  rep.energyBefore = energy;
  if (skinned) {
    setBarrier(posed);
    energy = evaluate(posed, inverted);
  }
  Points trial = posed;
  Eigen::VectorXd step(n);
  double firstNorm = -1.0;
  std::vector<int> freeIndex(std::size_t(posed.rows()), -1);  // node -> its place among the unknowns
  for (std::size_t i = 0; i < nFree; ++i) freeIndex[std::size_t(freeNodes[i])] = int(i);
  // The line search's first trial: 9/10 of the way to where the first barrier tet would turn flat
  // along the step (or the whole step). Halving from the whole step, a thin tet turned at 1 and 1/2
  // and the medium phantom's early Newton steps took 1/4 or 1/8 of theirs (every cut-back there was
  // a turned tet, none the energy's); from the turning point they take 0.2-0.75, and its strained
  // region needs 10 Newton steps in place of 12 (large: 17 in place of 22).
  constexpr double kTurnFraction = 0.9;
  auto firstTrialFraction = [&]() {
    std::mutex lock;
    double first = 1.0 / kTurnFraction;
    parallelFor(nT, [&](std::size_t b, std::size_t e) {
      double local = 1.0 / kTurnFraction;
      for (std::size_t t = b; t < e; ++t) {
        if (!barrier[t]) continue;
        const auto T = tets.row(Eigen::Index(t));
        Vec3 d[4];
        for (int a = 0; a < 4; ++a) {
          const int i = freeIndex[std::size_t(T[a])];
          d[a] = i >= 0 ? Vec3(step.segment<3>(Eigen::Index(3 * i))) : Vec3::Zero();
        }
        Mat3 D, E;
        const Vec3 x0 = node(posed, T[0]);
        for (int c = 0; c < 3; ++c) {
          D.col(c) = node(posed, T[c + 1]) - x0;
          E.col(c) = d[c + 1] - d[0];
        }
        local = tetTurningPoint(D, E, local);
      }
      const std::lock_guard<std::mutex> guard(lock);
      first = std::min(first, local);
    }, 4096);
    return std::min(1.0, kTurnFraction * first);
  };
  auto newton = [&](int maxIterations) {
    if (options.inversionBarrier && volumeTerm.kappa > 0) {  // the barrier guards the tets positive now
      // (Not on tets of Dirichlet nodes only: their energy is a constant of the solve, and a bone
      // move of the continuation may turn them.)
      // (The energy is re-evaluated only when a flag changed: callers pass the energy of posed.)
      bool changed = false;
      for (std::size_t t = 0; t < nT; ++t) {
        const char b = hasFree[t] && state[t].sigma.prod() > 0.0;
        changed = changed || b != barrier[t];
        barrier[t] = b;
      }
      if (changed) energy = evaluate(posed, inverted);
    }
    for (int it = 0; it < maxIterations; ++it) {
      checkCancelled(RelaxationProgress::Newton);
      const auto assemblyStart = std::chrono::steady_clock::now();
      assemble(nullptr);
      rep.assemblySeconds += seconds(assemblyStart);
      const double gradNorm = grad.norm();
      if (firstNorm < 0) firstNorm = gradNorm;
      if (!(gradNorm > 0.0)) {
        rep.converged = true;
        return;
      }
      // Inexact Newton: the CG tolerance tightens as the gradient falls.
      const double eta = std::clamp(gradNorm / firstNorm, options.tolerance, 0.1);
      const auto solveStart = std::chrono::steady_clock::now();
      step.setZero();
      int iterations = 0;
      double residual = 0.0;
      solveNewton(-grad, step, eta, iterations, residual);
      rep.solveSeconds += seconds(solveStart);
      rep.cgIterations.push_back(iterations);
      rep.relativeResidual.push_back(residual);
      rep.newtonIterations = rep.outerIterations = rep.newtonIterations + 1;

      double maxMove = 0;
      for (std::size_t i = 0; i < nFree; ++i) maxMove = std::max(maxMove, step.segment<3>(Eigen::Index(3 * i)).norm());
      const double slope = grad.dot(step);
      double alpha = firstTrialFraction();
      bool accepted = false, smallDecrease = false;
      for (int halving = 0; halving < 40 && alpha * maxMove > 1e-3 * stepLimit; ++halving, alpha *= 0.5) {
        for (std::size_t i = 0; i < nFree; ++i)
          trial.row(freeNodes[i]) = posed.row(freeNodes[i]) + alpha * step.segment<3>(Eigen::Index(3 * i)).transpose();
        // A step that inverts more tets, or turns a barrier tet, is refused on the signs of the tet
        // volumes alone, without the per-tet SVDs of the energy (most of the line search's cut-backs
        // are such steps: far from the minimum, Newton's full step overshoots a thin tet).
        if (!trialAdmissible(trial, tets, barrier, inverted)) continue;
        int trialInverted = 0;
        const double trialEnergy = evaluate(trial, trialInverted);
        if (trialInverted <= inverted && trialEnergy <= energy + 1e-4 * alpha * std::min(slope, 0.0)) {
          smallDecrease = energy - trialEnergy < options.energyTolerance * energy &&
                          (!regionsSwitched || alpha * maxMove < 10.0 * stepLimit);
          energy = trialEnergy;
          inverted = trialInverted;
          accepted = true;
          break;
        }
      }
      if (!accepted) {  // no descent left at this precision: at the minimum
        rep.converged = maxMove < stepLimit;
        evaluate(posed, inverted);  // the per-tet state of the iterate, not of the last trial
        return;
      }
      for (std::size_t i = 0; i < nFree; ++i) posed.row(freeNodes[i]) = trial.row(freeNodes[i]);
      if (alpha * maxMove < stepLimit || smallDecrease) {
        rep.converged = true;
        return;
      }
    }
  };
  newton(options.maxNewtonIterations);
  // The energy is finite through det F = 0, so a few tets may settle inverted: move their free
  // nodes out of the fold, then let Newton smooth the neighbourhood (it never re-inverts a tet; on
  // the moved nodes' surroundings alone, see untangleRelaxRings, and on the whole mesh after the
  // last round); Newton's moves may open room for another round. A round that leaves as many tets inverted
  // (the untangling could not free them) is undone at once: its Newton steps would only spend
  // time, and its pose is less relaxed than the one before it.
  bool relaxedLocally = false;
  for (int round = 0; round < 3 && inverted > 0 && options.untangle; ++round) {
    checkCancelled(RelaxationProgress::Untangling);
    const auto untangleStart = std::chrono::steady_clock::now();
    const Points before = posed;
    const UntangleReport u = untangleTets(rest, tets, fixedBone, posed);
    rep.untangledNodes += u.nodesMoved;
    rep.untangleSeconds += seconds(untangleStart);
    if (u.nodesMoved == 0) break;
    // Counted on the tet volumes, without the SVDs of an evaluation: undone, the per-tet state and
    // the energy are still those of before.
    if (u.invertedAfter >= u.invertedBefore) {
      rep.untangledNodes -= u.nodesMoved;
      posed = before;
      break;
    }
    if (options.untangleRelaxRings < 0) {
      energy = evaluate(posed, inverted);
      newton(std::max(1, options.maxNewtonIterations / 2));
      continue;
    }
    std::vector<int> moved;
    for (int v : freeNodes)
      if (posed.row(v) != before.row(v)) moved.push_back(v);
    const auto localStart = std::chrono::steady_clock::now();
    CorotationalReport local;
    try {
      relaxNeighbourhood(rest, tets, fixedBone, posed, moved, options.untangleRelaxRings, options, &local);
    } catch (const RelaxationCancelled&) {
      throw;
    } catch (const std::runtime_error&) {
      // A part singular on its own (CHOLMOD refuses a projected Hessian with a zero eigenvalue, which
      // the whole mesh's coupling may not have): posed is left as untangled, for the whole-mesh solve.
    }
    rep.untangleNewtonIterations += local.newtonIterations;
    rep.untangleSeconds += seconds(localStart);
    energy = evaluate(posed, inverted);
    relaxedLocally = true;
  }
  if (relaxedLocally) {  // the whole mesh around the relaxed neighbourhoods
    firstNorm = -1.0;
    newton(std::max(1, options.maxNewtonIterations / 2));
  }
  // Region volumes to regionVolumeTolerance (see CorotationalOptions::regionVolumeTolerance): the
  // multiplier takes the pressure the penalty holds, so the next minimum needs less excess for it.
  auto keepRegionVolumes = [&]() {
    if (!(options.regionVolumeStiffness > 0.0)) return;  // no penalty: no pressure to fold in
    double previousWorst = 0;
    for (int update = 0; update < options.maxRegionVolumeUpdates; ++update) {
      double worst = 0;
      for (int r = 0; r < nRegions; ++r)
        if (regionRest[std::size_t(r)] > 0)
          worst = std::max(worst, std::abs(regionVolume[std::size_t(r)] / regionRest[std::size_t(r)] - 1.0));
      if (worst <= options.regionVolumeTolerance) return;
      // Near the tolerance, an update that did not halve the worst excess has met the Newton solves'
      // own accuracy: more updates only spend Newton steps (medium phantom: 1.4e-4, then 1.2e-5,
      // 1.7e-5, 1.2e-5). Further out they still pay (the CMU walk's bodies: 2e-4 off without them).
      if (update > 0 && worst > 0.5 * previousWorst && worst < 10.0 * options.regionVolumeTolerance) return;
      previousWorst = worst;
      regionMultiplier = regionPressure;
      ++rep.regionVolumeUpdates;
      energy = evaluate(posed, inverted);
      firstNorm = -1.0;
      newton(std::max(1, options.maxNewtonIterations / 2));
    }
  };
  keepRegionVolumes();
  // Fold-free continuation (see CorotationalOptions::continuation).
  auto invertedWithFreeNode = [&](const Points& x) { return countInverted(x, tets, &hasFree); };
  const int directInverted = invertedWithFreeNode(posed);
  // A node pinched between bones has no fold-free place: no path can end (see Continuation).
  if (options.inversionBarrier && volumeTerm.kappa > 0 &&
      (options.continuation == CorotationalOptions::Always ||
       (options.continuation == CorotationalOptions::IfInverted && directInverted > 0 &&
        findPinchedNodes(posed, tets, fixedBone).empty()))) {
    const auto continuationStart = std::chrono::steady_clock::now();
    const Points direct = posed;
    const bool directConverged = rep.converged;
    const std::vector<char> directBarrier = barrier;
    const std::vector<double> directMultiplier = regionMultiplier;
    // The path's own regions, if any; the multipliers start at 0 (the rest shape has no pressure).
    const bool pathRegions = !options.pathVolumeRegions.empty();
    if (pathRegions)
      useRegions(options.pathVolumeRegions);
    else
      std::fill(regionMultiplier.begin(), regionMultiplier.end(), 0.0);
    const BonePath path(rest, direct, fixedBone, options.boneParents);
    std::vector<int> pathNodes;  // the Dirichlet nodes of the tets
    {
      std::vector<char> seen(std::size_t(posed.rows()), 0);
      for (std::size_t t = 0; t < nT; ++t)
        for (int a = 0; a < 4; ++a) {
          const int v = tets(Eigen::Index(t), a);
          if (fixedBone[std::size_t(v)] >= 0 && !seen[std::size_t(v)]) {
            seen[std::size_t(v)] = 1;
            pathNodes.push_back(v);
          }
        }
    }
    // s = 0: the rest shape under the skeleton's global rigid motion; no tet is inverted there.
    for (int v : freeNodes) posed.row(v) = path.start(node(rest, v)).transpose();
    path.place(0.0, pathNodes, posed);
    trial = posed;
    for (std::size_t t = 0; t < nT; ++t) barrier[t] = hasFree[t];  // every tet is positive all along
    Points move = Points::Zero(posed.rows(), 3);
    Eigen::VectorXd predictor(n);
    double s = 0.0, ds = 0.125;
    int rescues = 0;  // relaxing Newton solves after a stall
    double rescuedAt = -1.0;  // s of the last one
    std::vector<double> sHistory;  // s after each step
    onPath = true;
    while (s < 1.0 && rep.continuationSteps < options.maxContinuationSteps) {
      pathS = s;
      checkCancelled(RelaxationProgress::Continuation);
      ++rep.continuationSteps;
      const double target = std::min(1.0, s + ds);
      path.place(target, pathNodes, move);
      for (int v : pathNodes) move.row(v) -= posed.row(v);
      energy = evaluate(posed, inverted);
      const auto assemblyStart = std::chrono::steady_clock::now();
      assemble(&move);
      rep.assemblySeconds += seconds(assemblyStart);
      // Predictor: the free nodes' response to the bone move (and to what is left of the gradient).
      const auto solveStart = std::chrono::steady_clock::now();
      predictor.setZero();
      int iterations = 0;
      double residual = 0.0;
      solveNewton(-(grad + dirichletForce), predictor, 1e-2, iterations, residual);
      rep.solveSeconds += seconds(solveStart);
      // The largest fraction of the step (halved from 1) that leaves every tet positive.
      double alpha = 1.0;
      bool accepted = false;
      for (int halving = 0; halving < 16; ++halving, alpha *= 0.5) {
        path.place(s + alpha * (target - s), pathNodes, trial);
        for (std::size_t i = 0; i < nFree; ++i)
          trial.row(freeNodes[i]) = posed.row(freeNodes[i]) + alpha * predictor.segment<3>(Eigen::Index(3 * i)).transpose();
        accepted = invertedWithFreeNode(trial) == 0;
        if (accepted) break;
      }
      // A stall (no fold-free fraction of the predictor, or steps that stay short, see below) may
      // be the tissue itself, carried along by predictors alone, blocking the way: it is relaxed
      // at this s (Newton, the bones held) and the path tried again, a few times per path.
      // A stall where the last rescue was made (the path has not moved 1e-3 on since) is the same
      // block: that rescue had relaxed the tissue here already, so another finds the same minimum
      // (medium phantom, 45 degree pose: rescues 2 and 3 at s = 0.6279, after the first at 0.6276).
      auto relaxHere = [&]() {
        if (rescues >= 3 || (rescuedAt >= 0.0 && s - rescuedAt < 1e-3)) return false;
        ++rescues;
        ++rep.continuationRescues;
        rescuedAt = s;
        energy = evaluate(posed, inverted);
        firstNorm = -1.0;
        newton(std::max(1, options.maxNewtonIterations / 2));
        ds = std::max(ds, 1e-3);
        sHistory.clear();
        return true;
      };
      if (!accepted) {
        if (relaxHere()) continue;
        break;
      }
      s = alpha == 1.0 ? target : s + alpha * (target - s);
      posed = trial;
      ds = alpha == 1.0 ? std::min(2.0 * ds, 0.5) : alpha * ds;
      // Steps that stay short: see continuation_stall.h.
      sHistory.push_back(s);
      if (ds < 1e-6 || continuationPaceStalls(sHistory, rep.continuationSteps, options.maxContinuationSteps)) {
        if (relaxHere()) continue;
        break;
      }
      if (s >= 1.0 && pathRegions) {  // the pose's own regions from here
        useRegions(options.volumeRegions);
        regionsSwitched = true;
      }
      energy = evaluate(posed, inverted);
      firstNorm = -1.0;  // each correction's forcing terms start afresh
      if (s >= 1.0 || options.continuationCorrections > 0)
        newton(s < 1.0 ? options.continuationCorrections : options.maxNewtonIterations);
    }
    // Newton never inverts a tet, so a completed path ends fold-free.
    const bool completed = s >= 1.0;
    if (completed) keepRegionVolumes();
    if (completed && (options.continuation == CorotationalOptions::Always || invertedWithFreeNode(posed) < directInverted)) {
      rep.continuationUsed = true;
    } else {
      posed = direct;
      barrier = directBarrier;
      if (pathRegions && s < 1.0) useRegions(options.volumeRegions);
      regionMultiplier = directMultiplier;
      energy = evaluate(posed, inverted);
      rep.converged = directConverged;
    }
    rep.continuationSeconds = seconds(continuationStart);
  }
  rep.energyAfter = energy;  // regionVolume is that of posed too: evaluate() last ran on it or on the accepted trial
  rep.regionVolumeRatio.resize(std::size_t(nRegions));
  for (int r = 0; r < nRegions; ++r)
    rep.regionVolumeRatio[std::size_t(r)] =
        regionRest[std::size_t(r)] > 0 ? regionVolume[std::size_t(r)] / regionRest[std::size_t(r)] : 1.0;
}

}  // namespace

namespace {

// The strained region first (see CorotationalOptions::strainedRegionThreshold), before the whole
// mesh's matrix and per-tet state exist, so that the part's own do not sit beside them. Returns
// whether it ran (posed then holds its result).
bool relaxStrainedRegionFirst(const Points& rest, const Tets& tets, const std::vector<int>& fixedBone,
                              const std::vector<RestTet>& restTets, std::size_t nFree, double lambda, double mu,
                              Points& posed, const CorotationalOptions& options, CorotationalReport& rep) {
  const auto regionStart = std::chrono::steady_clock::now();
  const std::size_t nT = std::size_t(tets.rows());
  const double volumeWeight = 0.5 * lambda / mu;
  std::vector<char> strainedTet(nT, 0);
  parallelFor(nT, [&](std::size_t b, std::size_t e) {
    for (std::size_t t = b; t < e; ++t) {
      if (!hasFreeNode(tets, fixedBone, t)) continue;
      const auto T = tets.row(Eigen::Index(t));
      Mat3 Ds;
      const Vec3 x0 = node(posed, T[0]);
      for (int c = 0; c < 3; ++c) Ds.col(c) = node(posed, T[c + 1]) - x0;
      Mat3 U, V;
      Vec3 s;
      signedSvd(Ds * restTets[t].DmInv, U, s, V);
      const double J = s.prod();
      strainedTet[t] = (s - Vec3::Ones()).squaredNorm() + volumeWeight * (J - 1.0) * (J - 1.0) >
                       options.strainedRegionThreshold;
    }
  }, 1024);
  std::vector<char> strained(std::size_t(posed.rows()), 0);
  for (std::size_t t = 0; t < nT; ++t)
    if (strainedTet[t])
      for (int a = 0; a < 4; ++a) strained[std::size_t(tets(Eigen::Index(t), a))] = 1;
  strainedTet = std::vector<char>();
  std::vector<int> centre;
  for (std::size_t v = 0; v < strained.size(); ++v)
    if (strained[v] && fixedBone[v] < 0) centre.push_back(int(v));
  const std::vector<char> unknown = grownNeighbourhood(tets, fixedBone, centre, options.strainedRegionRings);
  const std::size_t partNodes = std::size_t(std::count(unknown.begin(), unknown.end(), char(1)));
  // A part of most of the mesh costs what the whole does (and a pose strained all over is no
  // skinned one: a fold from a bad start, say), so then the whole mesh goes at once.
  bool ran = false;
  if (partNodes > 0 && partNodes <= kStrainedRegionLargestPart * double(nFree)) {
    CorotationalReport part;
    try {
      rep.strainedRegionNodes = relaxPart(rest, tets, fixedBone, posed, unknown, options,
                                          RelaxationProgress::StrainedRegion, &part);
      ran = rep.strainedRegionNodes > 0;
    } catch (const RelaxationCancelled&) {
      throw;
    } catch (const std::runtime_error&) {
      // A part singular on its own (see the untangling's neighbourhoods): the whole mesh from posed.
    }
    rep.strainedRegionNewtonIterations = part.newtonIterations;
  }
  rep.strainedRegionSeconds = seconds(regionStart);
  return ran;
}

/// relaxCorotational's work on posed in place (a cancelled solve leaves it part-way).
void relaxInPlace(const Points& rest, const Tets& tets, const std::vector<int>& fixedBone, Points& posed,
                  const CorotationalOptions& options, CorotationalReport* report) {
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
  if (!(options.strainedRegionThreshold >= 0.0) || options.strainedRegionRings < 0)
    throw std::invalid_argument("relaxCorotational: the strained region's threshold and rings must not be negative");
  if (options.outerIterations < 1)
    throw std::invalid_argument("relaxCorotational: outerIterations must be >= 1");
  if (!(options.tolerance > 0.0))
    throw std::invalid_argument("relaxCorotational: tolerance must be positive");
  if (options.maxCgIterations < 1)
    throw std::invalid_argument("relaxCorotational: maxCgIterations must be >= 1");
  if (options.coarseAggregateSize < 1)
    throw std::invalid_argument("relaxCorotational: coarseAggregateSize must be >= 1");
  if (!(options.twoLevelBelowTolerance >= 0.0))
    throw std::invalid_argument("relaxCorotational: twoLevelBelowTolerance must be >= 0");
  if (options.coarseRefreshInterval < 1)
    throw std::invalid_argument("relaxCorotational: coarseRefreshInterval must be >= 1");
  if (options.maxNewtonIterations < 1)
    throw std::invalid_argument("relaxCorotational: maxNewtonIterations must be >= 1");
  if (options.maxContinuationSteps < 1 || options.continuationCorrections < 0)
    throw std::invalid_argument("relaxCorotational: maxContinuationSteps must be >= 1 and continuationCorrections >= 0");
  if (!(options.stepTolerance > 0.0))
    throw std::invalid_argument("relaxCorotational: stepTolerance must be positive");
  if (!(options.energyTolerance >= 0.0))
    throw std::invalid_argument("relaxCorotational: energyTolerance must be >= 0");
  if (!(options.inversionPenalty >= 0.0) || !std::isfinite(options.inversionPenalty))
    throw std::invalid_argument("relaxCorotational: inversionPenalty must be >= 0");
  if (!(options.inversionThreshold >= 0.0 && options.inversionThreshold < 1.0))
    throw std::invalid_argument("relaxCorotational: inversionThreshold must be in [0, 1)");
  for (const auto& [name, ids] : {std::make_pair("volumeRegions", &options.volumeRegions),
                                   std::make_pair("pathVolumeRegions", &options.pathVolumeRegions)}) {
    if (!ids->empty() && Eigen::Index(ids->size()) != nT)
      throw std::invalid_argument(std::string("relaxCorotational: ") + name + " has " + std::to_string(ids->size()) +
                                  " entries but the mesh has " + std::to_string(nT) + " tets");
    for (std::size_t t = 0; t < ids->size(); ++t)
      if ((*ids)[t] >= nT)  // more regions than tets: not a region id
        throw std::invalid_argument(std::string("relaxCorotational: ") + name + "[" + std::to_string(t) + "] = " +
                                    std::to_string((*ids)[t]) + " is not below the tet count " + std::to_string(nT));
  }
  if (!(options.regionVolumeStiffness >= 0.0) || !std::isfinite(options.regionVolumeStiffness))
    throw std::invalid_argument("relaxCorotational: regionVolumeStiffness must be >= 0");
  if (options.startCorrection.size() > 0 &&
      (options.startCorrection.rows() != nV || !options.startCorrection.allFinite()))
    throw std::invalid_argument("relaxCorotational: startCorrection must be empty or " + std::to_string(nV) +
                                " finite rows");
  if (!(options.regionVolumeTolerance >= 0.0) || options.maxRegionVolumeUpdates < 0)
    throw std::invalid_argument("relaxCorotational: regionVolumeTolerance and maxRegionVolumeUpdates must be >= 0");
  for (Eigen::Index t = 0; t < nT; ++t)
    for (int a = 0; a < 4; ++a)
      if (tets(t, a) < 0 || tets(t, a) >= nV)
        throw std::invalid_argument("relaxCorotational: tet " + std::to_string(t) +
                                    " has node index " + std::to_string(tets(t, a)) +
                                    " outside [0, " + std::to_string(nV) + ")");
  if (!options.boneParents.empty() && !fixedBone.empty()) {
    const int bones = *std::max_element(fixedBone.begin(), fixedBone.end()) + 1;
    if (int(options.boneParents.size()) < bones)
      throw std::invalid_argument("relaxCorotational: boneParents has " + std::to_string(options.boneParents.size()) +
                                  " entries but fixedBone names bone " + std::to_string(bones - 1));
  }
  const bool anyFixed = std::any_of(fixedBone.begin(), fixedBone.end(), [](int b) { return b >= 0; });
  if (nV > 0 && !anyFixed)
    throw std::invalid_argument(
        "relaxCorotational: no node is fixed; the elastic system is singular (mark bone nodes "
        "with fixedBone >= 0)");

  reachCheckpoint(options, RelaxationProgress{});
  const SingleThreadedBlas blasOnThisThread;  // the CG's threads keep the cores (see blas_threads.h)
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
  if (options.startCorrection.size() > 0) {  // on the unknowns only: fixed nodes and nodes in no tet stay
    Points start = posed;
    for (int v : freeNodes) start.row(v) += options.startCorrection.row(v);
    if (!turnsAPositiveTet(posed, start, tets)) {
      posed = start;
      rep.correctedStart = true;
    }
  }

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

  const double nu = options.poisson, E = options.young;
  const double lambda = E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
  const double mu = E / (2.0 * (1.0 + nu));
  Points skinned;  // the input pose, when the strained region went first
  if (options.model == CorotationalOptions::FixedCorotated && options.strainedRegionThreshold > 0.0 &&
      !rep.correctedStart) {
    Points input = posed;
    if (relaxStrainedRegionFirst(rest, tets, fixedBone, restTets, nFree, lambda, mu, posed, options, rep))
      skinned = std::move(input);
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

  // Block sparsity pattern: row i holds its free neighbours (and itself), sorted; an upper matrix
  // (the block CG's, see NewtonMatrix) only those from i on. Two passes over each row's tets, the
  // first to count, the second to fill: a per-thread mark (last row that listed a column) leaves
  // only the row's distinct columns to sort, and then maps each to its place in the row.
  NewtonMatrix A;
  A.blocked = options.preconditioner == CorotationalOptions::BlockJacobi ||
              options.preconditioner == CorotationalOptions::TwoLevel;
  auto stored = [&](std::size_t i, int v) {  // the column of node v in row i, or -1
    const int d = fixedBone[std::size_t(v)] < 0 ? dof[std::size_t(v)] : -1;
    return A.blocked && d < int(i) ? -1 : d;
  };
  // Row i's distinct columns, in the order met, written to out (if given); returns their count.
  auto distinctColumns = [&](std::size_t i, std::vector<int>& mark, int* out) {
    int len = 0;
    for (int k = incStart[i]; k < incStart[i + 1]; ++k) {
      const int t = incTet[std::size_t(k)] / 4;
      for (int c = 0; c < 4; ++c) {
        const int col = stored(i, tets(t, c));
        if (col >= 0 && mark[std::size_t(col)] != int(i)) {
          mark[std::size_t(col)] = int(i);
          if (out) out[len] = col;
          ++len;
        }
      }
    }
    return len;
  };
  // (Chunks of at least a 32nd of the rows: each allocates its own mark.)
  const std::size_t patternGrain = std::max<std::size_t>(1024, nFree / 32);
  std::vector<int> rowStart(nFree + 1, 0);
  parallelFor(nFree, [&](std::size_t b, std::size_t e) {
    std::vector<int> mark(nFree, -1);
    for (std::size_t i = b; i < e; ++i) rowStart[i + 1] = distinctColumns(i, mark, nullptr);
  }, patternGrain);
  for (std::size_t i = 0; i < nFree; ++i) {
    if (rowStart[i + 1] >= kNotStored)  // over 65534 neighbours: not a tet mesh a skinning could come from
      throw std::invalid_argument("relaxCorotational: a node has too many neighbours");
    rowStart[i + 1] += rowStart[i];
  }
  // Where each (free node, incident tet, tet node) block goes in the node's row: its index there
  // (kNotStored: not stored), found once here instead of by a search in every assembly.
  std::vector<int> column(static_cast<std::size_t>(rowStart[nFree]));
  std::vector<std::uint16_t> incColumn(4 * incTet.size(), kNotStored);
  parallelFor(nFree, [&](std::size_t b, std::size_t e) {
    std::vector<int> mark(nFree, -1), place(nFree);
    for (std::size_t i = b; i < e; ++i) {
      int* cols = column.data() + rowStart[i];
      const int len = distinctColumns(i, mark, cols);
      std::sort(cols, cols + len);
      for (int q = 0; q < len; ++q) place[std::size_t(cols[q])] = q;
      for (int k = incStart[i]; k < incStart[i + 1]; ++k) {
        const int t = incTet[std::size_t(k)] / 4;
        for (int c = 0; c < 4; ++c) {
          const int col = stored(i, tets(t, c));
          if (col >= 0) incColumn[4 * std::size_t(k) + std::size_t(c)] = std::uint16_t(place[std::size_t(col)]);
        }
      }
    }
  }, patternGrain);
  const Eigen::Index n = Eigen::Index(3 * nFree);
  if (A.blocked) {
    A.blocks.upper = true;
    A.blocks.rowStart = rowStart;
    A.blocks.column = std::move(column);
    A.blocks.values.assign(9 * std::size_t(rowStart[nFree]), 0.0f);
  } else {
    // Symmetric, so the column-major arrays are filled row by row: column 3i+c holds row 3i+c.
    SpMat& S = A.scalar;
    S.resize(n, n);
    S.resizeNonZeros(Eigen::Index(9) * rowStart[nFree]);
    for (std::size_t i = 0; i < nFree; ++i)
      for (int c = 0; c < 3; ++c) S.outerIndexPtr()[3 * i + c] = 9 * rowStart[i] + 3 * c * (rowStart[i + 1] - rowStart[i]);
    S.outerIndexPtr()[n] = 9 * rowStart[nFree];
    parallelFor(nFree, [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i)
        for (int c = 0; c < 3; ++c) {
          int* inner = S.innerIndexPtr() + S.outerIndexPtr()[3 * i + c];
          for (int k = rowStart[i]; k < rowStart[i + 1]; ++k)
            for (int d = 0; d < 3; ++d) inner[3 * (k - rowStart[i]) + d] = 3 * column[std::size_t(k)] + d;
        }
    });
    column = std::vector<int>();
  }

  SpdSolver solver(options);
  solver.setNodes(rest, posed, freeNodes);
  if (options.model == CorotationalOptions::FixedCorotated) {
    relaxFixedCorotated(rest, tets, posed, options, rep, restTets, fixedBone, freeNodes, incStart, incTet, incColumn, A,
                        solver, lambda, mu, skinned.rows() > 0 ? &skinned : nullptr);
    countInvertedAfter(posed, tets, fixedBone, rep);
    rep.seconds = seconds(start);
    return;
  }
  std::vector<Mat3> rotation(static_cast<std::size_t>(nT));
  Eigen::VectorXd rhs(n), residual0(n), x(n);
  for (int outer = 0; outer < options.outerIterations; ++outer) {
    RelaxationProgress linearProgress;
    linearProgress.phase = RelaxationProgress::Linear;
    linearProgress.outerIteration = outer;
    reachCheckpoint(options, linearProgress);
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
    // K'_ab = R K_ab R^T = V (lambda h_a h_b^T + mu h_b h_a^T + mu (g_a.g_b) I) with h = R g (K_ab =
    // V (lambda g_a g_b^T + mu g_b g_a^T + mu (g_a.g_b) I)), and the force of the rotated rest shape
    // R sum_b K_ab X_b = V (3 lambda + 2 mu) h_a (sum_b X_b g_b^T = I), so that
    // rhs_i = sum_t V (3 lambda + 2 mu) h_a  -  sum_{b fixed} K'_ab x_b. The residual of the start,
    // rhs_i - sum_{b free} K'_ab x_b, is summed here in double from every block of the row (an upper
    // matrix stores only some): the float block CG then solves for the correction alone.
    parallelFor(nFree, [&](std::size_t b, std::size_t e) {
      std::vector<double> row;  // the row's stored blocks, summed in double
      for (std::size_t i = b; i < e; ++i) {
        row.assign(9 * std::size_t(A.rowLength(i)), 0.0);
        Vec3 r = Vec3::Zero(), free = Vec3::Zero();
        for (int k = incStart[i]; k < incStart[i + 1]; ++k) {
          const int t = incTet[std::size_t(k)] / 4, a = incTet[std::size_t(k)] % 4;
          const RestTet& rt = restTets[std::size_t(t)];
          const Eigen::Matrix<double, 4, 3> g = gradients(rt);
          const Eigen::Matrix<double, 4, 3> h = g * rotation[std::size_t(t)].transpose();
          const Vec3 ga = g.row(a).transpose(), ha = h.row(a).transpose();
          r += rt.volume * (3.0 * lambda + 2.0 * mu) * ha;
          for (int bb = 0; bb < 4; ++bb) {
            const Vec3 hb = h.row(bb).transpose();
            Mat3 block = lambda * ha * hb.transpose() + mu * hb * ha.transpose();
            block.diagonal().array() += mu * ga.dot(g.row(bb).transpose());
            block *= rt.volume;
            const int v = tets(t, bb);
            if (fixedBone[std::size_t(v)] >= 0) {
              r -= block * node(posed, v);
              continue;
            }
            free += block * node(posed, v);
            const std::uint16_t slot = incColumn[4 * std::size_t(k) + std::size_t(bb)];
            if (slot == kNotStored) continue;  // below the diagonal of an upper matrix
            double* dst = row.data() + 9 * std::size_t(slot);
            for (int c = 0; c < 3; ++c)
              for (int d = 0; d < 3; ++d) dst[3 * c + d] += block(c, d);
          }
        }
        A.setRow(i, row.data());
        rhs.segment<3>(Eigen::Index(3 * i)) = r;
        residual0.segment<3>(Eigen::Index(3 * i)) = r - free;
        x.segment<3>(Eigen::Index(3 * i)) = node(posed, freeNodes[i]);
      }
    }, 256);

    rep.assemblySeconds += seconds(assemblyStart);
    const auto solveStart = std::chrono::steady_clock::now();
    int iterations = 0;
    double residual = 0.0;
    if (A.blocked)
      solver.solveCorrection(A.blocks, rhs, residual0, x, options.tolerance, iterations, residual);
    else
      solver.solve(A.scalar, rhs, x, options.tolerance, iterations, residual);
    rep.solveSeconds += seconds(solveStart);
    for (std::size_t i = 0; i < nFree; ++i)
      posed.row(freeNodes[i]) = x.segment<3>(Eigen::Index(3 * i)).transpose();
    rep.cgIterations.push_back(iterations);
    rep.relativeResidual.push_back(residual);
    rep.outerIterations = outer + 1;
  }
  if (options.untangle && countInverted(posed, tets) > 0) {
    const auto untangleStart = std::chrono::steady_clock::now();
    rep.untangledNodes = untangleTets(rest, tets, fixedBone, posed).nodesMoved;
    rep.untangleSeconds = seconds(untangleStart);
  }
  countInvertedAfter(posed, tets, fixedBone, rep);
  rep.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

void relaxCorotational(const Points& rest, const Tets& tets, const std::vector<int>& fixedBone,
                       Points& posed, const CorotationalOptions& options, CorotationalReport* report) {
  if (!options.checkpoint) {
    relaxInPlace(rest, tets, fixedBone, posed, options, report);
    return;
  }
  const Points input = posed;
  try {
    relaxInPlace(rest, tets, fixedBone, posed, options, report);
  } catch (const RelaxationCancelled&) {
    posed = input;
    throw;
  }
}

void relaxNeighbourhood(const Points& rest, const Tets& tets, const std::vector<int>& fixedBone, Points& posed,
                        const std::vector<int>& centre, int rings, const CorotationalOptions& options,
                        CorotationalReport* report) {
  const Eigen::Index nV = rest.rows(), nT = tets.rows();
  if (posed.rows() != nV || Eigen::Index(fixedBone.size()) != nV)
    throw std::invalid_argument("relaxNeighbourhood: rest, posed and fixedBone differ in size");
  if (nT > 0 && (tets.minCoeff() < 0 || tets.maxCoeff() >= nV))
    throw std::invalid_argument("relaxNeighbourhood: a tet has a node index outside [0, " + std::to_string(nV) + ")");
  for (int v : centre)
    if (v < 0 || v >= nV) throw std::invalid_argument("relaxNeighbourhood: centre node " + std::to_string(v) + " out of range");
  relaxPart(rest, tets, fixedBone, posed, grownNeighbourhood(tets, fixedBone, centre, rings), options,
            RelaxationProgress::Neighbourhood, report);
}

namespace {

bool touches(const Tets& tets, Eigen::Index t, const std::vector<char>& set) {
  for (int c = 0; c < 4; ++c)
    if (set[std::size_t(tets(t, c))]) return true;
  return false;
}

// Grown ring by ring over the tets (a few passes over the tet list: no adjacency to build).
std::vector<char> grownNeighbourhood(const Tets& tets, const std::vector<int>& fixedBone, const std::vector<int>& centre,
                                     int rings) {
  auto isFree = [&](int v) { return fixedBone[std::size_t(v)] < 0; };
  std::vector<char> active(fixedBone.size(), 0);
  for (int v : centre) active[std::size_t(v)] = isFree(v);
  for (int ring = 0; ring < rings; ++ring) {
    std::vector<char> next = active;
    for (Eigen::Index t = 0; t < tets.rows(); ++t)
      if (touches(tets, t, active))
        for (int c = 0; c < 4; ++c)
          if (isFree(tets(t, c))) next[std::size_t(tets(t, c))] = 1;
    active.swap(next);
  }
  return active;
}

int relaxPart(const Points& rest, const Tets& tets, const std::vector<int>& fixedBone, Points& posed,
              const std::vector<char>& active, const CorotationalOptions& options, RelaxationProgress::Phase phase,
              CorotationalReport* report) {
  const Eigen::Index nV = rest.rows(), nT = tets.rows();
  // The part: the tets touching an unknown, their nodes renumbered.
  std::vector<int> local(std::size_t(nV), -1), global;
  std::vector<Eigen::Index> partTets;
  for (Eigen::Index t = 0; t < nT; ++t)
    if (touches(tets, t, active)) {
      partTets.push_back(t);
      for (int c = 0; c < 4; ++c) {
        const int v = tets(t, c);
        if (local[std::size_t(v)] < 0) {
          local[std::size_t(v)] = int(global.size());
          global.push_back(v);
        }
      }
    }
  // (No held node: a part of the mesh that no bone holds, singular on its own.)
  if (partTets.empty() || std::none_of(global.begin(), global.end(), [&](int v) { return !active[std::size_t(v)]; })) {
    if (report) *report = CorotationalReport{};
    return 0;
  }
  const Eigen::Index m = Eigen::Index(global.size());
  Points partRest(m, 3), partPosed(m, 3);
  std::vector<int> partFixed(static_cast<std::size_t>(m));
  for (Eigen::Index k = 0; k < m; ++k) {
    const int v = global[std::size_t(k)];
    partRest.row(k) = rest.row(v);
    partPosed.row(k) = posed.row(v);
    // Held nodes keep their bone (or 0 for a held free node: the id only matters to the continuation).
    partFixed[std::size_t(k)] = active[std::size_t(v)] ? -1 : std::max(0, fixedBone[std::size_t(v)]);
  }
  Tets partTetNodes(Eigen::Index(partTets.size()), 4);
  for (std::size_t q = 0; q < partTets.size(); ++q)
    for (int c = 0; c < 4; ++c) partTetNodes(Eigen::Index(q), c) = local[std::size_t(tets(partTets[q], c))];
  CorotationalOptions o = options;
  o.volumeRegions.clear();
  o.pathVolumeRegions.clear();
  o.boneParents.clear();
  o.startCorrection.resize(0, 3);
  o.continuation = CorotationalOptions::Never;
  o.untangle = false;
  o.strainedRegionThreshold = 0.0;
  if (options.checkpoint)
    o.checkpoint = [&options, phase](const RelaxationProgress& p) {
      RelaxationProgress part = p;
      part.phase = phase;
      return options.checkpoint(part);
    };
  relaxCorotational(partRest, partTetNodes, partFixed, partPosed, o, report);
  int unknowns = 0;
  for (Eigen::Index k = 0; k < m; ++k)
    if (partFixed[std::size_t(k)] < 0) {
      posed.row(global[std::size_t(k)]) = partPosed.row(k);
      ++unknowns;
    }
  return unknowns;
}

}  // namespace

}  // namespace repose
