#include "fold_free_continuation.h"

#include <algorithm>
#include <chrono>

#include "bone_path.h"
#include "continuation_stall.h"
#include "fem_checkpoint.h"
#include "pinched_nodes.h"

namespace repose {
namespace fem {

namespace {

// The path from s = 0 (the rest shape under the skeleton's global rigid motion) to s = 1 (the pose),
// one predictor step at a time: the free nodes' linear response to the bones' move, cut back until no
// tet with a free node inverts; the step length doubles after a full step and shrinks to the accepted
// fraction otherwise.
class FoldFreePath {
 public:
  /// Puts posed at s = 0. direct: the pose whose bone nodes the path ends at.
  FoldFreePath(FixedCorotatedNewton& solve, const Points& direct);
  /// Steps until the path ends, its step budget is spent or it stalls; returns whether it ended.
  bool run();

 private:
  bool step();
  bool predict(double target, double& alpha);
  bool relaxHere();
  int invertedWithFreeNode(const Points& x) const { return countInverted(x, solve_.tets, &solve_.terms.hasFree); }

  FixedCorotatedNewton& solve_;
  const BonePath path_;
  const bool pathRegions_;   // the path has regions of its own (pathVolumeRegions)
  std::vector<int> pathNodes_;  // the Dirichlet nodes of the tets
  Points move_;              // #V by 3: the bone nodes' move of the step (0 elsewhere)
  Eigen::VectorXd predictor_;
  double s_ = 0.0, ds_ = 0.125;
  int rescues_ = 0;          // relaxing Newton solves after a stall
  double rescuedAt_ = -1.0;  // s of the last one
  double paceAtRescue_ = 0.0;  // ... and the path's pace that called for it (continuation_stall.h)
  std::vector<double> sHistory_;  // s after each step since the start or the last rescue
};

FoldFreePath::FoldFreePath(FixedCorotatedNewton& solve, const Points& direct)
    : solve_(solve),
      path_(solve.rest, direct, solve.fixedBone, solve.options.boneParents),
      pathRegions_(!solve.options.pathVolumeRegions.empty()),
      move_(Points::Zero(solve.posed.rows(), 3)),
      predictor_(Eigen::Index(3 * solve.freeNodes.size())) {
  const Tets& tets = solve.tets;
  std::vector<char> seen(std::size_t(solve.posed.rows()), 0);
  for (Eigen::Index t = 0; t < tets.rows(); ++t)
    for (int a = 0; a < 4; ++a) {
      const int v = tets(t, a);
      if (solve.fixedBone[std::size_t(v)] >= 0 && !seen[std::size_t(v)]) {
        seen[std::size_t(v)] = 1;
        pathNodes_.push_back(v);
      }
    }
  // s = 0: the rest shape under the skeleton's global rigid motion; no tet is inverted there.
  for (int v : solve.freeNodes) solve.posed.row(v) = path_.start(node(solve.rest, v)).transpose();
  path_.place(0.0, pathNodes_, solve.posed);
  solve.trial = solve.posed;
  solve.terms.barrier = solve.terms.hasFree;  // every tet is positive all along
}

bool FoldFreePath::run() {
  solve_.onPath = true;
  while (s_ < 1.0 && solve_.rep.continuationSteps < solve_.options.maxContinuationSteps)
    if (!step()) break;
  return s_ >= 1.0;
}

// One step of the path; returns whether the path goes on.
bool FoldFreePath::step() {
  const CorotationalOptions& options = solve_.options;
  solve_.pathS = s_;
  solve_.checkCancelled(RelaxationProgress::Continuation);
  ++solve_.rep.continuationSteps;
  const double target = std::min(1.0, s_ + ds_);
  double alpha = 1.0;
  if (!predict(target, alpha)) return relaxHere();
  s_ = alpha == 1.0 ? target : s_ + alpha * (target - s_);
  solve_.posed = solve_.trial;
  ds_ = alpha == 1.0 ? std::min(2.0 * ds_, 0.5) : alpha * ds_;
  // Steps that stay short: see continuation_stall.h.
  sHistory_.push_back(s_);
  if (ds_ < 1e-6 || continuationPaceStalls(sHistory_, solve_.rep.continuationSteps, options.maxContinuationSteps))
    return relaxHere();
  if (s_ >= 1.0 && pathRegions_) {  // the pose's own regions from here
    solve_.useRegions(options.volumeRegions);
    solve_.regionsSwitched = true;
  }
  solve_.energy = solve_.terms.evaluate(solve_.posed, solve_.inverted);
  solve_.firstNorm = -1.0;  // each correction's forcing terms start afresh
  if (s_ >= 1.0 || options.continuationCorrections > 0)
    solve_.newton(s_ < 1.0 ? options.continuationCorrections : options.maxNewtonIterations);
  return true;
}

// The predictor towards target, and the largest fraction alpha of it (halved from 1) that leaves
// every tet positive, placed in the solve's trial pose; returns whether some fraction did.
bool FoldFreePath::predict(double target, double& alpha) {
  Points& posed = solve_.posed;
  CorotationalReport& rep = solve_.rep;
  path_.place(target, pathNodes_, move_);
  for (int v : pathNodes_) move_.row(v) -= posed.row(v);
  solve_.energy = solve_.terms.evaluate(posed, solve_.inverted);
  const auto assemblyStart = std::chrono::steady_clock::now();
  solve_.terms.assemble(&move_);
  rep.assemblySeconds += seconds(assemblyStart);
  // Predictor: the free nodes' response to the bone move (and to what is left of the gradient).
  const auto solveStart = std::chrono::steady_clock::now();
  predictor_.setZero();
  int iterations = 0;
  double residual = 0.0;
  solve_.solve(-(solve_.terms.grad + solve_.terms.dirichletForce), predictor_, 1e-2, iterations, residual);
  rep.solveSeconds += seconds(solveStart);
  const std::vector<int>& freeNodes = solve_.freeNodes;
  for (int halving = 0; halving < 16; ++halving, alpha *= 0.5) {
    path_.place(s_ + alpha * (target - s_), pathNodes_, solve_.trial);
    for (std::size_t i = 0; i < freeNodes.size(); ++i)
      solve_.trial.row(freeNodes[i]) =
          posed.row(freeNodes[i]) + alpha * predictor_.segment<3>(Eigen::Index(3 * i)).transpose();
    if (invertedWithFreeNode(solve_.trial) == 0) return true;
  }
  return false;
}

// A stall (no fold-free fraction of the predictor, or steps that stay short) may be the tissue
// itself, carried along by predictors alone, blocking the way: it is relaxed at this s (Newton, the
// bones held) and the path tried again, a few times per path. A stall where the last rescue was made
// (the path has not moved 1e-3 on since) is the same block: that rescue had relaxed the tissue here
// already, so another finds the same minimum (medium phantom, 45 degree pose: rescues 2 and 3 at
// s = 0.6279, after the first at 0.6276). Nor is it relaxed again when the last relaxation has not
// sped the path up (continuationRelaxationPaid). Returns whether the path goes on.
bool FoldFreePath::relaxHere() {
  if (rescues_ >= 3 || (rescuedAt_ >= 0.0 && s_ - rescuedAt_ < 1e-3)) return false;
  if (rescuedAt_ >= 0.0 && !continuationRelaxationPaid(sHistory_, rescuedAt_, paceAtRescue_)) return false;
  paceAtRescue_ = continuationPace(sHistory_, std::max(rescuedAt_, 0.0));
  ++rescues_;
  ++solve_.rep.continuationRescues;
  rescuedAt_ = s_;
  solve_.energy = solve_.terms.evaluate(solve_.posed, solve_.inverted);
  solve_.firstNorm = -1.0;
  solve_.newton(std::max(1, solve_.options.maxNewtonIterations / 2));
  ds_ = std::max(ds_, 1e-3);
  sHistory_.clear();
  return true;
}

}  // namespace

void foldFreeContinuation(FixedCorotatedNewton& solve) {
  const CorotationalOptions& options = solve.options;
  CorotationalReport& rep = solve.rep;
  Points& posed = solve.posed;
  FixedCorotatedEnergy& terms = solve.terms;
  const int directInverted = countInverted(posed, solve.tets, &terms.hasFree);
  // A node pinched between bones has no fold-free place: no path can end (see Continuation).
  if (!(terms.guarded() &&
        (options.continuation == CorotationalOptions::Always ||
         (options.continuation == CorotationalOptions::IfInverted && directInverted > 0 &&
          findPinchedNodes(posed, solve.tets, solve.fixedBone).empty()))))
    return;
  const auto continuationStart = std::chrono::steady_clock::now();
  const Points direct = posed;
  const bool directConverged = rep.converged;
  const std::vector<char> directBarrier = terms.barrier;
  const std::vector<double> directMultiplier = terms.regions.multiplier;
  // The path's own regions, if any; the multipliers start at 0 (the rest shape has no pressure).
  const bool pathRegions = !options.pathVolumeRegions.empty();
  if (pathRegions)
    solve.useRegions(options.pathVolumeRegions);
  else
    std::fill(terms.regions.multiplier.begin(), terms.regions.multiplier.end(), 0.0);
  FoldFreePath path(solve, direct);
  // Newton never inverts a tet, so a completed path ends fold-free.
  const bool completed = path.run();
  if (completed) solve.keepRegionVolumes();
  if (completed && (options.continuation == CorotationalOptions::Always ||
                    countInverted(posed, solve.tets, &terms.hasFree) < directInverted)) {
    rep.continuationUsed = true;
  } else {
    posed = direct;
    terms.barrier = directBarrier;
    if (pathRegions && !completed) solve.useRegions(options.volumeRegions);
    terms.regions.multiplier = directMultiplier;
    solve.energy = terms.evaluate(posed, solve.inverted);
    rep.converged = directConverged;
  }
  rep.continuationSeconds = seconds(continuationStart);
}

}  // namespace fem
}  // namespace repose
