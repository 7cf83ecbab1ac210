#pragma once
// Static corotational linear-elastic relaxation of a posed tet mesh (Mueller & Gross 2004):
// refines a skinned pose so that nearly incompressible tissue keeps its volume.
#include <functional>
#include <stdexcept>
#include <vector>

#include "tet_mesh.h"

namespace repose {

struct RelaxationProgress;

/// The defaults are those of vtkReposeCorotationalRelax (its constructor reads them from here), the
/// solve every user of the CLI, the GUI and the Python filters gets.
struct CorotationalOptions {
  /// Poisson's ratio, in (-1, 0.5). Near 0.5 the tissue is nearly incompressible (and CG slower).
  double poisson = 0.49;
  /// Young's modulus. With displacement boundary conditions only, the static equilibrium
  /// K'(x) x = f0 is homogeneous in E (both sides scale with it), so the solution does not depend
  /// on E; nor does the relative CG residual or the Jacobi / incomplete-Cholesky convergence.
  /// 1 keeps the matrix entries O(element size) in mm, far from under- or overflow.
  double young = 1.0;
  /// Corotational outer iterations: rotations re-extracted from the last solution, then solved again.
  int outerIterations = 1;
  /// CG stops when |K'x - f0| / |f0| <= tolerance.
  double tolerance = 1e-6;
  int maxCgIterations = 2000;
  /// Eigen's ConjugateGradient with DiagonalPreconditioner (Jacobi) or IncompleteCholesky (AMD
  /// ordering): fewer iterations, but the factorization and triangular solves cost more.
  /// Cholmod: no CG, a CHOLMOD supernodal Cholesky factorization (symbolic analysis once per
  /// call, numeric factorization per outer / Newton iteration) and a direct solve.
  /// BlockJacobi: our CG on the matrix stored as float 3x3 blocks (a third of the memory traffic),
  /// preconditioned by the inverses of the diagonal blocks, threaded.
  /// TwoLevel (default): the same block CG with a two-level preconditioner, block Jacobi plus a coarse
  /// correction by the rigid-body modes of aggregates of about coarseAggregateSize nodes
  /// (see two_level_preconditioner.h).
  enum Preconditioner { Jacobi, IncompleteCholesky, Cholmod, BlockJacobi, TwoLevel };
  Preconditioner preconditioner = TwoLevel;
  /// TwoLevel: target nodes per aggregate. Larger: a smaller coarse matrix, more CG iterations.
  int coarseAggregateSize = 200;
  /// TwoLevel: solves with a looser relative tolerance than this use block Jacobi alone (a truncated
  /// block-Jacobi CG moves the nodes locally). With the inversion barrier, FixedCorotated's loose
  /// first Newton steps also gain from the coarse space (tiny phantom, squat frame: 34 Newton steps
  /// instead of 45), so by default every solve is two-level.
  double twoLevelBelowTolerance = 1.0;
  /// TwoLevel: the coarse level (the aggregates' rigid modes, P^T A P and its Cholesky factorization)
  /// is rebuilt for one solve in this many; the solves in between take their own matrix's block-Jacobi
  /// inverses beside the last coarse level. That is still an SPD preconditioner, so CG converges to
  /// the same tolerance, and consecutive Newton matrices differ little, so a coarse level a few steps
  /// old costs few iterations more, while its rebuild is 0.15-0.5 s of a medium-phantom Newton step
  /// (every 4th solve: small and medium phantoms at 30, 45 and 60 degrees 5-17 % faster, a warm start
  /// on medium 16 s against 24 s; medium's 45 degree pose from cold took one more whole-mesh Newton
  /// step, 26-28 s against 25-26 s). 1: every solve.
  int coarseRefreshInterval = 4;

  /// Linear: linearized corotational elasticity (Mueller & Gross), outerIterations solves; its
  /// volume is only kept to first order (sum of the principal stretches, not their product).
  /// FixedCorotated: the nonlinear, inversion-safe energy
  ///   psi(F) = mu |F - R|^2 + lambda/2 (det F - 1)^2   (Stomakhin et al. 2012)
  /// plus the inversion penalty below, minimized by projected Newton (per-tet Hessians with their
  /// negative eigenvalues clamped, Smith et al. 2019) with PCG and a backtracking line search that
  /// accepts a step only if it lowers the energy and does not increase the number of inverted tets
  /// (starting from 9/10 of the way to where the first tet would turn flat, tet_turning_point.h).
  enum Model { Linear, FixedCorotated };
  Model model = FixedCorotated;
  /// FixedCorotated: at most this many Gauss-Newton iterations.
  int maxNewtonIterations = 60;
  /// FixedCorotated: stops when the largest node move of a step is below stepTolerance times the
  /// mean rest edge length (then det F is settled to about that relative accuracy).
  double stepTolerance = 0.01;
  /// FixedCorotated: also stops when an iteration lowers the energy by less than this fraction
  /// (after the continuation's path has switched to volumeRegions, only with a move below 10
  /// stepTolerance edge lengths too: the new region terms start far from their targets but are a
  /// tiny part of the energy, and Newton stopped with tissue regions 6e-3 off, where 5e-5 is reached).
  double energyTolerance = 1e-3;
  /// FixedCorotated: a penalty inversionPenalty * lambda * (inversionThreshold - det F)^2 is added
  /// to each tet's energy density below det F = inversionThreshold. The fixed-corotated energy is
  /// finite through det F = 0, so without it a fold can be a minimum (where skinning drives tissue
  /// into tissue, e.g. in a deep crease); the penalty leaves tets with det F above the threshold
  /// (all but the most compressed) untouched. 0 turns it off.
  double inversionPenalty = 10.0;
  double inversionThreshold = 0.1;
  /// FixedCorotated: tets that are positive when a Newton run starts (all but those the skinning or
  /// a fold left inverted) get, in place of that penalty, the clamped log barrier
  ///   inversionPenalty * lambda * b(det F),  b(J) = -(J - t)^2 ln(J / t) below J = t = inversionThreshold
  /// (C2 at t, infinite at J = 0; Li et al. 2020). The penalty's finite stiffness lets Newton's step
  /// aim through det F = 0, and the line search, which refuses new inversions, then cuts the whole
  /// step until it stalls far from the minimum; the barrier's growing stiffness turns the step
  /// itself away from inversion. Tets inverted at the start keep the penalty, which is finite there.
  bool inversionBarrier = true;
  /// FixedCorotated: optional volume regions, one entry per tet (0 .. #tets - 1: the tet's region, -1: none;
  /// empty: no region term). Each region r adds the energy
  ///   regionVolumeStiffness * lambda / 2 * V_r0 (V_r / V_r0 - 1)^2
  /// over the volume V_r of its tets that have a free node: the per-tet volume term again, for the
  /// region as a whole. Linear tets lock when nearly incompressible: at nu = 0.49 a squeezed part of
  /// the body loses volume because the per-tet pressures cannot reach a volume-keeping bulge. One
  /// pressure per region (a piecewise-constant pressure field, as in mixed elements) has no such
  /// lock. Its Hessian couples a region's whole surface: kept as a low-rank term beside the sparse
  /// blocks in CG (BlockJacobi and TwoLevel only; the other solvers omit it from the Newton matrix).
  /// The penalty alone leaves each region short by about its pressure / stiffness (on the tiny
  /// phantom's walk, bodies 0.12-0.35 % short at stiffness 3): after Newton has converged, each
  /// region's pressure is folded into a fixed multiplier term Lambda_r (V_r - V_r0) (augmented
  /// Lagrangian) and Newton resumes, until every region is within regionVolumeTolerance of its rest
  /// volume, after maxRegionVolumeUpdates such updates, or once an update has not halved the worst
  /// region's excess when that is within 10 regionVolumeTolerance (the Newton solves' own accuracy
  /// is then the limit). Raising the stiffness instead works too,
  /// but slows CG (stiffness 300: twice the CG iterations) where an update costs a few Newton steps.
  std::vector<int> volumeRegions;
  /// The regions of the fold-free continuation's path before its end (empty: volumeRegions), the
  /// same form. Coarser regions than the pose's keep the path moving: with a term per tissue, a thin
  /// tissue squeezed between bones must keep its own volume at every step, and the path can stall
  /// there (tiny phantom's test pose: 170 steps and not kept, against 29 with body segments).
  /// volumeRegions take over at the path's end, for its last Newton solve and multiplier updates.
  std::vector<int> pathVolumeRegions;
  double regionVolumeStiffness = 30.0;
  double regionVolumeTolerance = 1e-5;
  int maxRegionVolumeUpdates = 4;
  /// Tets still inverted after the solve get their free nodes moved out of the fold (see
  /// tet_untangling.h); FixedCorotated then resumes Newton from there.
  bool untangle = true;
  /// FixedCorotated: after an untangling round, the free nodes it moved and this many rings of free
  /// neighbours around them are relaxed on their own (relaxNeighbourhood: the rest of the mesh was
  /// at its minimum and is held), then the whole mesh once after the last round. Each round used to
  /// cost a whole-mesh Newton solve of 5 to 8 steps; the neighbourhood's is a few hundredths of a
  /// second (medium phantom, 45 degree pose: 22 Newton steps in place of 30, 56 s in place of 72).
  /// < 0: a whole-mesh solve after every round (the former way, kept for comparison).
  int untangleRelaxRings = 2;
  /// FixedCorotated, from a cold start (no startCorrection taken): the strained region is relaxed on its
  /// own before the whole mesh. Its tets are those whose skinned strain, |sigma - 1|^2 +
  /// lambda / (2 mu) (det F - 1)^2 (the energy density over mu), exceeds this threshold; their free
  /// nodes and strainedRegionRings rings of free neighbours are the unknowns of a relaxNeighbourhood
  /// solve, with every other node held where skinning put it. Skinning moves most of the body
  /// rigidly, and the nonlinear work (the barrier, the line search's cut-backs) is all at the
  /// joints: there Newton's steps cost what the part costs, and the whole mesh then starts next to
  /// its minimum (medium phantom, 45 degree pose: half the free nodes, 12 part steps, then 4
  /// whole-mesh steps in place of 16; 28-36 s in place of 50-55 s, to a 0.3 % lower energy). A warm
  /// start is already next to its minimum (the same pose warm: no gain), so it goes straight to the
  /// whole mesh, and so does a part of more than 90 % of the free nodes (no cheaper than the whole).
  /// 0: off. The default, 1e-4, takes strains above about 1 % or volume changes above 0.2 %.
  double strainedRegionThreshold = 1e-4;
  int strainedRegionRings = 3;
  /// FixedCorotated: a fold can be a local minimum (skin folded into a deep crease, where a node
  /// moved one at a time cannot get out). Then the pose is solved again by continuation from the
  /// rest shape, which has no fold: the bone nodes move along rigid paths (bone_path.h) in steps, each
  /// a predictor (the free nodes' linear response to the bone move, cut back until no tet inverts) and
  /// Newton corrections with the barrier on every tet, so no tet is ever inverted on the way.
  /// The result replaces the direct one if it has fewer inverted tets (IfInverted), or always (Always,
  /// for tests and comparisons). Never: the direct solve only. Needs inversionBarrier. IfInverted
  /// does not start where a node is pinched between bones (pinched_nodes.h): no fold-free pose exists
  /// there, so no path can reach its end (medium phantom, 45 degree pose: 2 nodes 0.63 mm short, and
  /// a path that crawled 57 steps, 165 s, before giving up). Always runs the path all the same.
  enum Continuation { Never, IfInverted, Always };
  Continuation continuation = IfInverted;
  /// ... in at most this many steps (the step length adapts: doubled after a full step, cut to the
  /// accepted fraction otherwise); the direct result is kept if the path is not completed. Where the
  /// path stalls (at the pace of its last 20 steps it would need more than twice this budget in
  /// all, or a step falls below 1e-6 of it), the tissue is first relaxed there (Newton
  /// with the bones held, at most 3 times per path, not again where the path has not moved 1e-3
  /// since, nor after a relaxation that did not speed the path up, see continuation_stall.h): carried
  /// by predictors alone it can block the way (walk frame 192, tiny phantom, whole mesh at once, with
  /// the line search of an earlier release: stalled at s = 0.45, completed after one such solve).
  int maxContinuationSteps = 200;
  /// ... and this many Newton corrections per intermediate step (the last one gets
  /// maxNewtonIterations). The predictor is itself a Newton step of the moved problem (it also takes
  /// out what is left of the gradient), and the path only needs to stay inside the fold-free set:
  /// on the small phantom's 45 degree pose, 0 corrections took 26 s (28 steps), 1 took 41 s (27
  /// steps), to final energies within 0.01 %.
  int continuationCorrections = 0;
  /// The continuation's bone paths follow the skeleton when given: per bone id (the fixedBone
  /// values), its parent's id or -1. Empty: each bone's path on its own (see bone_path.h).
  std::vector<int> boneParents;
  /// Optional (#V by 3, or empty): a correction added to posed's free nodes to make the start, e.g.
  /// the last animation frame's relaxed minus skinned positions. Consecutive frames differ little,
  /// so Newton then starts next to the minimum (tiny phantom, walk frame 432: 12 Newton steps
  /// instead of 35 and a continuation). Taken only if it inverts no tet that posed has positive:
  /// FixedCorotated with the barrier never turns a positive tet (nor does untangling), so its result
  /// then has every tet positive that posed has. The result may be another local minimum than from
  /// posed alone (the tissue's history): frames stay coherent rather than each finding its own minimum.
  Points startCorrection;
  /// Optional: called with where the solve is before the set-up, each Newton step, each untangling
  /// round, each continuation step and each linear outer iteration (a few seconds apart at most on a
  /// 2.7 M-tet mesh), on the solving thread. Returning true stops the solve with RelaxationCancelled,
  /// posed as it came in. It must be cheap (report progress, read an atomic flag).
  std::function<bool(const RelaxationProgress&)> checkpoint;
};

/// Where a relaxation is, as CorotationalOptions::checkpoint sees it.
struct RelaxationProgress {
  enum Phase { Setup, Newton, Untangling, Neighbourhood, Continuation, Linear, StrainedRegion };
  Phase phase = Setup;
  int newtonIterations = 0;   ///< whole-mesh Newton steps so far (Neighbourhood, StrainedRegion: that part's own)
  int continuationSteps = 0;  ///< fold-free continuation steps so far
  double pathFraction = 0.0;  ///< Continuation: how far along the bones' paths (0 to 1)
  int outerIteration = 0;     ///< Linear: the outer iteration about to start (0-based)
};

/// Thrown by relaxCorotational when CorotationalOptions::checkpoint answers true.
struct RelaxationCancelled : std::runtime_error {
  RelaxationCancelled() : std::runtime_error("relaxation cancelled") {}
};

struct CorotationalReport {
  int outerIterations = 0;               ///< outer iterations done
  std::vector<int> cgIterations;         ///< per outer iteration
  std::vector<double> relativeResidual;  ///< per outer iteration, CG's |r| / |b| at exit
  int invertedBefore = 0;                ///< tets with signed volume <= 0 in the input pose
  int invertedAfter = 0;                 ///< ... in the relaxed pose
  double seconds = 0.0;                  ///< wall time of the whole call
  double assemblySeconds = 0.0;          ///< of which rotations + matrix assembly (all iterations)
  double solveSeconds = 0.0;             ///< of which CG (all iterations)
  int newtonIterations = 0;              ///< FixedCorotated: Gauss-Newton iterations done
  double energyBefore = 0.0;             ///< FixedCorotated: energy of the input pose (the barrier on its positive tets)
  double energyAfter = 0.0;              ///< ... and of the result
  bool converged = false;                ///< FixedCorotated: the step tolerance was reached
  int untangledNodes = 0;                ///< node moves made by the untangling step
  int untangleNewtonIterations = 0;      ///< Newton iterations of the neighbourhood solves after untangling
  double untangleSeconds = 0.0;          ///< ... and its time
  int invertedRigid = 0;                 ///< inverted tets after relaxing whose nodes are all fixed
  std::vector<double> regionVolumeRatio; ///< FixedCorotated with volumeRegions: V_r / V_r0 after relaxing
  int regionVolumeUpdates = 0;           ///< ... and the multiplier updates made (see regionVolumeTolerance)
  int continuationSteps = 0;             ///< FixedCorotated: steps of the fold-free continuation (0: not run)
  bool continuationUsed = false;         ///< ... whose result replaced the direct solve's
  double continuationSeconds = 0.0;      ///< ... and its time (included in seconds)
  int continuationRescues = 0;           ///< ... and its relaxing Newton solves where the path stalled
  bool correctedStart = false;           ///< options.startCorrection was taken
  int strainedRegionNodes = 0;           ///< unknowns of the strained region's solve (0: not run)
  int strainedRegionNewtonIterations = 0;///< ... its Newton iterations (not in newtonIterations)
  double strainedRegionSeconds = 0.0;    ///< ... and its time (included in seconds)
  /// Free nodes of the result pinched between bones (pinched_nodes.h): folds that no solve can
  /// remove, so the IfInverted continuation is not run for them.
  int pinchedNodes = 0;
  double pinchedShortfall = 0.0;         ///< ... the farthest one of them stays on the wrong side of a bone face
};

/// Relaxes posed to the static equilibrium of corotational linear elasticity.
///
/// rest       #V by 3 rest node positions (the stress-free shape)
/// tets       #T by 4 node indices, positively oriented at rest (rest volume > 0)
/// fixedBone  #V: >= 0 marks a Dirichlet node, held at its current position in posed; -1 is free
/// posed      #V by 3, in: the warm start (e.g. the skinned pose), out: the relaxed positions
///            (fixed nodes and nodes in no tet are left untouched)
/// options    see CorotationalOptions
/// report     optional; filled with iteration counts, residuals, inverted tet counts, time
///
/// Element rotations come from the polar decomposition of F = Ds Dm^-1 by SVD with the sign fixed
/// so that det R = +1 (Irving et al. 2004): an inverted tet's rotation does not flip it further.
/// Assembly is threaded with parallelFor; the SPD system of the free nodes is solved by CG
/// warm-started from posed. A pose with no free node is a no-op.
/// Throws std::invalid_argument on size mismatches, out-of-range node indices, degenerate or
/// inverted rest tets, bad options, or when no node is fixed (the system would be singular).
/// With options.model == FixedCorotated the nonlinear energy above is minimized instead (the report's
/// cgIterations / relativeResidual are then per Newton iteration); the number of inverted tets never
/// increases, and inverted skinned tets are pushed back since the energy is finite and smooth
/// through det F = 0. Young's modulus scales the energy only: the minimizer does not depend on it.
/// Throws std::runtime_error if the incomplete Cholesky, CHOLMOD or two-level coarse factorization fails,
/// and RelaxationCancelled (posed unchanged) when options.checkpoint asks it to stop.
void relaxCorotational(const Points& rest, const Tets& tets, const std::vector<int>& fixedBone,
                       Points& posed, const CorotationalOptions& options,
                       CorotationalReport* report = nullptr);

/// Relaxes the neighbourhood of some nodes on its own: the free nodes in centre and `rings` rings of
/// free neighbours around them (nodes sharing a tet) are the unknowns, on the tets that touch them;
/// every other node is held where posed has it. This is relaxCorotational on that part of the mesh
/// (options' model, solver and tolerances; no volume regions, continuation, start correction or
/// untangling), so the result is the minimum of the whole mesh's energy over those unknowns. Nodes
/// outside the neighbourhood are not touched. Fixed nodes and nodes of no tet in centre are ignored;
/// an empty neighbourhood, or one that holds no node, is a no-op. report, if given, is the part's.
/// Throws std::invalid_argument on size mismatches, or tet or centre nodes out of range.
void relaxNeighbourhood(const Points& rest, const Tets& tets, const std::vector<int>& fixedBone, Points& posed,
                        const std::vector<int>& centre, int rings, const CorotationalOptions& options,
                        CorotationalReport* report = nullptr);

}  // namespace repose
