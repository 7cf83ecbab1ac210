#include "fixed_corotated_newton.h"

#include <Eigen/LU>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <mutex>
#include <stdexcept>

#include "fem_checkpoint.h"
#include "parallel_for.h"
#include "tet_turning_point.h"
#include "tet_untangling.h"

namespace repose {
namespace fem {

namespace {

// The line search's first trial: 9/10 of the way to where the first barrier tet would turn flat
// along the step (or the whole step). Halving from the whole step, a thin tet turned at 1 and 1/2
// and the medium phantom's early Newton steps took 1/4 or 1/8 of theirs (every cut-back there was
// a turned tet, none the energy's); from the turning point they take 0.2-0.75, and its strained
// region needs 10 Newton steps in place of 12 (large: 17 in place of 22).
constexpr double kTurnFraction = 0.9;

// stepTolerance times the mean rest edge length: the scale of the step tolerance.
double stepLimitOf(const std::vector<RestTet>& restTets, double stepTolerance) {
  double edgeSum = 0;
  for (const RestTet& rt : restTets) {
    const Mat3 Dm = rt.DmInv.inverse();
    edgeSum += Dm.colwise().norm().sum() + (Dm.col(1) - Dm.col(0)).norm() + (Dm.col(2) - Dm.col(0)).norm() +
               (Dm.col(2) - Dm.col(1)).norm();
  }
  return stepTolerance * edgeSum / (6.0 * double(std::max<std::size_t>(restTets.size(), 1)));
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

}  // namespace

FixedCorotatedNewton::FixedCorotatedNewton(const Points& rest, const Tets& tets, const std::vector<int>& fixedBone,
                                           const std::vector<RestTet>& restTets, FreeNodeSystem& system,
                                           SpdSolver& solver, const CorotationalOptions& options, double lambda,
                                           double mu, Points& posed, CorotationalReport& rep, const Points* skinned)
    : rest(rest),
      tets(tets),
      fixedBone(fixedBone),
      freeNodes(system.freeNodes),
      options(options),
      rep(rep),
      posed(posed),
      terms(tets, fixedBone, restTets, system, options, lambda, mu),
      solver_(solver),
      matrix_(system.A),
      stepLimit_(stepLimitOf(restTets, options.stepTolerance)),
      step_(Eigen::Index(3 * system.freeNodes.size())),
      freeIndex_(std::size_t(posed.rows()), -1) {
  solver_.setLowRank(terms.regions.count > 0 ? &terms.regions.coupling : nullptr);
  // The input pose's energy (skinned: before the strained region was relaxed, when it was).
  terms.setBarrier(skinned ? *skinned : posed);
  energy = terms.evaluate(skinned ? *skinned : posed, inverted);
  rep.energyBefore = energy;
  if (skinned) {
    terms.setBarrier(posed);
    energy = terms.evaluate(posed, inverted);
  }
  trial = posed;
  for (std::size_t i = 0; i < freeNodes.size(); ++i) freeIndex_[std::size_t(freeNodes[i])] = int(i);
}

void FixedCorotatedNewton::useRegions(const std::vector<int>& ids) {
  terms.useRegions(ids);
  solver_.setLowRank(terms.regions.count > 0 ? &terms.regions.coupling : nullptr);
}

void FixedCorotatedNewton::solve(const Eigen::VectorXd& b, Eigen::VectorXd& x, double tolerance, int& iterations,
                                 double& residual) {
  if (matrix_.blocked)
    solver_.solve(matrix_.blocks, b, x, tolerance, iterations, residual);
  else
    solver_.solve(matrix_.scalar, b, x, tolerance, iterations, residual);
}

void FixedCorotatedNewton::checkCancelled(RelaxationProgress::Phase phase) {
  if (!options.checkpoint) return;
  RelaxationProgress p;
  p.phase = onPath ? RelaxationProgress::Continuation : phase;
  p.newtonIterations = rep.newtonIterations;
  p.continuationSteps = rep.continuationSteps;
  p.pathFraction = pathS;
  reachCheckpoint(options, p);
}

double FixedCorotatedNewton::firstTrialFraction() const {
  const std::vector<char>& barrier = terms.barrier;
  std::mutex lock;
  double first = 1.0 / kTurnFraction;
  parallelFor(barrier.size(), [&](std::size_t b, std::size_t e) {
    double local = 1.0 / kTurnFraction;
    for (std::size_t t = b; t < e; ++t) {
      if (!barrier[t]) continue;
      const auto T = tets.row(Eigen::Index(t));
      Vec3 d[4];
      for (int a = 0; a < 4; ++a) {
        const int i = freeIndex_[std::size_t(T[a])];
        d[a] = i >= 0 ? Vec3(step_.segment<3>(Eigen::Index(3 * i))) : Vec3::Zero();
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
}

void FixedCorotatedNewton::newton(int maxIterations) {
  // The barrier guards the tets positive now. (The energy is re-evaluated only when a flag changed:
  // callers pass the energy of posed.)
  if (terms.guarded() && terms.barrierFromState()) energy = terms.evaluate(posed, inverted);
  for (int it = 0; it < maxIterations; ++it)
    if (newtonStep()) return;
}

// One Newton step from posed; returns whether Newton has stopped (converged, or no step descends).
bool FixedCorotatedNewton::newtonStep() {
  checkCancelled(RelaxationProgress::Newton);
  const auto assemblyStart = std::chrono::steady_clock::now();
  terms.assemble(nullptr);
  rep.assemblySeconds += seconds(assemblyStart);
  const double gradNorm = terms.grad.norm();
  if (firstNorm < 0) firstNorm = gradNorm;
  if (!(gradNorm > 0.0)) {
    rep.converged = true;
    return true;
  }
  // Inexact Newton: the CG tolerance tightens as the gradient falls.
  const double eta = std::clamp(gradNorm / firstNorm, options.tolerance, 0.1);
  const auto solveStart = std::chrono::steady_clock::now();
  step_.setZero();
  int iterations = 0;
  double residual = 0.0;
  solve(-terms.grad, step_, eta, iterations, residual);
  rep.solveSeconds += seconds(solveStart);
  rep.cgIterations.push_back(iterations);
  rep.relativeResidual.push_back(residual);
  rep.newtonIterations = rep.outerIterations = rep.newtonIterations + 1;

  double maxMove = 0;
  for (std::size_t i = 0; i < freeNodes.size(); ++i)
    maxMove = std::max(maxMove, step_.segment<3>(Eigen::Index(3 * i)).norm());
  const double slope = terms.grad.dot(step_);
  double alpha = firstTrialFraction();
  bool smallDecrease = false;
  if (!lineSearch(maxMove, slope, alpha, smallDecrease)) {  // no descent left at this precision: at the minimum
    rep.converged = maxMove < stepLimit_;
    terms.evaluate(posed, inverted);  // the per-tet state of the iterate, not of the last trial
    return true;
  }
  for (int v : freeNodes) posed.row(v) = trial.row(v);
  if (alpha * maxMove < stepLimit_ || smallDecrease) {
    rep.converged = true;
    return true;
  }
  return false;
}

// Backtracking from alpha along step_: the first fraction (halved each time) that inverts no more
// tets and lowers the energy enough (Armijo) goes to trial, energy and inverted; returns whether one
// did. smallDecrease: the decrease was below the energy tolerance.
bool FixedCorotatedNewton::lineSearch(double maxMove, double slope, double& alpha, bool& smallDecrease) {
  for (int halving = 0; halving < 40 && alpha * maxMove > 1e-3 * stepLimit_; ++halving, alpha *= 0.5) {
    for (std::size_t i = 0; i < freeNodes.size(); ++i)
      trial.row(freeNodes[i]) = posed.row(freeNodes[i]) + alpha * step_.segment<3>(Eigen::Index(3 * i)).transpose();
    // A step that inverts more tets, or turns a barrier tet, is refused on the signs of the tet
    // volumes alone, without the per-tet SVDs of the energy (most of the line search's cut-backs
    // are such steps: far from the minimum, Newton's full step overshoots a thin tet).
    if (!trialAdmissible(trial, tets, terms.barrier, inverted)) continue;
    int trialInverted = 0;
    const double trialEnergy = terms.evaluate(trial, trialInverted);
    if (trialInverted <= inverted && trialEnergy <= energy + 1e-4 * alpha * std::min(slope, 0.0)) {
      smallDecrease = energy - trialEnergy < options.energyTolerance * energy &&
                      (!regionsSwitched || alpha * maxMove < 10.0 * stepLimit_);
      energy = trialEnergy;
      inverted = trialInverted;
      return true;
    }
  }
  return false;
}

// The energy is finite through det F = 0, so a few tets may settle inverted: move their free nodes
// out of the fold, then let Newton smooth the neighbourhood (it never re-inverts a tet; on the moved
// nodes' surroundings alone, see untangleRelaxRings, and on the whole mesh after the last round);
// Newton's moves may open room for another round. A round that leaves as many tets inverted (the
// untangling could not free them) is undone at once: its Newton steps would only spend time, and its
// pose is less relaxed than the one before it.
void FixedCorotatedNewton::untangleRounds() {
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
      energy = terms.evaluate(posed, inverted);
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
    energy = terms.evaluate(posed, inverted);
    relaxedLocally = true;
  }
  if (relaxedLocally) {  // the whole mesh around the relaxed neighbourhoods
    firstNorm = -1.0;
    newton(std::max(1, options.maxNewtonIterations / 2));
  }
}

// The multiplier takes the pressure the penalty holds, so the next minimum needs less excess for it.
void FixedCorotatedNewton::keepRegionVolumes() {
  if (!(options.regionVolumeStiffness > 0.0)) return;  // no penalty: no pressure to fold in
  double previousWorst = 0;
  for (int update = 0; update < options.maxRegionVolumeUpdates; ++update) {
    const double worst = terms.regions.worstExcess();
    if (worst <= options.regionVolumeTolerance) return;
    // Near the tolerance, an update that did not halve the worst excess has met the Newton solves'
    // own accuracy: more updates only spend Newton steps (medium phantom: 1.4e-4, then 1.2e-5,
    // 1.7e-5, 1.2e-5). Further out they still pay (the CMU walk's bodies: 2e-4 off without them).
    if (update > 0 && worst > 0.5 * previousWorst && worst < 10.0 * options.regionVolumeTolerance) return;
    previousWorst = worst;
    terms.regions.multiplier = terms.regions.pressure;
    ++rep.regionVolumeUpdates;
    energy = terms.evaluate(posed, inverted);
    firstNorm = -1.0;
    newton(std::max(1, options.maxNewtonIterations / 2));
  }
}

void FixedCorotatedNewton::finishReport() {
  // The regions' volumes are posed's too: evaluate() last ran on it or on the accepted trial.
  rep.energyAfter = energy;
  rep.regionVolumeRatio = terms.regions.ratios();
}

}  // namespace fem
}  // namespace repose
