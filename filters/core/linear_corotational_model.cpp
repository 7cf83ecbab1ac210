#include "linear_corotational_model.h"

#include <chrono>

#include "fem_checkpoint.h"
#include "parallel_for.h"
#include "tet_untangling.h"

namespace repose {
namespace fem {

namespace {

// Element rotations from the current pose.
void elementRotations(const Points& posed, const Tets& tets, const std::vector<RestTet>& restTets,
                      std::vector<Mat3>& rotation) {
  parallelFor(std::size_t(tets.rows()), [&](std::size_t b, std::size_t e) {
    for (std::size_t t = b; t < e; ++t) {
      const auto T = tets.row(Eigen::Index(t));
      Mat3 Ds;
      const Vec3 x0 = node(posed, T[0]);
      for (int k = 0; k < 3; ++k) Ds.col(k) = node(posed, T[k + 1]) - x0;
      rotation[t] = robustRotation(Ds * restTets[t].DmInv);
    }
  });
}

// The rotated stiffness K' (into the system's matrix), its right-hand side rhs, the residual of the
// start residual0 and the start x, per free node.
struct LinearSystem {
  const Tets& tets;
  const std::vector<int>& fixedBone;
  const std::vector<RestTet>& restTets;
  FreeNodeSystem& system;
  const std::vector<Mat3>& rotation;
  double lambda, mu;
  Eigen::VectorXd rhs, residual0, x;

  // Row-wise assembly (no write conflicts): for free node i = local a of tet t, the blocks
  // K'_ab = R K_ab R^T = V (lambda h_a h_b^T + mu h_b h_a^T + mu (g_a.g_b) I) with h = R g (K_ab =
  // V (lambda g_a g_b^T + mu g_b g_a^T + mu (g_a.g_b) I)), and the force of the rotated rest shape
  // R sum_b K_ab X_b = V (3 lambda + 2 mu) h_a (sum_b X_b g_b^T = I), so that
  // rhs_i = sum_t V (3 lambda + 2 mu) h_a  -  sum_{b fixed} K'_ab x_b. The residual of the start,
  // rhs_i - sum_{b free} K'_ab x_b, is summed here in double from every block of the row (an upper
  // matrix stores only some): the float block CG then solves for the correction alone.
  void assemble(const Points& posed) {
    parallelFor(system.freeNodes.size(), [&](std::size_t b, std::size_t e) {
      std::vector<double> row;  // the row's stored blocks, summed in double
      for (std::size_t i = b; i < e; ++i) assembleRow(i, posed, row);
    }, 256);
  }

  void assembleRow(std::size_t i, const Points& posed, std::vector<double>& row) {
    row.assign(9 * std::size_t(system.A.rowLength(i)), 0.0);
    Vec3 r = Vec3::Zero(), free = Vec3::Zero();
    for (int k = system.incStart[i]; k < system.incStart[i + 1]; ++k) {
      const int t = system.incTet[std::size_t(k)] / 4, a = system.incTet[std::size_t(k)] % 4;
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
        const std::uint16_t slot = system.incColumn[4 * std::size_t(k) + std::size_t(bb)];
        if (slot == kNotStored) continue;  // below the diagonal of an upper matrix
        double* dst = row.data() + 9 * std::size_t(slot);
        for (int c = 0; c < 3; ++c)
          for (int d = 0; d < 3; ++d) dst[3 * c + d] += block(c, d);
      }
    }
    system.A.setRow(i, row.data());
    rhs.segment<3>(Eigen::Index(3 * i)) = r;
    residual0.segment<3>(Eigen::Index(3 * i)) = r - free;
    x.segment<3>(Eigen::Index(3 * i)) = node(posed, system.freeNodes[i]);
  }
};

}  // namespace

void relaxLinearCorotational(const Points& rest, const Tets& tets, const std::vector<int>& fixedBone,
                             const std::vector<RestTet>& restTets, FreeNodeSystem& system, SpdSolver& solver,
                             const CorotationalOptions& options, double lambda, double mu, Points& posed,
                             CorotationalReport& rep) {
  const std::vector<int>& freeNodes = system.freeNodes;
  const Eigen::Index n = Eigen::Index(3 * freeNodes.size());
  std::vector<Mat3> rotation(static_cast<std::size_t>(tets.rows()));
  LinearSystem linear{tets, fixedBone, restTets, system, rotation, lambda, mu,
                      Eigen::VectorXd(n), Eigen::VectorXd(n), Eigen::VectorXd(n)};
  for (int outer = 0; outer < options.outerIterations; ++outer) {
    RelaxationProgress linearProgress;
    linearProgress.phase = RelaxationProgress::Linear;
    linearProgress.outerIteration = outer;
    reachCheckpoint(options, linearProgress);
    const auto assemblyStart = std::chrono::steady_clock::now();
    elementRotations(posed, tets, restTets, rotation);
    linear.assemble(posed);
    rep.assemblySeconds += seconds(assemblyStart);
    const auto solveStart = std::chrono::steady_clock::now();
    int iterations = 0;
    double residual = 0.0;
    if (system.A.blocked)
      solver.solveCorrection(system.A.blocks, linear.rhs, linear.residual0, linear.x, options.tolerance, iterations,
                             residual);
    else
      solver.solve(system.A.scalar, linear.rhs, linear.x, options.tolerance, iterations, residual);
    rep.solveSeconds += seconds(solveStart);
    for (std::size_t i = 0; i < freeNodes.size(); ++i)
      posed.row(freeNodes[i]) = linear.x.segment<3>(Eigen::Index(3 * i)).transpose();
    rep.cgIterations.push_back(iterations);
    rep.relativeResidual.push_back(residual);
    rep.outerIterations = outer + 1;
  }
  if (options.untangle && countInverted(posed, tets) > 0) {
    const auto untangleStart = std::chrono::steady_clock::now();
    rep.untangledNodes = untangleTets(rest, tets, fixedBone, posed).nodesMoved;
    rep.untangleSeconds = seconds(untangleStart);
  }
}

}  // namespace fem
}  // namespace repose
