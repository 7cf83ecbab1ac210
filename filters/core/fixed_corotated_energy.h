#pragma once
// The fixed-corotated energy over a mesh's free nodes (internal to corotational_fem): its value at a
// pose, and the gradient and projected Hessian that Newton's steps solve with.
//   psi(F) = mu |F - R|^2 + h(det F)   per tet (Stomakhin et al. 2012; h: volume_term.h),
// plus the volume regions' terms (fem_volume_regions.h). Energies are per unit Young's modulus
// times mm^3; the Hessian is projected per tet (negative eigenvalues clamped, Smith et al. 2019).
#include <Eigen/Core>
#include <vector>

#include "corotational_fem.h"
#include "fem_newton_matrix.h"
#include "fem_tet_geometry.h"
#include "fem_volume_regions.h"
#include "volume_term.h"

namespace repose {
namespace fem {

/// Per-tet state of the energy at a pose: Irving's signed SVD F = U diag(sigma) V^T (det U =
/// det V = +1, an inverted tet has sigma(2) < 0). Stress, cofactor and Hessian follow from it.
struct TetState {
  Mat3 U, V;
  Vec3 sigma;
};

class FixedCorotatedEnergy {
 public:
  /// tets, fixedBone, restTets as relaxCorotational's; system: the free nodes, their incidences and
  /// the matrix that assemble() fills. lambda, mu: Lame's parameters. All must outlive this.
  FixedCorotatedEnergy(const Tets& tets, const std::vector<int>& fixedBone, const std::vector<RestTet>& restTets,
                       FreeNodeSystem& system, const CorotationalOptions& options, double lambda, double mu);

  /// The volume regions from ids (#T or empty), multipliers at 0.
  void useRegions(const std::vector<int>& ids);
  /// Energy and inverted-tet count of a pose x (#V by 3); always refreshes the per-tet state and the
  /// regions' volumes and pressures (a rejected trial's state is overwritten by the next trial, an
  /// accepted one's is the state of the new iterate).
  double evaluate(const Points& x, int& inverted);
  /// Gradient (grad) and projected Hessian (the system's matrix) at the last evaluated pose, row-wise
  /// over the free nodes. With a move of the Dirichlet nodes (#V by 3, read at Dirichlet nodes
  /// only), also dirichletForce = H_fd move: the first-order change of the free nodes' gradient when
  /// the Dirichlet nodes take that move.
  void assemble(const Points* dirichletMove);

  /// Whether tets get the log barrier (CorotationalOptions::inversionBarrier, with a penalty).
  bool guarded() const { return options_.inversionBarrier && volumeTerm.kappa > 0; }
  /// The barrier flags of pose x, on the signs of its tet volumes: set before the first evaluation,
  /// barrierFromState() then finds them unchanged.
  void setBarrier(const Points& x);
  /// The barrier on the tets with a free node that are positive at the last evaluated pose; returns
  /// whether a flag changed (the energy then needs evaluating again).
  bool barrierFromState();

  const VolumeTerm volumeTerm;
  std::vector<char> hasFree;     ///< #T: some node of the tet is free
  std::vector<char> barrier;     ///< #T: the log barrier (1) or the penalty (0) below det F = eps
  std::vector<TetState> state;   ///< #T, at the last evaluated pose
  VolumeRegions regions;
  Eigen::VectorXd grad;          ///< 3 #free
  Eigen::VectorXd dirichletForce;///< 3 #free, by assemble() with a Dirichlet move

 private:
  /// A tet's projected Hessian in the frame of its U and V (see prepareHessians).
  struct TetHessian {
    float c[3], d[3];
    float S[3][3];
  };
  void prepareHessians();
  static Mat3 blockInFrame(const TetHessian& h, const Vec3& wa, const Vec3& wb);
  void assembleRow(std::size_t i, const Points* dirichletMove, std::vector<double>& row);

  const Tets& tets_;
  const std::vector<int>& fixedBone_;
  const std::vector<RestTet>& restTets_;
  FreeNodeSystem& system_;
  const CorotationalOptions& options_;
  const double lambda_, mu_;
  std::size_t nSumBlocks_;
  std::vector<double> blockSums_;  // evaluate()'s per-block sums: energy, then each region's volume
  std::vector<int> blockCounts_;   // ... and inverted tets
  std::vector<TetHessian> hessian_;
};

}  // namespace fem
}  // namespace repose
