#include "resample_pull.h"

#include <Eigen/Dense>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include "parallel_for.h"
#include "tet_boundary.h"

namespace repose {
namespace {

// Slack on barycentric coordinates so voxel centres on shared faces are covered by at least one tet
// despite rounding (no cracks); the lowest-numbered tet covering a voxel gives its value.
constexpr double kBaryEps = 1e-7;
// k-slices per slab: slabs are the unit of parallel work, each written by one thread only.
constexpr int kSlabSlices = 16;
constexpr int kEdges[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
// Branch-free choice between doubles (data-dependent conditions in the scan loops mispredict often).
inline double select(bool c, double a, double b) {
  std::uint64_t x, y;
  std::memcpy(&x, &a, 8);
  std::memcpy(&y, &b, 8);
  const std::uint64_t m = std::uint64_t(0) - std::uint64_t(c);
  const std::uint64_t z = (x & m) | (y & ~m);
  double r;
  std::memcpy(&r, &z, 8);
  return r;
}
// Per-voxel coverage marks of a slab.
constexpr std::uint8_t kEmpty = 0, kCovered = 1, kExtrapolated = 2;

void validate(const ImageGrid& restGrid, std::size_t restSize, const Points& restNodes,
              const Points& posedNodes, const Tets& tets, const ImageGrid& outGrid,
              const PullResampleOptions& options) {
  if (restGrid.voxelCount() == 0 || restSize != restGrid.voxelCount())
    throw std::invalid_argument("pull resample: rest volume data size (" + std::to_string(restSize) +
                                ") does not match its grid (" + std::to_string(restGrid.voxelCount()) +
                                " voxels)");
  if (restNodes.rows() != posedNodes.rows())
    throw std::invalid_argument("pull resample: rest mesh has " + std::to_string(restNodes.rows()) +
                                " nodes but posed mesh has " + std::to_string(posedNodes.rows()) +
                                "; they must share topology");
  if (outGrid.dims[0] <= 0 || outGrid.dims[1] <= 0 || outGrid.dims[2] <= 0)
    throw std::invalid_argument("pull resample: output grid has non-positive dimensions");
  if (!(outGrid.spacing.array() > 0).all() || !(restGrid.spacing.array() > 0).all())
    throw std::invalid_argument("pull resample: grid spacing must be positive");
  const int nV = int(restNodes.rows());
  if (tets.size() > 0 && (tets.minCoeff() < 0 || tets.maxCoeff() >= nV))
    throw std::invalid_argument("pull resample: tet node index out of range [0, " + std::to_string(nV) + ")");
  if (!posedNodes.allFinite() || !restNodes.allFinite())
    throw std::invalid_argument("pull resample: non-finite node coordinates");
  if (!std::isfinite(options.extrapolationDistance))
    throw std::invalid_argument("pull resample: extrapolation distance must be finite");
  if (options.boundary && options.boundary->boundaryFaceMask.size() != std::size_t(tets.rows()))
    throw std::invalid_argument("pull resample: tet boundary has " +
                                std::to_string(options.boundary->boundaryFaceMask.size()) + " tets but the mesh has " +
                                std::to_string(tets.rows()) + "; compute it with tetBoundary(tets)");
}

// Affine maps of one tet in index space: barycentric λ_a = g_a · x + c_a (x = output index, c_a
// includes the slack) and rest index r = A x + b.
struct TetSetup {
  double g[4][3], c[4];
  double A[3][3], b[3];
  double lo[3], hi[3];    // posed bounding box (output index space)
  double vy[4], vz[4];    // posed vertex j, k (cross-sections)
  bool restInside;        // rest tet well inside the rest grid: no bounds checks needed
};

using Vertices = double[4][3];

// p: posed vertices (output index space), r: rest vertices (rest index space). False if degenerate.
bool setupTet(const Vertices& p, const Vertices& r, const int restDims[3], TetSetup& s) {
  double e[3][3], f[3][3];
  for (int q = 0; q < 3; ++q)
    for (int m = 0; m < 3; ++m) {
      e[q][m] = p[q + 1][m] - p[0][m];
      f[q][m] = r[q + 1][m] - r[0][m];
    }
  // Rows of the inverse of [e0 e1 e2] (columns): cross products over the determinant.
  double n[3][3];
  for (int q = 0; q < 3; ++q) {
    const double* u = e[(q + 1) % 3];
    const double* v = e[(q + 2) % 3];
    n[q][0] = u[1] * v[2] - u[2] * v[1];
    n[q][1] = u[2] * v[0] - u[0] * v[2];
    n[q][2] = u[0] * v[1] - u[1] * v[0];
  }
  const double det = e[0][0] * n[0][0] + e[0][1] * n[0][1] + e[0][2] * n[0][2];
  if (!(std::abs(det) > 0)) return false;
  const double inv = 1.0 / det;
  for (int a = 0; a < 4; ++a) s.c[a] = 0;
  for (int q = 0; q < 3; ++q) {
    for (int m = 0; m < 3; ++m) s.g[q + 1][m] = n[q][m] * inv;
    s.c[q + 1] = -(s.g[q + 1][0] * p[0][0] + s.g[q + 1][1] * p[0][1] + s.g[q + 1][2] * p[0][2]);
  }
  for (int m = 0; m < 3; ++m) s.g[0][m] = -(s.g[1][m] + s.g[2][m] + s.g[3][m]);
  s.c[0] = 1.0 - (s.c[1] + s.c[2] + s.c[3]);
  for (int a = 0; a < 4; ++a) s.c[a] += kBaryEps;
  for (int m = 0; m < 3; ++m) {
    for (int k = 0; k < 3; ++k) s.A[m][k] = f[0][m] * s.g[1][k] + f[1][m] * s.g[2][k] + f[2][m] * s.g[3][k];
    s.b[m] = r[0][m] - (s.A[m][0] * p[0][0] + s.A[m][1] * p[0][1] + s.A[m][2] * p[0][2]);
  }
  s.restInside = true;
  for (int m = 0; m < 3; ++m) {
    double lo = p[0][m], hi = p[0][m], rlo = r[0][m], rhi = r[0][m];
    for (int a = 1; a < 4; ++a) {
      lo = std::min(lo, p[a][m]);
      hi = std::max(hi, p[a][m]);
      rlo = std::min(rlo, r[a][m]);
      rhi = std::max(rhi, r[a][m]);
    }
    s.lo[m] = lo;
    s.hi[m] = hi;
    s.restInside = s.restInside && rlo > -0.5 + 1e-3 && rhi < restDims[m] - 0.5 - 1e-3;
  }
  for (int a = 0; a < 4; ++a) {
    s.vy[a] = p[a][1];
    s.vz[a] = p[a][2];
  }
  return true;
}

// Calls emit(i0, i1, j, k, rk) for every run of voxel centres (i0..i1, j, k), k in [k0, k1], with all
// λ_a >= -kBaryEps; rk = rest index of voxel (0, 0, k). Each λ_a is linear in i along a row, so a run
// is an intersection of half-lines. Tets are a few voxels wide, so rows are short: the per-row work is
// kept branch-free (fixed-size bound lists, integer rounding).
template <class Emit>
inline void scanTet(const TetSetup& s, int k0, int k1, int nx, int ny, Emit&& emit) {
  const double kb = std::max(double(k0), std::ceil(s.lo[2] - 1e-6));
  const double ke = std::min(double(k1), std::floor(s.hi[2] + 1e-6));
  const double ib = std::max(0.0, std::ceil(s.lo[0] - 1e-6));
  const double ie = std::min(double(nx - 1), std::floor(s.hi[0] + 1e-6));
  if (kb > ke || ib > ie) return;
  // Constraints by the sign of dλ/di: lower bounds i >= -λ_a(0, j, k) / g_a.x, upper bounds likewise,
  // and flat ones (λ_a constant along rows), which restrict j instead. At most 3 lower and 3 upper;
  // unused slots hold bounds that never bind.
  int lower[3] = {-1, -1, -1}, upper[3] = {-1, -1, -1}, flat[4], nl = 0, nu = 0, nf = 0;
  for (int a = 0; a < 4; ++a) {
    if (s.g[a][0] > 0 && nl < 3)
      lower[nl++] = a;
    else if (s.g[a][0] < 0 && nu < 3)
      upper[nu++] = a;
    else if (s.g[a][0] == 0)
      flat[nf++] = a;
  }
  double bl[3] = {0, 0, 0}, bu[3] = {0, 0, 0}, nil[3], niu[3];
  for (int q = 0; q < 3; ++q) {
    nil[q] = lower[q] >= 0 ? -1.0 / s.g[lower[q]][0] : 0.0;
    niu[q] = upper[q] >= 0 ? -1.0 / s.g[upper[q]][0] : 0.0;
    if (lower[q] >= 0) bl[q] = s.g[lower[q]][1] * nil[q];
    if (upper[q] >= 0) bu[q] = s.g[upper[q]][1] * niu[q];
  }
  double edgeDyDz[6];
  for (int e = 0; e < 6; ++e) {
    const double dz = s.vz[kEdges[e][1]] - s.vz[kEdges[e][0]];
    edgeDyDz[e] = std::abs(dz) > 1e-12 ? (s.vy[kEdges[e][1]] - s.vy[kEdges[e][0]]) / dz : 0.0;
  }
  for (int k = int(kb); k <= int(ke); ++k) {
    // j-range of the cross-section at plane k: crossings of the edges spanning k (an edge in the plane
    // contributes its first vertex; the other is the crossing of its other edges), padded so rounding
    // never drops a row; rows it adds needlessly come out empty below.
    double ylo = 1e300, yhi = -1e300;
    for (int e = 0; e < 6; ++e) {
      const int a = kEdges[e][0], b = kEdges[e][1];
      const double za = s.vz[a], zb = s.vz[b];
      const double zmin = std::min(za, zb), zmax = std::max(za, zb);
      const bool spans = (k >= zmin - 1e-6) & (k <= zmax + 1e-6);
      const double y = s.vy[a] + (std::min(std::max(double(k), zmin), zmax) - za) * edgeDyDz[e];
      ylo = std::min(ylo, select(spans, y, 1e300));
      yhi = std::max(yhi, select(spans, y, -1e300));
    }
    double jb = std::max(0.0, std::ceil(ylo - 1e-4));
    double je = std::min(double(ny - 1), std::floor(yhi + 1e-4));
    for (int q = 0; q < nf; ++q) {  // flat: λ = g.y j + g.z k + c >= 0
      const int a = flat[q];
      const double base = s.g[a][2] * k + s.c[a];
      if (s.g[a][1] > 0)
        jb = std::max(jb, std::ceil(-base / s.g[a][1]));
      else if (s.g[a][1] < 0)
        je = std::min(je, std::floor(-base / s.g[a][1]));
      else if (base < 0)
        je = jb - 1;
    }
    if (jb > je) continue;
    double al[3], au[3];
    for (int q = 0; q < 3; ++q) {
      al[q] = lower[q] >= 0 ? (s.g[lower[q]][2] * k + s.c[lower[q]]) * nil[q] : -1e300;
      au[q] = upper[q] >= 0 ? (s.g[upper[q]][2] * k + s.c[upper[q]]) * niu[q] : 1e300;
    }
    double rk[3];
    for (int m = 0; m < 3; ++m) rk[m] = s.A[m][2] * k + s.b[m];
    for (int j = int(jb); j <= int(je); ++j) {
      const double lo = std::max(std::max(ib, al[0] + bl[0] * j), std::max(al[1] + bl[1] * j, al[2] + bl[2] * j));
      const double hi = std::min(std::min(ie, au[0] + bu[0] * j), std::min(au[1] + bu[1] * j, au[2] + bu[2] * j));
      if (!(lo <= hi)) continue;
      // 0 <= lo <= hi < nx here, so truncation is floor.
      int i0 = int(lo);
      i0 += double(i0) < lo;
      const int i1 = int(hi);
      if (i0 <= i1) emit(i0, i1, j, k, rk);
    }
  }
}

// Tets bucketed by slab (CSR), in increasing tet order.
struct SlabBuckets {
  std::vector<std::size_t> offset;
  std::vector<int> items;
};

SlabBuckets bucketize(std::size_t n, int nSlabs, const std::vector<int>& slabLo, const std::vector<int>& slabHi) {
  SlabBuckets B;
  B.offset.assign(std::size_t(nSlabs) + 1, 0);
  for (std::size_t t = 0; t < n; ++t)
    for (int s = slabLo[t]; s <= slabHi[t]; ++s) ++B.offset[std::size_t(s) + 1];
  for (int s = 0; s < nSlabs; ++s) B.offset[s + 1] += B.offset[s];
  B.items.resize(B.offset.back());
  std::vector<std::size_t> fill(B.offset.begin(), B.offset.end() - 1);
  for (std::size_t t = 0; t < n; ++t)
    for (int s = slabLo[t]; s <= slabHi[t]; ++s) B.items[fill[s]++] = int(t);
  return B;
}

// Everything the slab loop needs, computed once per call.
struct Prepared {
  int nx = 0, ny = 0, nz = 0, nSlabs = 0;
  int restDims[3] = {0, 0, 0};
  std::vector<float> P, R;  // #V x 3 node positions in output / rest index space
  SlabBuckets tets;         // pass 1
  // Pass 2: boundary tets (not inverted) and the barycentric relaxation δ_a of each of their vertices.
  std::vector<int> extTet;
  std::vector<float> extDelta;  // 4 per entry of extTet
  SlabBuckets ext;              // indices into extTet
  std::size_t inverted = 0;
};

inline void loadTet(const Prepared& pr, const Tets& tets, std::size_t t, Vertices& p, Vertices& r) {
  for (int a = 0; a < 4; ++a) {
    const std::size_t v = std::size_t(tets(t, a)) * 3;
    for (int m = 0; m < 3; ++m) {
      p[a][m] = pr.P[v + m];
      r[a][m] = pr.R[v + m];
    }
  }
}

// The tet inflated by λ_a >= -δ_a: the simplex with barycentrics (λ_a + δ_a) / (1 + Σδ), i.e. vertices
// q_c = (1 + Σδ) p_c - Σ_b δ_b p_b (a homothety, so orientation is kept). Rest vertices likewise,
// which extends the tet's affine map.
void inflate(const Vertices& p, const float* delta, Vertices& q) {
  double S = 0, sum[3] = {0, 0, 0};
  for (int b = 0; b < 4; ++b) {
    S += delta[b];
    for (int m = 0; m < 3; ++m) sum[m] += delta[b] * p[b][m];
  }
  for (int c = 0; c < 4; ++c)
    for (int m = 0; m < 3; ++m) q[c][m] = (1.0 + S) * p[c][m] - sum[m];
}

void slabRange(double zlo, double zhi, int nz, int& lo, int& hi) {
  const double kLo = std::max(0.0, std::ceil(zlo - 1e-6));
  const double kHi = std::min(double(nz - 1), std::floor(zhi + 1e-6));
  lo = 0;
  hi = -1;
  if (kLo > kHi) return;
  lo = int(kLo) / kSlabSlices;
  hi = int(kHi) / kSlabSlices;
}

Prepared prepare(const ImageGrid& restGrid, const Points& restNodes, const Points& posedNodes, const Tets& tets,
                 const ImageGrid& outGrid, const PullResampleOptions& options) {
  Prepared pr;
  pr.nx = outGrid.dims[0];
  pr.ny = outGrid.dims[1];
  pr.nz = outGrid.dims[2];
  pr.nSlabs = (pr.nz + kSlabSlices - 1) / kSlabSlices;
  for (int a = 0; a < 3; ++a) pr.restDims[a] = restGrid.dims[a];
  const std::size_t nV = std::size_t(posedNodes.rows());
  const std::size_t nT = std::size_t(tets.rows());
  pr.P.resize(3 * nV);
  pr.R.resize(3 * nV);
  parallelFor(nV, [&](std::size_t b, std::size_t e) {
    for (std::size_t v = b; v < e; ++v) {
      const Eigen::Vector3d p = outGrid.physicalToIndex(posedNodes.row(v).transpose());
      const Eigen::Vector3d r = restGrid.physicalToIndex(restNodes.row(v).transpose());
      for (int m = 0; m < 3; ++m) {
        pr.P[3 * v + m] = float(p[m]);
        pr.R[3 * v + m] = float(r[m]);
      }
    }
  });

  // Orientation in index space flips with a left-handed direction matrix.
  const double orient = outGrid.direction.determinant() < 0 ? -1.0 : 1.0;
  const double distance = options.extrapolationDistance < 0 ? 2.0 * restGrid.spacing.maxCoeff()
                                                             : options.extrapolationDistance;
  const std::uint8_t* boundary =
      options.boundary && distance > 0 ? options.boundary->boundaryFaceMask.data() : nullptr;
  const Eigen::Vector3d invSpacing = outGrid.spacing.cwiseInverse();
  std::vector<int> slabLo(nT), slabHi(nT);
  std::vector<float> delta(boundary ? 4 * nT : 0);
  std::vector<int> extLo(boundary ? nT : 0), extHi(boundary ? nT : 0);
  std::atomic<std::size_t> inverted{0};
  parallelFor(nT, [&](std::size_t b, std::size_t e) {
    std::size_t localInverted = 0;
    Vertices p, r, q;
    TetSetup st;
    for (std::size_t t = b; t < e; ++t) {
      slabLo[t] = 0;
      slabHi[t] = -1;
      if (boundary) {
        extLo[t] = 0;
        extHi[t] = -1;
      }
      loadTet(pr, tets, t, p, r);
      Eigen::Matrix3d M;
      for (int c = 0; c < 3; ++c)
        for (int m = 0; m < 3; ++m) M(m, c) = p[c + 1][m] - p[0][m];
      const double det = orient * M.determinant();
      const double scale = M.colwise().norm().prod();
      if (!(det > 1e-12 * scale)) {
        ++localInverted;
        continue;
      }
      double zlo = p[0][2], zhi = p[0][2];
      for (int c = 1; c < 4; ++c) {
        zlo = std::min(zlo, p[c][2]);
        zhi = std::max(zhi, p[c][2]);
      }
      slabRange(zlo, zhi, pr.nz, slabLo[t], slabHi[t]);
      if (!boundary || !boundary[t] || !setupTet(p, r, pr.restDims, st)) continue;
      // δ_a = d / h_a, h_a (mm) = 1 / |physical gradient of λ_a|.
      float* dl = &delta[4 * t];
      for (int a = 0; a < 4; ++a) {
        const Eigen::Vector3d g(st.g[a][0], st.g[a][1], st.g[a][2]);
        dl[a] = (boundary[t] >> a) & 1 ? float(distance * g.cwiseProduct(invSpacing).norm()) : 0.0f;
      }
      inflate(p, dl, q);
      zlo = q[0][2];
      zhi = q[0][2];
      for (int c = 1; c < 4; ++c) {
        zlo = std::min(zlo, q[c][2]);
        zhi = std::max(zhi, q[c][2]);
      }
      slabRange(zlo, zhi, pr.nz, extLo[t], extHi[t]);
    }
    inverted += localInverted;
  }, 4096);
  pr.inverted = inverted.load();
  pr.tets = bucketize(nT, pr.nSlabs, slabLo, slabHi);
  if (boundary) {
    std::vector<int> lo, hi;
    for (std::size_t t = 0; t < nT; ++t) {
      if (extLo[t] > extHi[t]) continue;
      pr.extTet.push_back(int(t));
      pr.extDelta.insert(pr.extDelta.end(), &delta[4 * t], &delta[4 * t] + 4);
      lo.push_back(extLo[t]);
      hi.push_back(extHi[t]);
    }
    pr.ext = bucketize(pr.extTet.size(), pr.nSlabs, lo, hi);
  }
  return pr;
}

// Runs both passes slab by slab. Kernel provides
//   fill(begin, end)                       background into output voxels [begin, end)
//   cover(s, i0, i1, j, rk, row, mark)     pass 1: write and mark every voxel of the run (overwriting)
//   extend(s, i0, i1, j, rk, row, mark)    pass 2: write voxels whose mark is kEmpty, mark them
// where row is the linear index of voxel (0, j, k), mark the marks of that row. Pass 1 visits tets in decreasing order, so the
// lowest-numbered tet covering a voxel writes last; pass 2 in increasing order, first writer wins.
template <class Kernel>
void run(const Prepared& pr, const Tets& tets, const Kernel& kernel, PullResampleReport* report,
         std::chrono::steady_clock::time_point start, std::size_t outputVoxels) {
  const int nx = pr.nx, ny = pr.ny, nz = pr.nz, nSlabs = pr.nSlabs;
  const std::size_t sliceSize = std::size_t(nx) * ny;
  std::atomic<std::size_t> covered{0}, extrapolated{0};
  parallelFor(std::size_t(nSlabs), [&](std::size_t b, std::size_t e) {
    std::vector<std::uint8_t> marks(sliceSize * kSlabSlices);
    TetSetup st;
    Vertices p, r, q, qr;
    std::size_t localCovered = 0, localExtrapolated = 0;
    for (std::size_t w = b; w < e; ++w) {
      // Interleave slabs so a static two-way split still gets both ends of the body.
      const std::size_t half = (std::size_t(nSlabs) + 1) / 2;
      const int s = w < half ? int(2 * w) : int(2 * (w - half) + 1);
      const int k0 = s * kSlabSlices, k1 = std::min(nz - 1, k0 + kSlabSlices - 1);
      const std::size_t slabBase = std::size_t(k0) * sliceSize;
      const std::size_t slabVoxels = std::size_t(k1 - k0 + 1) * sliceSize;
      std::uint8_t* mark = marks.data();
      std::memset(mark, kEmpty, slabVoxels);
      kernel.fill(slabBase, slabBase + slabVoxels);
      for (std::size_t q1 = pr.tets.offset[s + 1]; q1-- > pr.tets.offset[s];) {
        const std::size_t t = std::size_t(pr.tets.items[q1]);
        loadTet(pr, tets, t, p, r);
        if (!setupTet(p, r, pr.restDims, st)) continue;
        scanTet(st, k0, k1, nx, ny, [&](int i0, int i1, int j, int k, const double* rk) {
          const std::size_t row = std::size_t(k) * sliceSize + std::size_t(j) * nx;
          kernel.cover(st, i0, i1, j, rk, row, mark + (row - slabBase));
        });
      }
      if (!pr.ext.offset.empty()) {
        for (std::size_t q2 = pr.ext.offset[s]; q2 < pr.ext.offset[s + 1]; ++q2) {
          const std::size_t x = std::size_t(pr.ext.items[q2]);
          loadTet(pr, tets, std::size_t(pr.extTet[x]), p, r);
          inflate(p, &pr.extDelta[4 * x], q);
          inflate(r, &pr.extDelta[4 * x], qr);
          if (!setupTet(q, qr, pr.restDims, st)) continue;
          scanTet(st, k0, k1, nx, ny, [&](int i0, int i1, int j, int k, const double* rk) {
            const std::size_t row = std::size_t(k) * sliceSize + std::size_t(j) * nx;
            kernel.extend(st, i0, i1, j, rk, row, mark + (row - slabBase));
          });
        }
      }
      std::uint32_t c = 0, x = 0;  // per slab: fits, and lets the loop vectorize
      for (std::size_t v = 0; v < slabVoxels; ++v) {
        c += mark[v] == kCovered;
        x += mark[v] == kExtrapolated;
      }
      localCovered += c;
      localExtrapolated += x;
    }
    covered += localCovered;
    extrapolated += localExtrapolated;
  }, 1);
  if (report) {
    report->outputVoxels = outputVoxels;
    report->coveredVoxels = covered.load();
    report->extrapolatedVoxels = extrapolated.load();
    report->invertedTets = pr.inverted;
    report->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
}

// Rest index of voxel (i0, j, k) under the tet's map (rk: that of (0, 0, k)), plus `offset` on every axis.
inline void restStart(const TetSetup& s, int i0, int j, const double* rk, double offset, double r[3]) {
  for (int m = 0; m < 3; ++m) r[m] = rk[m] + s.A[m][1] * j + s.A[m][0] * i0 + offset;
}

struct LabelKernel {
  const std::int32_t* src;
  std::int32_t* dst;
  int dx, dy, dz;
  std::int32_t background;

  void fill(std::size_t b, std::size_t e) const {
    if (background != 0) std::fill(dst + b, dst + e, background);
  }
  // Nearest voxel: the one whose footprint [c-0.5, c+0.5) holds the rest point. With r shifted by +0.5
  // the index is the truncation, and the rest index steps by a constant vector along the row.
  bool inside(const double r[3]) const {
    return r[0] >= 0 && r[1] >= 0 && r[2] >= 0 && r[0] < dx && r[1] < dy && r[2] < dz;
  }
  std::size_t index(const double r[3]) const {
    return (std::size_t(int(r[2])) * std::size_t(dy) + std::size_t(int(r[1]))) * std::size_t(dx) + std::size_t(int(r[0]));
  }
  void cover(const TetSetup& s, int i0, int i1, int j, const double* rk, std::size_t row, std::uint8_t* mark) const {
    double r[3];
    restStart(s, i0, j, rk, 0.5, r);
    const double sx = s.A[0][0], sy = s.A[1][0], sz = s.A[2][0];
    std::int32_t* d = dst + row;
    if (s.restInside) {
      for (int i = i0; i <= i1; ++i, r[0] += sx, r[1] += sy, r[2] += sz) {
        d[i] = src[index(r)];
        mark[i] = kCovered;
      }
    } else {
      for (int i = i0; i <= i1; ++i, r[0] += sx, r[1] += sy, r[2] += sz) {
        d[i] = inside(r) ? src[index(r)] : background;
        mark[i] = kCovered;
      }
    }
  }
  void extend(const TetSetup& s, int i0, int i1, int j, const double* rk, std::size_t row, std::uint8_t* mark) const {
    double r[3];
    restStart(s, i0, j, rk, 0.5, r);
    const double sx = s.A[0][0], sy = s.A[1][0], sz = s.A[2][0];
    std::int32_t* d = dst + row;
    for (int i = i0; i <= i1; ++i, r[0] += sx, r[1] += sy, r[2] += sz) {
      if (mark[i] != kEmpty || !inside(r)) continue;
      const std::int32_t v = src[index(r)];
      if (v == background) continue;  // never paint background over a neighbour's extension
      d[i] = v;
      mark[i] = kExtrapolated;
    }
  }
};

struct IntensityKernel {
  const float* src;
  float* dst;
  int dx, dy, dz;
  float background;

  void fill(std::size_t b, std::size_t e) const {
    if (background != 0.0f) std::fill(dst + b, dst + e, background);
  }
  bool inside(const double r[3]) const {
    return r[0] >= -0.5 && r[1] >= -0.5 && r[2] >= -0.5 && r[0] < dx - 0.5 && r[1] < dy - 0.5 && r[2] < dz - 0.5;
  }
  // Trilinear inside the voxel footprints of the rest grid (edge voxels replicated within half a voxel).
  float sample(const double r[3]) const {
    int idx[3];
    double f[3];
    const int d[3] = {dx, dy, dz};
    for (int a = 0; a < 3; ++a) {
      const double c = std::min(std::max(r[a], 0.0), double(d[a] - 1));
      int i = int(c);
      if (i > d[a] - 2) i = std::max(0, d[a] - 2);
      idx[a] = i;
      f[a] = c - i;
    }
    const std::size_t sy = std::size_t(dx), sz = std::size_t(dx) * dy;
    const std::size_t base = idx[2] * sz + idx[1] * sy + idx[0];
    const std::size_t ox = dx > 1 ? 1 : 0, oy = dy > 1 ? sy : 0, oz = dz > 1 ? sz : 0;
    const double c00 = src[base] + f[0] * (src[base + ox] - src[base]);
    const double c10 = src[base + oy] + f[0] * (src[base + oy + ox] - src[base + oy]);
    const double c01 = src[base + oz] + f[0] * (src[base + oz + ox] - src[base + oz]);
    const double c11 = src[base + oz + oy] + f[0] * (src[base + oz + oy + ox] - src[base + oz + oy]);
    const double c0 = c00 + f[1] * (c10 - c00);
    const double c1 = c01 + f[1] * (c11 - c01);
    return float(c0 + f[2] * (c1 - c0));
  }
  void cover(const TetSetup& s, int i0, int i1, int j, const double* rk, std::size_t row, std::uint8_t* mark) const {
    double r[3];
    restStart(s, i0, j, rk, 0.0, r);
    const double sx = s.A[0][0], sy = s.A[1][0], sz = s.A[2][0];
    float* d = dst + row;
    for (int i = i0; i <= i1; ++i, r[0] += sx, r[1] += sy, r[2] += sz) {
      d[i] = s.restInside || inside(r) ? sample(r) : background;
      mark[i] = kCovered;
    }
  }
  void extend(const TetSetup& s, int i0, int i1, int j, const double* rk, std::size_t row, std::uint8_t* mark) const {
    double r[3];
    restStart(s, i0, j, rk, 0.0, r);
    const double sx = s.A[0][0], sy = s.A[1][0], sz = s.A[2][0];
    float* d = dst + row;
    for (int i = i0; i <= i1; ++i, r[0] += sx, r[1] += sy, r[2] += sz) {
      if (mark[i] != kEmpty || !inside(r)) continue;
      d[i] = sample(r);
      mark[i] = kExtrapolated;
    }
  }
};

}  // namespace

LabelVolume resampleLabelsPull(const LabelVolume& rest, const Points& restNodes, const Points& posedNodes,
                               const Tets& tets, const ImageGrid& outGrid, const PullResampleOptions& options,
                               std::int32_t background, PullResampleReport* report) {
  const auto start = std::chrono::steady_clock::now();
  validate(rest.grid, rest.data.size(), restNodes, posedNodes, tets, outGrid, options);
  const Prepared pr = prepare(rest.grid, restNodes, posedNodes, tets, outGrid, options);
  LabelVolume out;
  out.grid = outGrid;
  out.data.resize(outGrid.voxelCount());  // zeros; slabs fill other backgrounds in parallel
  const LabelKernel kernel{rest.data.data(), out.data.data(), rest.grid.dims[0], rest.grid.dims[1],
                           rest.grid.dims[2], background};
  run(pr, tets, kernel, report, start, outGrid.voxelCount());
  return out;
}

LabelVolume resampleLabelsPull(const LabelVolume& rest, const Points& restNodes, const Points& posedNodes,
                               const Tets& tets, const ImageGrid& outGrid, std::int32_t background,
                               PullResampleReport* report) {
  return resampleLabelsPull(rest, restNodes, posedNodes, tets, outGrid, PullResampleOptions{}, background, report);
}

IntensityVolume resampleIntensityPull(const IntensityVolume& rest, const Points& restNodes,
                                      const Points& posedNodes, const Tets& tets, const ImageGrid& outGrid,
                                      const PullResampleOptions& options, float background,
                                      PullResampleReport* report) {
  const auto start = std::chrono::steady_clock::now();
  validate(rest.grid, rest.data.size(), restNodes, posedNodes, tets, outGrid, options);
  const Prepared pr = prepare(rest.grid, restNodes, posedNodes, tets, outGrid, options);
  IntensityVolume out;
  out.grid = outGrid;
  out.data.resize(outGrid.voxelCount());
  const IntensityKernel kernel{rest.data.data(), out.data.data(), rest.grid.dims[0], rest.grid.dims[1],
                               rest.grid.dims[2], background};
  run(pr, tets, kernel, report, start, outGrid.voxelCount());
  return out;
}

IntensityVolume resampleIntensityPull(const IntensityVolume& rest, const Points& restNodes,
                                      const Points& posedNodes, const Tets& tets, const ImageGrid& outGrid,
                                      float background, PullResampleReport* report) {
  return resampleIntensityPull(rest, restNodes, posedNodes, tets, outGrid, PullResampleOptions{}, background,
                               report);
}

}  // namespace repose
