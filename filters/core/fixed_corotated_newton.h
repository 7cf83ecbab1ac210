#pragma once
// Projected Newton on the fixed-corotated energy (internal to corotational_fem, see
// CorotationalOptions::FixedCorotated): each step solves the projected Hessian's system by the chosen
// SPD solver (inexact: the CG tolerance tightens as the gradient falls) and a backtracking line
// search accepts it only if it lowers the energy and inverts no more tets; then the untangling
// rounds for the tets left inverted, and the volume regions' multiplier updates.
#include <Eigen/Core>
#include <vector>

#include "corotational_fem.h"
#include "fem_newton_matrix.h"
#include "fem_spd_solver.h"
#include "fem_tet_geometry.h"
#include "fixed_corotated_energy.h"

namespace repose {
namespace fem {

/// The state of one fixed-corotated solve of posed, shared by its stages (Newton, untangling,
/// region volumes, the fold-free continuation): the iterate, its energy and its inverted tets.
struct FixedCorotatedNewton {
  /// Evaluates the start: rep.energyBefore is that of skinned when given (the input pose, before the
  /// strained region was relaxed), else of posed. All arguments must outlive the solve; posed is the
  /// iterate, updated in place.
  FixedCorotatedNewton(const Points& rest, const Tets& tets, const std::vector<int>& fixedBone,
                       const std::vector<RestTet>& restTets, FreeNodeSystem& system, SpdSolver& solver,
                       const CorotationalOptions& options, double lambda, double mu, Points& posed,
                       CorotationalReport& rep, const Points* skinned);
  FixedCorotatedNewton(const FixedCorotatedNewton&) = delete;
  FixedCorotatedNewton& operator=(const FixedCorotatedNewton&) = delete;

  /// At most maxIterations Newton steps from posed (energy must be posed's); the barrier first
  /// guards the tets positive now. Stops at the step or energy tolerance or when no step descends.
  void newton(int maxIterations);
  /// Up to 3 rounds: tets still inverted get their free nodes moved out of the fold, then Newton on
  /// the moved nodes' neighbourhoods and, after the last round, on the whole mesh.
  void untangleRounds();
  /// Folds each region's pressure into its multiplier and resumes Newton, until the regions are
  /// within CorotationalOptions::regionVolumeTolerance (or the updates stop paying).
  void keepRegionVolumes();
  /// The volume regions from ids (#T or empty), multipliers at 0, the solver given their coupling.
  void useRegions(const std::vector<int>& ids);
  /// The system matrix's solve (float blocks or the double matrix), x in: the guess.
  void solve(const Eigen::VectorXd& b, Eigen::VectorXd& x, double tolerance, int& iterations, double& residual);
  /// The checkpoint, told the continuation's progress while onPath.
  void checkCancelled(RelaxationProgress::Phase phase);
  /// The report's energyAfter and region volume ratios, of posed.
  void finishReport();

  const Points& rest;
  const Tets& tets;
  const std::vector<int>& fixedBone;
  const std::vector<int>& freeNodes;  ///< the unknowns' nodes (system.freeNodes)
  const CorotationalOptions& options;
  CorotationalReport& rep;
  Points& posed;  ///< the iterate
  FixedCorotatedEnergy terms;
  double energy = 0.0;       ///< of posed
  int inverted = 0;          ///< posed's inverted tets
  double firstNorm = -1.0;   ///< the gradient's norm at the first Newton step (< 0: the next one sets it)
  /// Set when the continuation's path regions give way to volumeRegions at its end: the new terms
  /// start far from their targets (tiny phantom, tissues: 6e-3) while their energy is a tiny part of
  /// the total, so from there on a small energy decrease ends Newton only with a small step too.
  bool regionsSwitched = false;
  bool onPath = false;       ///< the continuation is running (for the checkpoint)
  double pathS = 0.0;        ///< ... and how far along its path
  Points trial;              ///< the line search's (and the continuation's) trial pose, #V by 3

 private:
  bool newtonStep();
  bool lineSearch(double maxMove, double slope, double& alpha, bool& smallDecrease);
  double firstTrialFraction() const;

  SpdSolver& solver_;
  NewtonMatrix& matrix_;         // the system's, assembled by terms
  double stepLimit_;             // stepTolerance times the mean rest edge length (mm)
  Eigen::VectorXd step_;         // 3 #free: the Newton step
  std::vector<int> freeIndex_;   // #V: node -> its place among the unknowns, -1 for none
};

}  // namespace fem
}  // namespace repose
