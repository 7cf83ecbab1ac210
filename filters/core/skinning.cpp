#include "skinning.h"

#include <atomic>
#include <cmath>
#include <stdexcept>
#include <string>

#include "dual_quaternion.h"
#include "parallel_for.h"

namespace repose {
namespace {

// Per-bone data precomputed once per call; plain arrays so the node loop does no allocation.
struct BoneDQ {
  double r[4];  // w, x, y, z
  double d[4];
};
struct BoneMatrix {
  double m[12];  // row-major 3x4
};

inline void applyMatrix(const double* m, const double* p, double* out) {
  out[0] = m[0] * p[0] + m[1] * p[1] + m[2] * p[2] + m[3];
  out[1] = m[4] * p[0] + m[5] * p[1] + m[6] * p[2] + m[7];
  out[2] = m[8] * p[0] + m[9] * p[1] + m[10] * p[2] + m[11];
}

struct SkinContext {
  int k, nb;
  const double* rest;
  double* posed;
  const float* w;
  const std::uint16_t* bone;
  const int* fixed;  // null when no node is fixed
  const BoneDQ* dqs;
  const BoneMatrix* mats;
  bool dualQuaternion;
  std::atomic<long long>* badNode;
};

// The node loop; K > 0 fixes k at compile time (fully unrolled slot loops), K = 0 reads c.k.
template <int K>
void skinRange(const SkinContext& c, std::size_t begin, std::size_t end) {
  const int k = K > 0 ? K : c.k;
  const int nb = c.nb;
  const double* restData = c.rest;
  double* posedData = c.posed;
  const float* wData = c.w;
  const std::uint16_t* bData = c.bone;
  const int* fixedData = c.fixed;
  const BoneDQ* dqs = c.dqs;
  const BoneMatrix* mats = c.mats;
  const bool dqs_method = c.dualQuaternion;
  std::atomic<long long>& badNode = *c.badNode;
  for (std::size_t i = begin; i < end; ++i) {
    const double* p = restData + 3 * i;
    double* out = posedData + 3 * i;
    const float* w = wData + i * std::size_t(k);
    const std::uint16_t* bo = bData + i * std::size_t(k);
    if (fixedData && fixedData[i] >= 0) {
      if (fixedData[i] >= nb) {
        badNode.store(static_cast<long long>(i));
        continue;
      }
      applyMatrix(mats[fixedData[i]].m, p, out);
      continue;
    }
    bool bad = false;
    for (int s = 0; s < k; ++s) bad |= int(bo[s]) >= nb;
    if (bad) {
      badNode.store(static_cast<long long>(i));
      continue;
    }
    if (dqs_method) {
      // Antipodality: align every bone's quaternion with the largest-weight bone's.
      int pivot = 0;
      for (int s = 1; s < k; ++s)
        if (w[s] > w[pivot]) pivot = s;
      const double* pr = dqs[bo[pivot]].r;
      double r0 = 0, r1 = 0, r2 = 0, r3 = 0, d0 = 0, d1 = 0, d2 = 0, d3 = 0;
      for (int s = 0; s < k; ++s) {
        const BoneDQ& q = dqs[bo[s]];
        // Branchless sign flip: the signs are unpredictable across nodes.
        const double ws = std::copysign(
            double(w[s]), q.r[0] * pr[0] + q.r[1] * pr[1] + q.r[2] * pr[2] + q.r[3] * pr[3]);
        r0 += ws * q.r[0]; r1 += ws * q.r[1]; r2 += ws * q.r[2]; r3 += ws * q.r[3];
        d0 += ws * q.d[0]; d1 += ws * q.d[1]; d2 += ws * q.d[2]; d3 += ws * q.d[3];
      }
      const double n2 = r0 * r0 + r1 * r1 + r2 * r2 + r3 * r3;
      if (!(n2 > 0)) {  // all weights zero: leave the node at rest
        out[0] = p[0]; out[1] = p[1]; out[2] = p[2];
        continue;
      }
      // Normalising by |r| enters both terms below squared, so 2/|r|^2 suffices (no sqrt).
      const double s2 = 2.0 / n2;
      // t = 2 (w0 ve - we v0 + v0 x ve) / |r|^2
      const double tx = s2 * (r0 * d1 - d0 * r1 + r2 * d3 - r3 * d2);
      const double ty = s2 * (r0 * d2 - d0 * r2 + r3 * d1 - r1 * d3);
      const double tz = s2 * (r0 * d3 - d0 * r3 + r1 * d2 - r2 * d1);
      // p' = p + 2 v x (v x p + w p) / |r|^2 + t
      const double cx = r2 * p[2] - r3 * p[1] + r0 * p[0];
      const double cy = r3 * p[0] - r1 * p[2] + r0 * p[1];
      const double cz = r1 * p[1] - r2 * p[0] + r0 * p[2];
      out[0] = p[0] + s2 * (r2 * cz - r3 * cy) + tx;
      out[1] = p[1] + s2 * (r3 * cx - r1 * cz) + ty;
      out[2] = p[2] + s2 * (r1 * cy - r2 * cx) + tz;
    } else {
      double m[12] = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
      double wsum = 0;
      for (int s = 0; s < k; ++s) {
        const double ws = w[s];
        if (ws == 0) continue;
        wsum += ws;
        const double* mb = mats[bo[s]].m;
        for (int c = 0; c < 12; ++c) m[c] += ws * mb[c];
      }
      if (!(wsum > 0)) {
        out[0] = p[0]; out[1] = p[1]; out[2] = p[2];
        continue;
      }
      applyMatrix(m, p, out);
    }
  }
}

}  // namespace

void skinNodes(const Points& rest, const SparseWeights& weights, const std::vector<int>& fixedBone,
               const std::vector<Eigen::Isometry3d>& boneTransforms, SkinningMethod method,
               Points& posed) {
  const std::size_t nv = std::size_t(rest.rows());
  const int k = weights.k;
  if (k < 1) throw std::invalid_argument("skinNodes: weights.k must be >= 1");
  if (weights.weight.size() != nv * std::size_t(k) || weights.bone.size() != nv * std::size_t(k))
    throw std::invalid_argument("skinNodes: weights are for " + std::to_string(weights.nodeCount()) +
                                " nodes, the mesh has " + std::to_string(nv));
  if (!fixedBone.empty() && fixedBone.size() != nv)
    throw std::invalid_argument("skinNodes: fixedBone has " + std::to_string(fixedBone.size()) +
                                " entries for " + std::to_string(nv) + " nodes");
  const int nb = int(boneTransforms.size());
  if (nv > 0 && nb == 0) throw std::invalid_argument("skinNodes: no bone transforms");

  std::vector<BoneDQ> dqs(nb);
  std::vector<BoneMatrix> mats(nb);
  for (int b = 0; b < nb; ++b) {
    const DualQuaternion dq = DualQuaternion::fromIsometry(boneTransforms[b]);
    dqs[b] = {{dq.real.w(), dq.real.x(), dq.real.y(), dq.real.z()},
              {dq.dual.w(), dq.dual.x(), dq.dual.y(), dq.dual.z()}};
    const Eigen::Matrix<double, 3, 4> M = boneTransforms[b].matrix().topRows<3>();
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) mats[b].m[r * 4 + c] = M(r, c);
  }

  posed.resize(rest.rows(), 3);
  std::atomic<long long> badNode{-1};
  SkinContext ctx;
  ctx.k = k;
  ctx.nb = nb;
  ctx.rest = rest.data();
  ctx.posed = posed.data();
  ctx.w = weights.weight.data();
  ctx.bone = weights.bone.data();
  ctx.fixed = fixedBone.empty() ? nullptr : fixedBone.data();
  ctx.dqs = dqs.data();
  ctx.mats = mats.data();
  ctx.dualQuaternion = method == SkinningMethod::DualQuaternion;
  ctx.badNode = &badNode;
  parallelFor(nv, [&ctx](std::size_t begin, std::size_t end) {
    switch (ctx.k) {
      case 4: skinRange<4>(ctx, begin, end); break;
      case 2: skinRange<2>(ctx, begin, end); break;
      case 3: skinRange<3>(ctx, begin, end); break;
      default: skinRange<0>(ctx, begin, end); break;
    }
  }, 8192);
  if (badNode.load() >= 0)
    throw std::invalid_argument("skinNodes: node " + std::to_string(badNode.load()) +
                                " uses a bone index >= the " + std::to_string(nb) +
                                " bone transforms given");
}

}  // namespace repose
