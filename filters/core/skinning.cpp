#include "skinning.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <stdexcept>
#include <string>

#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
#include <immintrin.h>
#endif

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

// ---- Float fast path -------------------------------------------------------------------------

namespace {

#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
#define REPOSE_SKIN_X86 1
#define REPOSE_ALWAYS_INLINE __attribute__((always_inline)) inline
#else
#define REPOSE_ALWAYS_INLINE inline
#endif

// Nodes are processed in blocks: a gather pass blends the per-bone data of each node into small
// structure-of-arrays buffers, then a pure arithmetic pass (which the compiler vectorises across
// nodes) transforms the rest positions, then the results are interleaved into x y z output.
constexpr std::size_t kBlock = 64;

struct FastArgs {
  int k;
  const float* x;
  const float* y;
  const float* z;
  const float* weight;
  const std::uint16_t* bone;
  const float* table;     // DQS: nb x nb x 8 (row a = every bone's DQ aligned with bone a); LBS: nb x 16
                          // (columns of the 3x4 matrix, each padded to 4)
  std::size_t rowStride;  // DQS: nb * 8; LBS: 0
  float* out;
};

template <int K>
REPOSE_ALWAYS_INLINE void dqsRangeFloat(const FastArgs& a, std::size_t begin, std::size_t end) {
  const int k = K > 0 ? K : a.k;
  alignas(64) float q[8][kBlock];
  alignas(64) float o[3][kBlock];
  for (std::size_t b = begin; b < end; b += kBlock) {
    const std::size_t n = std::min(kBlock, end - b);
    for (std::size_t j = 0; j < n; ++j) {
      const std::size_t i = b + j;
      const float* w = a.weight + i * std::size_t(k);
      const std::uint16_t* bo = a.bone + i * std::size_t(k);
      // Slot 0 holds the largest weight, so the table row of bo[0] has every bone's quaternion
      // already sign-aligned with it: no per-node antipodality test.
      const float* row = a.table + std::size_t(bo[0]) * a.rowStride;
      float acc[8];
      const float* t0 = row + std::size_t(bo[0]) * 8;
      for (int e = 0; e < 8; ++e) acc[e] = w[0] * t0[e];
      for (int s = 1; s < k; ++s) {
        const float* t = row + std::size_t(bo[s]) * 8;
        const float ws = w[s];
        for (int e = 0; e < 8; ++e) acc[e] += ws * t[e];
      }
      for (int e = 0; e < 8; ++e) q[e][j] = acc[e];
    }
    const float* px = a.x + b;
    const float* py = a.y + b;
    const float* pz = a.z + b;
    for (std::size_t j = 0; j < n; ++j) {
      const float r0 = q[0][j], r1 = q[1][j], r2 = q[2][j], r3 = q[3][j];
      const float d0 = q[4][j], d1 = q[5][j], d2 = q[6][j], d3 = q[7][j];
      // Same formulas as the double path: normalising enters squared, so 2/|r|^2 suffices.
      const float s2 = 2.0f / (r0 * r0 + r1 * r1 + r2 * r2 + r3 * r3);
      const float tx = s2 * (r0 * d1 - d0 * r1 + r2 * d3 - r3 * d2);
      const float ty = s2 * (r0 * d2 - d0 * r2 + r3 * d1 - r1 * d3);
      const float tz = s2 * (r0 * d3 - d0 * r3 + r1 * d2 - r2 * d1);
      const float x = px[j], y = py[j], z = pz[j];
      const float cx = r2 * z - r3 * y + r0 * x;
      const float cy = r3 * x - r1 * z + r0 * y;
      const float cz = r1 * y - r2 * x + r0 * z;
      o[0][j] = x + s2 * (r2 * cz - r3 * cy) + tx;
      o[1][j] = y + s2 * (r3 * cx - r1 * cz) + ty;
      o[2][j] = z + s2 * (r1 * cy - r2 * cx) + tz;
    }
    float* out = a.out + 3 * b;
    for (std::size_t j = 0; j < n; ++j) {
      out[3 * j] = o[0][j];
      out[3 * j + 1] = o[1][j];
      out[3 * j + 2] = o[2][j];
    }
  }
}

template <int K>
REPOSE_ALWAYS_INLINE void lbsRangeFloat(const FastArgs& a, std::size_t begin, std::size_t end) {
  const int k = K > 0 ? K : a.k;
  alignas(64) float m[12][kBlock];
  alignas(64) float o[3][kBlock];
  for (std::size_t b = begin; b < end; b += kBlock) {
    const std::size_t n = std::min(kBlock, end - b);
    for (std::size_t j = 0; j < n; ++j) {
      const std::size_t i = b + j;
      const float* w = a.weight + i * std::size_t(k);
      const std::uint16_t* bo = a.bone + i * std::size_t(k);
      float acc[16];  // columns c0 c1 c2 t of the blended 3x4 matrix, 4 floats each
      const float* t0 = a.table + std::size_t(bo[0]) * 16;
      for (int e = 0; e < 16; ++e) acc[e] = w[0] * t0[e];
      for (int s = 1; s < k; ++s) {
        const float* t = a.table + std::size_t(bo[s]) * 16;
        const float ws = w[s];
        for (int e = 0; e < 16; ++e) acc[e] += ws * t[e];
      }
      for (int e = 0; e < 12; ++e) m[e][j] = acc[e + e / 3];
    }
    const float* px = a.x + b;
    const float* py = a.y + b;
    const float* pz = a.z + b;
    for (std::size_t j = 0; j < n; ++j) {
      const float x = px[j], y = py[j], z = pz[j];
      o[0][j] = m[0][j] * x + m[3][j] * y + m[6][j] * z + m[9][j];
      o[1][j] = m[1][j] * x + m[4][j] * y + m[7][j] * z + m[10][j];
      o[2][j] = m[2][j] * x + m[5][j] * y + m[8][j] * z + m[11][j];
    }
    float* out = a.out + 3 * b;
    for (std::size_t j = 0; j < n; ++j) {
      out[3 * j] = o[0][j];
      out[3 * j + 1] = o[1][j];
      out[3 * j + 2] = o[2][j];
    }
  }
}

REPOSE_ALWAYS_INLINE void runFast(bool dq, const FastArgs& a, std::size_t begin, std::size_t end) {
  if (dq) {
    switch (a.k) {
      case 4: dqsRangeFloat<4>(a, begin, end); break;
      case 3: dqsRangeFloat<3>(a, begin, end); break;
      case 2: dqsRangeFloat<2>(a, begin, end); break;
      default: dqsRangeFloat<0>(a, begin, end); break;
    }
  } else {
    switch (a.k) {
      case 4: lbsRangeFloat<4>(a, begin, end); break;
      case 3: lbsRangeFloat<3>(a, begin, end); break;
      case 2: lbsRangeFloat<2>(a, begin, end); break;
      default: lbsRangeFloat<0>(a, begin, end); break;
    }
  }
}

void runFastDefault(bool dq, const FastArgs& a, std::size_t begin, std::size_t end) {
  runFast(dq, a, begin, end);
}

#ifdef REPOSE_SKIN_X86
// Hand-vectorised AVX2 kernels (the compiler does not vectorise the per-node gathers well).
// DQS: blend 8 nodes' dual quaternions (one 8-float register each), transpose to one register per
// component, do the transform for 8 nodes at once, write x y z.
__attribute__((target("avx2,fma"))) inline void transpose8(__m256* r) {
  const __m256 t0 = _mm256_unpacklo_ps(r[0], r[1]), t1 = _mm256_unpackhi_ps(r[0], r[1]);
  const __m256 t2 = _mm256_unpacklo_ps(r[2], r[3]), t3 = _mm256_unpackhi_ps(r[2], r[3]);
  const __m256 t4 = _mm256_unpacklo_ps(r[4], r[5]), t5 = _mm256_unpackhi_ps(r[4], r[5]);
  const __m256 t6 = _mm256_unpacklo_ps(r[6], r[7]), t7 = _mm256_unpackhi_ps(r[6], r[7]);
  const __m256 u0 = _mm256_shuffle_ps(t0, t2, _MM_SHUFFLE(1, 0, 1, 0));
  const __m256 u1 = _mm256_shuffle_ps(t0, t2, _MM_SHUFFLE(3, 2, 3, 2));
  const __m256 u2 = _mm256_shuffle_ps(t1, t3, _MM_SHUFFLE(1, 0, 1, 0));
  const __m256 u3 = _mm256_shuffle_ps(t1, t3, _MM_SHUFFLE(3, 2, 3, 2));
  const __m256 u4 = _mm256_shuffle_ps(t4, t6, _MM_SHUFFLE(1, 0, 1, 0));
  const __m256 u5 = _mm256_shuffle_ps(t4, t6, _MM_SHUFFLE(3, 2, 3, 2));
  const __m256 u6 = _mm256_shuffle_ps(t5, t7, _MM_SHUFFLE(1, 0, 1, 0));
  const __m256 u7 = _mm256_shuffle_ps(t5, t7, _MM_SHUFFLE(3, 2, 3, 2));
  r[0] = _mm256_permute2f128_ps(u0, u4, 0x20);
  r[1] = _mm256_permute2f128_ps(u1, u5, 0x20);
  r[2] = _mm256_permute2f128_ps(u2, u6, 0x20);
  r[3] = _mm256_permute2f128_ps(u3, u7, 0x20);
  r[4] = _mm256_permute2f128_ps(u0, u4, 0x31);
  r[5] = _mm256_permute2f128_ps(u1, u5, 0x31);
  r[6] = _mm256_permute2f128_ps(u2, u6, 0x31);
  r[7] = _mm256_permute2f128_ps(u3, u7, 0x31);
}

// Writes 8 nodes' x y z (one register per coordinate) as 24 interleaved floats.
__attribute__((target("avx2,fma"))) inline void storeXyz8(__m256 x, __m256 y, __m256 z, float* out) {
  const __m128 zero = _mm_setzero_ps();
  for (int h = 0; h < 2; ++h) {
    __m128 a = h ? _mm256_extractf128_ps(x, 1) : _mm256_castps256_ps128(x);
    __m128 b = h ? _mm256_extractf128_ps(y, 1) : _mm256_castps256_ps128(y);
    __m128 c = h ? _mm256_extractf128_ps(z, 1) : _mm256_castps256_ps128(z);
    __m128 d = zero;
    _MM_TRANSPOSE4_PS(a, b, c, d);  // a..d = (x, y, z, 0) of 4 nodes
    float* o = out + 12 * h;
    _mm_storeu_ps(o, a);  // each 4-float store's last lane is rewritten by the next node
    _mm_storeu_ps(o + 3, b);
    _mm_storeu_ps(o + 6, c);
    if (h == 0) {
      _mm_storeu_ps(o + 9, d);
    } else {  // last node: exactly 3 floats (the next ones may belong to another thread)
      _mm_storel_pi(reinterpret_cast<__m64*>(o + 9), d);
      _mm_store_ss(o + 11, _mm_movehl_ps(d, d));
    }
  }
}

template <int K>
__attribute__((target("avx2,fma"))) inline void dqsRangeAvx2(const FastArgs& a, std::size_t begin,
                                                             std::size_t end) {
  const int k = K > 0 ? K : a.k;
  const __m256 two = _mm256_set1_ps(2.0f);
  std::size_t i0 = begin;
  for (; i0 + 8 <= end; i0 += 8) {
    __m256 q[8];
    for (int j = 0; j < 8; ++j) {
      const std::size_t i = i0 + j;
      const float* w = a.weight + i * std::size_t(k);
      const std::uint16_t* bo = a.bone + i * std::size_t(k);
      const float* row = a.table + std::size_t(bo[0]) * a.rowStride;
      __m256 acc = _mm256_mul_ps(_mm256_set1_ps(w[0]), _mm256_loadu_ps(row + std::size_t(bo[0]) * 8));
      for (int s = 1; s < k; ++s)
        acc = _mm256_fmadd_ps(_mm256_set1_ps(w[s]), _mm256_loadu_ps(row + std::size_t(bo[s]) * 8), acc);
      q[j] = acc;
    }
    transpose8(q);
    const __m256 r0 = q[0], r1 = q[1], r2 = q[2], r3 = q[3], d0 = q[4], d1 = q[5], d2 = q[6], d3 = q[7];
    const __m256 s2 = two / (r0 * r0 + r1 * r1 + r2 * r2 + r3 * r3);
    const __m256 tx = s2 * (r0 * d1 - d0 * r1 + r2 * d3 - r3 * d2);
    const __m256 ty = s2 * (r0 * d2 - d0 * r2 + r3 * d1 - r1 * d3);
    const __m256 tz = s2 * (r0 * d3 - d0 * r3 + r1 * d2 - r2 * d1);
    const __m256 x = _mm256_loadu_ps(a.x + i0), y = _mm256_loadu_ps(a.y + i0), z = _mm256_loadu_ps(a.z + i0);
    const __m256 cx = r2 * z - r3 * y + r0 * x;
    const __m256 cy = r3 * x - r1 * z + r0 * y;
    const __m256 cz = r1 * y - r2 * x + r0 * z;
    storeXyz8(x + s2 * (r2 * cz - r3 * cy) + tx, y + s2 * (r3 * cx - r1 * cz) + ty,
              z + s2 * (r1 * cy - r2 * cx) + tz, a.out + 3 * i0);
  }
  if (i0 < end) dqsRangeFloat<K>(a, i0, end);
}

// LBS: per node, blend the two 8-float halves [c0|c1], [c2|t] of the bone matrices, then
// x*c0 + y*c1 + z*c2 + t as one 8-wide multiply-add and a fold of the halves.
template <int K>
__attribute__((target("avx2,fma"))) inline void lbsRangeAvx2(const FastArgs& a, std::size_t begin,
                                                             std::size_t end) {
  const int k = K > 0 ? K : a.k;
  const __m128 one = _mm_set1_ps(1.0f);
  // All but the range's last node store 4 floats (the 4th is rewritten by the next node).
  const std::size_t last = end > begin ? end - 1 : begin;
  for (std::size_t i = begin; i < last; ++i) {
    const float* w = a.weight + i * std::size_t(k);
    const std::uint16_t* bo = a.bone + i * std::size_t(k);
    const float* t = a.table + std::size_t(bo[0]) * 16;
    __m256 ws = _mm256_set1_ps(w[0]);
    __m256 A = _mm256_mul_ps(ws, _mm256_loadu_ps(t)), B = _mm256_mul_ps(ws, _mm256_loadu_ps(t + 8));
    for (int s = 1; s < k; ++s) {
      t = a.table + std::size_t(bo[s]) * 16;
      ws = _mm256_set1_ps(w[s]);
      A = _mm256_fmadd_ps(ws, _mm256_loadu_ps(t), A);
      B = _mm256_fmadd_ps(ws, _mm256_loadu_ps(t + 8), B);
    }
    const __m256 xy = _mm256_set_m128(_mm_broadcast_ss(a.y + i), _mm_broadcast_ss(a.x + i));
    const __m256 z1 = _mm256_set_m128(one, _mm_broadcast_ss(a.z + i));
    const __m256 v = _mm256_fmadd_ps(A, xy, _mm256_mul_ps(B, z1));
    _mm_storeu_ps(a.out + 3 * i, _mm_add_ps(_mm256_castps256_ps128(v), _mm256_extractf128_ps(v, 1)));
  }
  if (last < end) lbsRangeFloat<K>(a, last, end);
}

__attribute__((target("avx2,fma"))) void runFastAvx2(bool dq, const FastArgs& a, std::size_t begin,
                                                     std::size_t end) {
  if (dq) {
    switch (a.k) {
      case 4: dqsRangeAvx2<4>(a, begin, end); break;
      case 3: dqsRangeAvx2<3>(a, begin, end); break;
      case 2: dqsRangeAvx2<2>(a, begin, end); break;
      default: dqsRangeAvx2<0>(a, begin, end); break;
    }
  } else {
    switch (a.k) {
      case 4: lbsRangeAvx2<4>(a, begin, end); break;
      case 3: lbsRangeAvx2<3>(a, begin, end); break;
      case 2: lbsRangeAvx2<2>(a, begin, end); break;
      default: lbsRangeAvx2<0>(a, begin, end); break;
    }
  }
}

// REPOSE_NO_SIMD=1 forces the portable kernels (lets tests cover them on AVX2 machines).
bool useAvx2() {
  static const bool has = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  const char* off = std::getenv("REPOSE_NO_SIMD");
  return has && !(off && *off && *off != '0');
}
#endif

}  // namespace

SkinningCache makeSkinningCache(const Points& rest, const SparseWeights& weights,
                                const std::vector<int>& fixedBone) {
  const std::size_t nv = std::size_t(rest.rows());
  const int k = weights.k;
  if (k < 1) throw std::invalid_argument("skinning cache: weights.k must be >= 1");
  if (weights.weight.size() != nv * std::size_t(k) || weights.bone.size() != nv * std::size_t(k))
    throw std::invalid_argument("skinning cache: weights are for " + std::to_string(weights.nodeCount()) +
                                " nodes, the mesh has " + std::to_string(nv));
  if (!fixedBone.empty() && fixedBone.size() != nv)
    throw std::invalid_argument("skinning cache: fixedBone has " + std::to_string(fixedBone.size()) +
                                " entries for " + std::to_string(nv) + " nodes");
  SkinningCache c;
  c.k = k;
  c.x.resize(nv);
  c.y.resize(nv);
  c.z.resize(nv);
  c.weight.resize(nv * std::size_t(k));
  c.bone.resize(nv * std::size_t(k));
  for (std::size_t i = 0; i < nv; ++i) {
    c.x[i] = float(rest(Eigen::Index(i), 0));
    c.y[i] = float(rest(Eigen::Index(i), 1));
    c.z[i] = float(rest(Eigen::Index(i), 2));
    float* w = c.weight.data() + i * std::size_t(k);
    std::uint16_t* bo = c.bone.data() + i * std::size_t(k);
    if (!fixedBone.empty() && fixedBone[i] >= 0) {
      if (fixedBone[i] > 65535)
        throw std::invalid_argument("skinning cache: node " + std::to_string(i) + " is fixed to bone " +
                                    std::to_string(fixedBone[i]) + ", not a bone index");
      for (int s = 0; s < k; ++s) {
        w[s] = s == 0 ? 1.0f : 0.0f;
        bo[s] = std::uint16_t(fixedBone[i]);
      }
    } else {
      std::copy_n(weights.weight.data() + i * std::size_t(k), k, w);
      std::copy_n(weights.bone.data() + i * std::size_t(k), k, bo);
      for (int s = 1; s < k; ++s)  // insertion sort by decreasing weight (k is tiny)
        for (int t = s; t > 0 && w[t] > w[t - 1]; --t) {
          std::swap(w[t], w[t - 1]);
          std::swap(bo[t], bo[t - 1]);
        }
      if (!(w[0] != 0)) {
        c.restNodes.push_back(i);
        std::fill_n(bo, k, std::uint16_t(0));
        std::fill_n(w, k, 0.0f);
        continue;
      }
      for (int s = 1; s < k; ++s)
        if (w[s] == 0) bo[s] = bo[0];  // unused slot: keep its table index in range
    }
    for (int s = 0; s < k; ++s)
      if (int(bo[s]) > c.maxBone) {
        c.maxBone = bo[s];
        c.maxBoneNode = i;
      }
  }
  return c;
}

void skinNodes(const SkinningCache& cache, const std::vector<Eigen::Isometry3d>& boneTransforms,
               SkinningMethod method, float* posed) {
  const std::size_t nv = cache.nodeCount();
  if (nv == 0) return;
  const int k = cache.k;
  if (k < 1 || cache.weight.size() != nv * std::size_t(k) || cache.bone.size() != nv * std::size_t(k) ||
      cache.y.size() != nv || cache.z.size() != nv)
    throw std::invalid_argument("skinNodes: inconsistent SkinningCache (build it with makeSkinningCache)");
  if (!posed) throw std::invalid_argument("skinNodes: null output buffer");
  const int nb = int(boneTransforms.size());
  if (nb == 0) throw std::invalid_argument("skinNodes: no bone transforms");
  if (cache.maxBone >= nb)
    throw std::invalid_argument("skinNodes: node " + std::to_string(cache.maxBoneNode) + " uses bone " +
                                std::to_string(cache.maxBone) + ", but only " + std::to_string(nb) +
                                " bone transforms are given");
  const bool dq = method == SkinningMethod::DualQuaternion;
  std::vector<float> table;
  if (dq) {
    std::vector<DualQuaternion> q(nb);
    for (int b = 0; b < nb; ++b) q[b] = DualQuaternion::fromIsometry(boneTransforms[b]);
    table.resize(std::size_t(nb) * nb * 8);
    for (int a = 0; a < nb; ++a)
      for (int b = 0; b < nb; ++b) {
        const double sign = q[a].real.coeffs().dot(q[b].real.coeffs()) < 0 ? -1.0 : 1.0;
        float* t = table.data() + (std::size_t(a) * nb + b) * 8;
        t[0] = float(sign * q[b].real.w());
        t[1] = float(sign * q[b].real.x());
        t[2] = float(sign * q[b].real.y());
        t[3] = float(sign * q[b].real.z());
        t[4] = float(sign * q[b].dual.w());
        t[5] = float(sign * q[b].dual.x());
        t[6] = float(sign * q[b].dual.y());
        t[7] = float(sign * q[b].dual.z());
      }
  } else {
    table.assign(std::size_t(nb) * 16, 0.0f);
    for (int b = 0; b < nb; ++b) {
      const Eigen::Matrix<double, 3, 4> M = boneTransforms[b].matrix().topRows<3>();
      for (int col = 0; col < 4; ++col)
        for (int r = 0; r < 3; ++r) table[std::size_t(b) * 16 + col * 4 + r] = float(M(r, col));
    }
  }
  FastArgs args{k,           cache.x.data(), cache.y.data(), cache.z.data(), cache.weight.data(),
                cache.bone.data(), table.data(), dq ? std::size_t(nb) * 8 : 0, posed};
  void (*run)(bool, const FastArgs&, std::size_t, std::size_t) = runFastDefault;
#ifdef REPOSE_SKIN_X86
  if (useAvx2()) run = runFastAvx2;
#endif
  // Chunks of 16k nodes: few enough for negligible scheduling cost, enough to balance 2-8 cores.
  parallelFor(nv, [&](std::size_t begin, std::size_t end) { run(dq, args, begin, end); }, 16384);
  for (std::size_t i : cache.restNodes) {
    posed[3 * i] = cache.x[i];
    posed[3 * i + 1] = cache.y[i];
    posed[3 * i + 2] = cache.z[i];
  }
}

}  // namespace repose
