#include "fixed_corotated_energy.h"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>

#include "parallel_for.h"
#include "signed_svd.h"

namespace repose {
namespace fem {

namespace {

// The sums of evaluate() are taken per fixed block of this many tets and then in block order, so that
// they do not depend on how the threads split the work: a solve gives the same result every run (the
// line search's accept / reject decisions, and through them the continuation's path, hang on the
// last digits).
constexpr std::size_t kSumBlock = 512;

// The twist / flip pairs (i, j) of singular values, and the third index l of each.
const int pairI[3] = {0, 1, 0}, pairJ[3] = {1, 2, 2}, pairL[3] = {2, 0, 1};

}  // namespace

FixedCorotatedEnergy::FixedCorotatedEnergy(const Tets& tets, const std::vector<int>& fixedBone,
                                           const std::vector<RestTet>& restTets, FreeNodeSystem& system,
                                           const CorotationalOptions& options, double lambda, double mu)
    : volumeTerm{lambda, options.inversionPenalty * lambda, options.inversionThreshold},
      hasFree(std::size_t(tets.rows()), 0),
      barrier(std::size_t(tets.rows()), 0),
      state(std::size_t(tets.rows())),
      grad(Eigen::Index(3 * system.freeNodes.size())),
      tets_(tets),
      fixedBone_(fixedBone),
      restTets_(restTets),
      system_(system),
      options_(options),
      lambda_(lambda),
      mu_(mu),
      nSumBlocks_((std::size_t(tets.rows()) + kSumBlock - 1) / kSumBlock),
      blockCounts_(nSumBlocks_),
      hessian_(std::size_t(tets.rows())) {
  for (std::size_t t = 0; t < hasFree.size(); ++t) hasFree[t] = hasFreeNode(tets, fixedBone, t);
  useRegions(options.volumeRegions);
}

void FixedCorotatedEnergy::useRegions(const std::vector<int>& ids) {
  regions.setUp(ids, hasFree, restTets_, system_.incStart, system_.incTet, options_.regionVolumeStiffness * lambda_);
  blockSums_.assign(nSumBlocks_ * std::size_t(1 + regions.count), 0.0);
}

double FixedCorotatedEnergy::evaluate(const Points& x, int& inverted) {
  const std::size_t nT = state.size();
  const int nRegions = regions.count;
  parallelFor(nSumBlocks_, [&](std::size_t bb, std::size_t be) {
    for (std::size_t k = bb; k < be; ++k) {
      double* sums = blockSums_.data() + k * std::size_t(1 + nRegions);
      std::fill(sums, sums + 1 + nRegions, 0.0);
      int localCount = 0;
      for (std::size_t t = k * kSumBlock; t < std::min(nT, (k + 1) * kSumBlock); ++t) {
        const auto T = tets_.row(Eigen::Index(t));
        const RestTet& rt = restTets_[t];
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
        sums[0] += rt.volume * (mu_ * (sigma - Vec3::Ones()).squaredNorm() + volumeTerm(J, barrier[t] != 0, p, stiffness));
        state[t] = TetState{U, V, sigma};
        if (nRegions > 0 && regions.region[t] >= 0) sums[1 + regions.region[t]] += rt.volume * J;
      }
      blockCounts_[k] = localCount;
    }
  }, 1);
  double energy = 0;
  int count = 0;
  std::fill(regions.volume.begin(), regions.volume.end(), 0.0);
  for (std::size_t k = 0; k < nSumBlocks_; ++k) {
    const double* sums = blockSums_.data() + k * std::size_t(1 + nRegions);
    energy += sums[0];
    count += blockCounts_[k];
    for (int r = 0; r < nRegions; ++r) regions.volume[std::size_t(r)] += sums[1 + r];
  }
  regions.updatePressures(energy);
  inverted = count;
  return energy;
}

// The projected Hessian of psi in F, per tet (Smith et al. 2019): diagonal in the modes U M V^T.
// Twist / flip of each pair (i, j) (third index l) have eigenvalues mu (2 - 4 / (s_i + s_j)) + p s_l
// and 2 mu - p s_l; the scalings a 3x3 block 2 mu I + h'' cofS cofS^T + p d2J/ds2 (p = h'). Negative
// eigenvalues are clamped to 0. Kept per tet in the frame of U and V (pair: c = (twist + flip) / 2,
// d = (flip - twist) / 2; scalings: the clamped block), once per Newton iteration, so the row-wise
// assembly does not redo it for each of the tet's four nodes.
void FixedCorotatedEnergy::prepareHessians() {
  const double mu = mu_;
  parallelFor(state.size(), [&](std::size_t b, std::size_t e) {
    for (std::size_t t = b; t < e; ++t) {
      const Vec3& s = state[t].sigma;
      double pressure, stiffness;
      volumeTerm(s.prod(), barrier[std::size_t(t)] != 0, pressure, stiffness);
      if (regions.count > 0 && regions.region[t] >= 0) pressure += regions.pressure[std::size_t(regions.region[t])];
      const Vec3 cofS(s(1) * s(2), s(0) * s(2), s(0) * s(1));  // cof F = U diag(cofS) V^T
      TetHessian& h = hessian_[t];
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
}

void FixedCorotatedEnergy::assemble(const Points* dirichletMove) {
  if (dirichletMove) dirichletForce.setZero(grad.size());
  prepareHessians();
  parallelFor(system_.freeNodes.size(), [&](std::size_t b, std::size_t e) {
    std::vector<double> row;  // the row's blocks, summed in double
    for (std::size_t i = b; i < e; ++i) assembleRow(i, dirichletMove, row);
  }, 256);
}

// Block (a, b) of a tet's Hessian in the frame of U, from its nodes' gradients wa, wb in the frame
// of V: diag(wa) S diag(wb) plus the twist / flip pairs.
Mat3 FixedCorotatedEnergy::blockInFrame(const TetHessian& h, const Vec3& wa, const Vec3& wb) {
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
  return L;
}

void FixedCorotatedEnergy::assembleRow(std::size_t i, const Points* dirichletMove, std::vector<double>& row) {
  const double mu = mu_;
  const int nRegions = regions.count;
  LowRankTerm3& coupling = regions.coupling;
  NewtonMatrix& A = system_.A;
  row.assign(9 * std::size_t(A.rowLength(i)), 0.0);
  Vec3 gi = Vec3::Zero(), fi = Vec3::Zero();
  const int couplingBegin = nRegions > 0 ? coupling.rowStart[i] : 0;
  const int couplingEnd = nRegions > 0 ? coupling.rowStart[i + 1] : 0;
  for (int q = couplingBegin; q < couplingEnd; ++q)
    for (int c = 0; c < 3; ++c) coupling.vector[3 * std::size_t(q) + std::size_t(c)] = 0.0;
  for (int k = system_.incStart[i]; k < system_.incStart[i + 1]; ++k) {
    const int t = system_.incTet[std::size_t(k)] / 4, a = system_.incTet[std::size_t(k)] % 4;
    const RestTet& rt = restTets_[std::size_t(t)];
    const TetState& st = state[std::size_t(t)];
    const TetHessian& h = hessian_[std::size_t(t)];
    const Vec3& s = st.sigma;
    double pressure, stiffness;
    volumeTerm(s.prod(), barrier[std::size_t(t)] != 0, pressure, stiffness);
    const int r = nRegions > 0 ? regions.region[std::size_t(t)] : -1;
    if (r >= 0) pressure += regions.pressure[std::size_t(r)];
    const Vec3 cofS(s(1) * s(2), s(0) * s(2), s(0) * s(1));
    const Eigen::Matrix<double, 4, 3> g = gradients(rt);
    // Each node's gradient in the frame of V.
    const Eigen::Matrix<double, 3, 4> w = st.V.transpose() * g.transpose();
    const Vec3 wa = w.col(a);
    if (r >= 0) {  // this node's part of the gradient of the region's volume: V0 cof(F) g_a
      int q = couplingBegin;
      while (coupling.term[std::size_t(q)] != r) ++q;
      const Vec3 dv = rt.volume * (st.U * cofS.cwiseProduct(wa));
      for (int c = 0; c < 3; ++c) coupling.vector[3 * std::size_t(q) + std::size_t(c)] += dv(c);
    }
    // Force: P g_a with P = U diag(2 mu (s - 1) + p cofS) V^T, times the volume.
    gi += rt.volume * (st.U * (2.0 * mu * (s - Vec3::Ones()) + pressure * cofS).cwiseProduct(wa));
    for (int bb = 0; bb < 4; ++bb) {
      const int v = tets_(t, bb);
      const bool dirichlet = fixedBone_[std::size_t(v)] >= 0;
      if (dirichlet && !dirichletMove) continue;  // Dirichlet: no increment
      const std::uint16_t slot = system_.incColumn[4 * std::size_t(k) + std::size_t(bb)];
      if (!dirichlet && slot == kNotStored) continue;  // below the diagonal of an upper matrix
      const Mat3 block = rt.volume * (st.U * blockInFrame(h, wa, w.col(bb)) * st.U.transpose());
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

void FixedCorotatedEnergy::setBarrier(const Points& x) {
  if (!guarded()) return;
  parallelFor(barrier.size(), [&](std::size_t b, std::size_t e) {
    for (std::size_t t = b; t < e; ++t) {
      const auto T = tets_.row(Eigen::Index(t));
      barrier[t] = hasFree[t] && tetVolume(node(x, T[0]), node(x, T[1]), node(x, T[2]), node(x, T[3])) > 0.0;
    }
  }, 4096);
}

bool FixedCorotatedEnergy::barrierFromState() {
  // (Not on tets of Dirichlet nodes only: their energy is a constant of the solve, and a bone move
  // of the continuation may turn them.)
  bool changed = false;
  for (std::size_t t = 0; t < barrier.size(); ++t) {
    const char b = hasFree[t] && state[t].sigma.prod() > 0.0;
    changed = changed || b != barrier[t];
    barrier[t] = b;
  }
  return changed;
}

}  // namespace fem
}  // namespace repose
