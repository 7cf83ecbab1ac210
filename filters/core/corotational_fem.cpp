// The corotational relaxation's driver: checks the input, sets up what every model shares (the rest
// tets, the free nodes' system, the SPD solver) and runs the chosen model's stages in order:
//   fixed-corotated: strained region first (relaxation_neighbourhood), Newton (fixed_corotated_newton),
//     untangling rounds, region volumes, fold-free continuation (fold_free_continuation);
//   linear: outer iterations (linear_corotational_model).
#include "corotational_fem.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include "blas_threads.h"
#include "fem_checkpoint.h"
#include "fem_newton_matrix.h"
#include "fem_spd_solver.h"
#include "fem_tet_geometry.h"
#include "fixed_corotated_newton.h"
#include "fold_free_continuation.h"
#include "linear_corotational_model.h"
#include "relaxation_neighbourhood.h"

namespace repose {
namespace {

using namespace fem;

void checkSizes(const Points& rest, const std::vector<int>& fixedBone, const Points& posed) {
  const Eigen::Index nV = rest.rows();
  if (posed.rows() != nV)
    throw std::invalid_argument("relaxCorotational: posed has " + std::to_string(posed.rows()) +
                                " nodes but rest has " + std::to_string(nV));
  if (Eigen::Index(fixedBone.size()) != nV)
    throw std::invalid_argument("relaxCorotational: fixedBone has " + std::to_string(fixedBone.size()) +
                                " entries but the mesh has " + std::to_string(nV) + " nodes");
}

void checkSolverOptions(const CorotationalOptions& options) {
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
}

void checkRegionOptions(const CorotationalOptions& options, Eigen::Index nV, Eigen::Index nT) {
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
}

void checkMesh(const Tets& tets, const std::vector<int>& fixedBone, const CorotationalOptions& options, Eigen::Index nV) {
  const Eigen::Index nT = tets.rows();
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
}

/// posed plus options.startCorrection on the unknowns (fixed nodes and nodes in no tet stay), if that
/// turns no positive tet; returns whether it was taken.
bool takeStartCorrection(const Tets& tets, const std::vector<int>& freeNodes, const CorotationalOptions& options,
                         Points& posed) {
  Points start = posed;
  for (int v : freeNodes) start.row(v) += options.startCorrection.row(v);
  if (turnsAPositiveTet(posed, start, tets)) return false;
  posed = start;
  return true;
}

/// The fixed-corotated model's stages on posed (see CorotationalOptions::FixedCorotated).
void relaxFixedCorotated(const Points& rest, const Tets& tets, const std::vector<int>& fixedBone,
                         const std::vector<RestTet>& restTets, FreeNodeSystem& system, SpdSolver& solver,
                         const CorotationalOptions& options, double lambda, double mu, Points& posed,
                         CorotationalReport& rep, const Points* skinned) {
  FixedCorotatedNewton solve(rest, tets, fixedBone, restTets, system, solver, options, lambda, mu, posed, rep, skinned);
  solve.newton(options.maxNewtonIterations);
  solve.untangleRounds();
  // Region volumes to regionVolumeTolerance (see CorotationalOptions::regionVolumeTolerance).
  solve.keepRegionVolumes();
  foldFreeContinuation(solve);
  solve.finishReport();
}

/// relaxCorotational's work on posed in place (a cancelled solve leaves it part-way).
void relaxInPlace(const Points& rest, const Tets& tets, const std::vector<int>& fixedBone, Points& posed,
                  const CorotationalOptions& options, CorotationalReport* report) {
  const auto start = std::chrono::steady_clock::now();
  const Eigen::Index nV = rest.rows();
  checkSizes(rest, fixedBone, posed);
  checkSolverOptions(options);
  checkRegionOptions(options, nV, tets.rows());
  checkMesh(tets, fixedBone, options, nV);

  reachCheckpoint(options, RelaxationProgress{});
  const SingleThreadedBlas blasOnThisThread;  // the CG's threads keep the cores (see blas_threads.h)
  CorotationalReport local;
  CorotationalReport& rep = report ? *report : local;
  rep = CorotationalReport{};
  rep.invertedBefore = countInverted(posed, tets);

  std::vector<int> freeNodes = unknownNodes(tets, fixedBone, nV);
  const std::size_t nFree = freeNodes.size();
  if (options.startCorrection.size() > 0) rep.correctedStart = takeStartCorrection(tets, freeNodes, options, posed);
  // Rest data per tet (shape-function gradients and volume); rest tets must be positive.
  const std::vector<RestTet> restTets = restTetsOf(rest, tets);
  if (nFree == 0) {
    rep.invertedAfter = rep.invertedBefore;
    rep.seconds = seconds(start);
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

  FreeNodeSystem system = freeNodeSystem(tets, fixedBone, std::move(freeNodes),
                                         options.preconditioner == CorotationalOptions::BlockJacobi ||
                                             options.preconditioner == CorotationalOptions::TwoLevel);
  SpdSolver solver(options);
  solver.setNodes(rest, posed, system.freeNodes);
  if (options.model == CorotationalOptions::FixedCorotated)
    relaxFixedCorotated(rest, tets, fixedBone, restTets, system, solver, options, lambda, mu, posed, rep,
                        skinned.rows() > 0 ? &skinned : nullptr);
  else
    relaxLinearCorotational(rest, tets, fixedBone, restTets, system, solver, options, lambda, mu, posed, rep);
  countInvertedAfter(posed, tets, fixedBone, rep);
  rep.seconds = seconds(start);
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

}  // namespace repose
