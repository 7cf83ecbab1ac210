#pragma once
// Static corotational linear-elastic relaxation of a posed tet mesh (Mueller & Gross 2004):
// refines a skinned pose so that nearly incompressible tissue keeps its volume.
#include <vector>

#include "tet_mesh.h"

namespace repose {

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
  enum Preconditioner { Jacobi, IncompleteCholesky };
  Preconditioner preconditioner = Jacobi;
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
/// Throws std::runtime_error if the incomplete Cholesky factorization fails.
void relaxCorotational(const Points& rest, const Tets& tets, const std::vector<int>& fixedBone,
                       Points& posed, const CorotationalOptions& options,
                       CorotationalReport* report = nullptr);

}  // namespace repose
