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
// Slabs of k-slices are the unit of parallel work, each written by one thread only. Thick slabs set
// up fewer tets twice (those crossing slab borders); a dozen slabs still balance the threads.
int slabSlices(int nz) { return std::min(32, std::max(8, nz / 12)); }
// Per-voxel coverage marks of a slab.
constexpr std::uint8_t kEmpty = 0, kCovered = 1, kExtrapolated = 2;
// Extrapolated voxels farther than this many 6-steps from the posed mesh's voxels are detached debris.
constexpr int kAttachReach = 4;

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
  if (options.restCoverage && (options.restCoverage->grid.dims != restGrid.dims ||
                               options.restCoverage->data.size() != restGrid.voxelCount()))
    throw std::invalid_argument("pull resample: rest coverage mask does not match the rest grid; compute it with "
                                "restMeshCoverage(rest grid, restNodes, tets)");
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
  bool restInside = false;  // rest tet well inside the rest grid: no bounds checks needed
  // The rest map is computed on the first voxel found (tets finer than the voxels often have none).
  double p0[3];
  const double (*rest)[3] = nullptr;
  bool mapReady = false;
};

using Vertices = double[4][3];

// Rest tet well inside the rest grid (the slack around a tet is far below 1e-3 voxels).
bool restInside(const Vertices& r, const int restDims[3]) {
  bool in = true;
  for (int m = 0; m < 3; ++m) {
    const double lo = std::min(std::min(r[0][m], r[1][m]), std::min(r[2][m], r[3][m]));
    const double hi = std::max(std::max(r[0][m], r[1][m]), std::max(r[2][m], r[3][m]));
    in = in && lo > -0.5 + 1e-3 && hi < restDims[m] - 0.5 - 1e-3;
  }
  return in;
}

// p: posed vertices (output index space), r: rest vertices (rest index space). False if degenerate.
bool setupTet(const Vertices& p, const Vertices& r, TetSetup& s) {
  double e[3][3];
  for (int q = 0; q < 3; ++q)
    for (int m = 0; m < 3; ++m) e[q][m] = p[q + 1][m] - p[0][m];
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
  for (int m = 0; m < 3; ++m) s.p0[m] = p[0][m];
  s.rest = r;
  s.mapReady = false;
  for (int m = 0; m < 3; ++m) {
    s.lo[m] = std::min(std::min(p[0][m], p[1][m]), std::min(p[2][m], p[3][m]));
    s.hi[m] = std::max(std::max(p[0][m], p[1][m]), std::max(p[2][m], p[3][m]));
  }
  for (int a = 0; a < 4; ++a) {
    s.vy[a] = p[a][1];
    s.vz[a] = p[a][2];
  }
  return true;
}

// Rest map r = A x + b of a set-up tet: the affine map taking the posed vertices to the rest ones.
inline void setupMap(TetSetup& s) {
  if (s.mapReady) return;
  const double(*r)[3] = s.rest;
  for (int m = 0; m < 3; ++m) {
    const double f0 = r[1][m] - r[0][m], f1 = r[2][m] - r[0][m], f2 = r[3][m] - r[0][m];
    for (int k = 0; k < 3; ++k) s.A[m][k] = f0 * s.g[1][k] + f1 * s.g[2][k] + f2 * s.g[3][k];
    s.b[m] = r[0][m] - (s.A[m][0] * s.p0[0] + s.A[m][1] * s.p0[1] + s.A[m][2] * s.p0[2]);
  }
  s.mapReady = true;
}

// Calls emit(i0, i1, j, k, rk) for every run of voxel centres (i0..i1, j, k), k in [k0, k1], with all
// λ_a >= -kBaryEps; rk = rest index of voxel (0, 0, k). Each λ_a is linear in i along a row, so a run
// is an intersection of half-lines. Tets are a few voxels wide, so rows are short: the per-row work is
// kept branch-free (fixed-size bound lists, integer rounding).
template <class Emit>
inline void scanTet(TetSetup& s, int k0, int k1, int nx, int ny, Emit&& emit) {
  const double kb = std::max(double(k0), std::ceil(s.lo[2] - 1e-6));
  const double ke = std::min(double(k1), std::floor(s.hi[2] + 1e-6));
  const double ib = std::max(0.0, std::ceil(s.lo[0] - 1e-6));
  const double ie = std::min(double(nx - 1), std::floor(s.hi[0] + 1e-6));
  if (kb > ke || ib > ie) return;
  // Tets about a voxel wide (common: meshes are often finer than the image) hold few candidate centres:
  // testing them directly is cheaper than setting up the scanlines.
  {
    const double jb0 = std::max(0.0, std::ceil(s.lo[1] - 1e-6));
    const double je0 = std::min(double(ny - 1), std::floor(s.hi[1] + 1e-6));
    if (jb0 > je0) return;
    if ((ke - kb + 1) * (je0 - jb0 + 1) * (ie - ib + 1) <= 8) {
      for (int k = int(kb); k <= int(ke); ++k)
        for (int j = int(jb0); j <= int(je0); ++j)
          for (int i = int(ib); i <= int(ie); ++i) {
            bool in = true;
            for (int a = 0; a < 4; ++a) in = in & (s.g[a][0] * i + s.g[a][1] * j + s.g[a][2] * k + s.c[a] >= 0);
            if (!in) continue;
            setupMap(s);
            double rk[3];
            for (int m = 0; m < 3; ++m) rk[m] = s.A[m][2] * k + s.b[m];
            emit(i, i, j, k, rk);
          }
      return;
    }
  }
  setupMap(s);
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
  // Vertices by increasing k: the cross-section at plane k is spanned by the crossings of the edges
  // from vertices below k to vertices above it.
  int o[4] = {0, 1, 2, 3};
  for (int a = 1; a < 4; ++a)
    for (int b = a; b > 0 && s.vz[o[b]] < s.vz[o[b - 1]]; --b) std::swap(o[b], o[b - 1]);
  const double z0 = s.vz[o[0]], z1 = s.vz[o[1]], z2 = s.vz[o[2]], z3 = s.vz[o[3]];
  auto slope = [&](int a, int b) {
    const double dz = s.vz[b] - s.vz[a];
    return dz > 1e-12 ? (s.vy[b] - s.vy[a]) / dz : 0.0;
  };
  const double m03 = slope(o[0], o[3]), m01 = slope(o[0], o[1]), m02 = slope(o[0], o[2]);
  const double m12 = slope(o[1], o[2]), m13 = slope(o[1], o[3]), m23 = slope(o[2], o[3]);
  const double y0 = s.vy[o[0]], y1 = s.vy[o[1]], y2 = s.vy[o[2]];
  for (int k = int(kb); k <= int(ke); ++k) {
    // j-range of the cross-section, padded so rounding never drops a row; rows it adds needlessly
    // come out empty below.
    const double z = std::min(std::max(double(k), z0), z3);
    double ylo = y0 + (z - z0) * m03, yhi = ylo, ya, yb;
    if (z <= z1) {
      // From the far ends, so an edge lying in the plane contributes both of its vertices.
      ya = y1 + (z - z1) * m01;
      yb = y2 + (z - z2) * m02;
    } else if (z <= z2) {
      ya = y1 + (z - z1) * m12;
      yb = y0 + (z - z0) * m02;
      const double yc = y1 + (z - z1) * m13;
      ylo = std::min(ylo, yc);
      yhi = std::max(yhi, yc);
    } else {
      ya = y1 + (z - z1) * m13;
      yb = y2 + (z - z2) * m23;
    }
    ylo = std::min(ylo, std::min(ya, yb)) - 1e-4;
    yhi = std::max(yhi, std::max(ya, yb)) + 1e-4;
    if (!(yhi >= 0)) continue;
    double jb = ylo > 0 ? std::ceil(ylo) : 0.0;
    double je = std::min(double(ny - 1), std::floor(yhi));
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
  // Fixed chunks counted and filled in parallel; chunk-major offsets within each slab keep tet order.
  const std::size_t nChunks = std::min<std::size_t>(64, std::max<std::size_t>(1, n / 16384));
  const std::size_t S = std::size_t(nSlabs);
  std::vector<std::size_t> start(nChunks * S, 0);
  auto chunkRange = [&](std::size_t c, std::size_t& b, std::size_t& e) {
    b = c * n / nChunks;
    e = (c + 1) * n / nChunks;
  };
  parallelFor(nChunks, [&](std::size_t cb, std::size_t ce) {
    for (std::size_t c = cb; c < ce; ++c) {
      std::size_t b, e;
      chunkRange(c, b, e);
      for (std::size_t t = b; t < e; ++t)
        for (int s = slabLo[t]; s <= slabHi[t]; ++s) ++start[c * S + std::size_t(s)];
    }
  }, 1);
  SlabBuckets B;
  B.offset.assign(S + 1, 0);
  std::size_t running = 0;
  for (std::size_t s = 0; s < S; ++s) {
    for (std::size_t c = 0; c < nChunks; ++c) {
      const std::size_t count = start[c * S + s];
      start[c * S + s] = running;
      running += count;
    }
    B.offset[s + 1] = running;
  }
  B.items.resize(running);
  parallelFor(nChunks, [&](std::size_t cb, std::size_t ce) {
    for (std::size_t c = cb; c < ce; ++c) {
      std::size_t b, e;
      chunkRange(c, b, e);
      std::size_t* fill = &start[c * S];
      for (std::size_t t = b; t < e; ++t)
        for (int s = slabLo[t]; s <= slabHi[t]; ++s) B.items[fill[s]++] = int(t);
    }
  }, 1);
  return B;
}

// Everything the slab loop needs, computed once per call.
struct Prepared {
  int nx = 0, ny = 0, nz = 0, slab = 1, nSlabs = 0;
  int restDims[3] = {0, 0, 0};
  std::vector<float> P, R;  // #V x 3 node positions in output / rest index space
  SlabBuckets tets;         // pass 1
  // Pass 2: boundary tets (not inverted) and the barycentric relaxation δ_a of each of their vertices.
  std::vector<std::uint8_t> inside;  // #T: restInside of the tet
  std::vector<int> extTet;
  std::vector<float> extDelta;  // 4 per entry of extTet
  double distance = 0;          // extrapolation distance d (mm)
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

void slabRange(double zlo, double zhi, int nz, int slab, int& lo, int& hi) {
  const double kLo = std::max(0.0, std::ceil(zlo - 1e-6));
  const double kHi = std::min(double(nz - 1), std::floor(zhi + 1e-6));
  lo = 0;
  hi = -1;
  if (kLo > kHi) return;
  lo = int(kLo) / slab;
  hi = int(kHi) / slab;
}

Prepared prepare(const ImageGrid& restGrid, const Points& restNodes, const Points& posedNodes, const Tets& tets,
                 const ImageGrid& outGrid, const PullResampleOptions& options) {
  Prepared pr;
  pr.nx = outGrid.dims[0];
  pr.ny = outGrid.dims[1];
  pr.nz = outGrid.dims[2];
  pr.slab = slabSlices(pr.nz);
  pr.nSlabs = (pr.nz + pr.slab - 1) / pr.slab;
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
  pr.distance = distance;
  const std::uint8_t* boundary =
      options.boundary && distance > 0 ? options.boundary->boundaryFaceMask.data() : nullptr;
  const Eigen::Vector3d invSpacing = outGrid.spacing.cwiseInverse();
  std::vector<int> slabLo(nT), slabHi(nT);
  pr.inside.assign(nT, 0);
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
      // Tets finer than the voxels often hold no voxel centre at all: leave those out of the buckets.
      bool holdsCentre = true;
      for (int m = 0; m < 2; ++m) {
        const double lo = std::min(std::min(p[0][m], p[1][m]), std::min(p[2][m], p[3][m]));
        const double hi = std::max(std::max(p[0][m], p[1][m]), std::max(p[2][m], p[3][m]));
        const int n = m == 0 ? pr.nx : pr.ny;
        holdsCentre = holdsCentre && std::max(0.0, std::ceil(lo - 1e-6)) <= std::min(double(n - 1), std::floor(hi + 1e-6));
      }
      if (holdsCentre) slabRange(zlo, zhi, pr.nz, pr.slab, slabLo[t], slabHi[t]);
      pr.inside[t] = restInside(r, pr.restDims);
      if (!boundary || !boundary[t] || !setupTet(p, r, st)) continue;
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
      slabRange(zlo, zhi, pr.nz, pr.slab, extLo[t], extHi[t]);
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

// Distance (mm) of a voxel of row (j, k) beyond the boundary faces of the (uninflated) tet it is
// extrapolated from: max over relaxed faces a of -λ_a h_a, with λ_a linear in i.
struct FaceDistance {
  double alpha[4], beta[4], h[4];  // λ_a = alpha + beta i; h_a = 0 for faces not relaxed
  double at(int i) const {
    double m = 0;
    for (int a = 0; a < 4; ++a) m = std::max(m, -(alpha[a] + beta[a] * i) * h[a]);
    return m;
  }
};

// Runs both passes slab by slab. Kernel provides
//   fill(begin, end)                       background into output voxels [begin, end)
//   cover(s, i0, i1, j, rk, row, mark)     pass 1: write and mark every voxel of the run (overwriting)
//   extend(s, i0, i1, j, rk, row, mark, fd)  pass 2: write voxels whose mark is kEmpty, mark them
// where row is the linear index of voxel (0, j, k), mark the marks of that row. Pass 1 visits tets in decreasing order, so the
// lowest-numbered tet covering a voxel writes last; pass 2 in increasing order, first writer wins.
template <class Kernel>
void run(const Prepared& pr, const Tets& tets, const Kernel& kernel, PullResampleReport* report,
         std::chrono::steady_clock::time_point start, std::size_t outputVoxels,
         std::vector<std::uint8_t>* allMarks = nullptr) {
  const int nx = pr.nx, ny = pr.ny, nz = pr.nz, nSlabs = pr.nSlabs;
  const std::size_t sliceSize = std::size_t(nx) * ny;
  std::atomic<std::size_t> covered{0}, extrapolated{0};
  // Marks of the whole output when the caller wants them (pinhole filling), else per slab.
  if (allMarks) allMarks->assign(outputVoxels, kEmpty);
  parallelFor(std::size_t(nSlabs), [&](std::size_t b, std::size_t e) {
    std::vector<std::uint8_t> marks(allMarks ? 0 : sliceSize * std::size_t(pr.slab));
    TetSetup st, orig;
    Vertices p, r, q, qr;
    std::size_t localCovered = 0, localExtrapolated = 0;
    for (std::size_t w = b; w < e; ++w) {
      // Interleave slabs so a static two-way split still gets both ends of the body.
      const std::size_t half = (std::size_t(nSlabs) + 1) / 2;
      const int s = w < half ? int(2 * w) : int(2 * (w - half) + 1);
      const int k0 = s * pr.slab, k1 = std::min(nz - 1, k0 + pr.slab - 1);
      const std::size_t slabBase = std::size_t(k0) * sliceSize;
      const std::size_t slabVoxels = std::size_t(k1 - k0 + 1) * sliceSize;
      std::uint8_t* mark = allMarks ? allMarks->data() + slabBase : marks.data();
      if (!allMarks) std::memset(mark, kEmpty, slabVoxels);
      kernel.fill(slabBase, slabBase + slabVoxels);
      for (std::size_t q1 = pr.tets.offset[s + 1]; q1-- > pr.tets.offset[s];) {
        const std::size_t t = std::size_t(pr.tets.items[q1]);
        loadTet(pr, tets, t, p, r);
        if (!setupTet(p, r, st)) continue;
        st.restInside = pr.inside[t] != 0;
        scanTet(st, k0, k1, nx, ny, [&](int i0, int i1, int j, int k, const double* rk) {
          const std::size_t row = std::size_t(k) * sliceSize + std::size_t(j) * nx;
          kernel.cover(st, i0, i1, j, rk, row, mark + (row - slabBase));
        });
      }
      if (!pr.ext.offset.empty()) {
        for (std::size_t q2 = pr.ext.offset[s]; q2 < pr.ext.offset[s + 1]; ++q2) {
          const std::size_t x = std::size_t(pr.ext.items[q2]);
          loadTet(pr, tets, std::size_t(pr.extTet[x]), p, r);
          const float* delta = &pr.extDelta[4 * x];
          if (!setupTet(p, r, orig)) continue;
          inflate(p, delta, q);
          inflate(r, delta, qr);
          if (!setupTet(q, qr, st)) continue;
          st.restInside = false;
          FaceDistance fd;
          for (int a = 0; a < 4; ++a) fd.h[a] = delta[a] > 0 ? pr.distance / delta[a] : 0.0;  // h_a = d / δ_a
          scanTet(st, k0, k1, nx, ny, [&](int i0, int i1, int j, int k, const double* rk) {
            const std::size_t row = std::size_t(k) * sliceSize + std::size_t(j) * nx;
            for (int a = 0; a < 4; ++a) {
              fd.alpha[a] = orig.g[a][1] * j + orig.g[a][2] * k + orig.c[a] - kBaryEps;
              fd.beta[a] = orig.g[a][0];
            }
            kernel.extend(st, i0, i1, j, rk, row, mark + (row - slabBase), fd);
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
  const std::uint8_t* restCovered;  // may be null
  double nearFace;                  // mm beyond its own faces within which an extension may sample covered voxels

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
  void extend(const TetSetup& s, int i0, int i1, int j, const double* rk, std::size_t row, std::uint8_t* mark,
              const FaceDistance& fd) const {
    double r[3];
    restStart(s, i0, j, rk, 0.5, r);
    const double sx = s.A[0][0], sy = s.A[1][0], sz = s.A[2][0];
    std::int32_t* d = dst + row;
    for (int i = i0; i <= i1; ++i, r[0] += sx, r[1] += sy, r[2] += sz) {
      if (mark[i] != kEmpty || !inside(r)) continue;
      const std::size_t n = index(r);
      if (restCovered && restCovered[n] && fd.at(i) > nearFace) continue;  // another part's interior
      const std::int32_t v = src[n];
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
  const std::uint8_t* restCovered;  // may be null
  double nearFace;                  // mm beyond its own faces within which an extension may sample covered voxels

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
  void extend(const TetSetup& s, int i0, int i1, int j, const double* rk, std::size_t row, std::uint8_t* mark,
              const FaceDistance& fd) const {
    double r[3];
    restStart(s, i0, j, rk, 0.0, r);
    const double sx = s.A[0][0], sy = s.A[1][0], sz = s.A[2][0];
    float* d = dst + row;
    for (int i = i0; i <= i1; ++i, r[0] += sx, r[1] += sy, r[2] += sz) {
      if (mark[i] != kEmpty || !inside(r)) continue;
      if (restCovered) {
        const std::size_t n = (std::size_t(int(r[2] + 0.5)) * std::size_t(dy) + std::size_t(int(r[1] + 0.5))) *
                                  std::size_t(dx) + std::size_t(int(r[0] + 0.5));
        if (restCovered[n] && fd.at(i) > nearFace) continue;
      }
      d[i] = sample(r);
      mark[i] = kExtrapolated;
    }
  }
};

// Coverage only: 1 on every voxel of a run.
struct CoverageKernel {
  std::uint8_t* dst;
  void fill(std::size_t, std::size_t) const {}
  void cover(const TetSetup&, int i0, int i1, int, const double*, std::size_t row, std::uint8_t*) const {
    std::fill(dst + row + i0, dst + row + i1 + 1, std::uint8_t(1));
  }
  void extend(const TetSetup&, int, int, int, const double*, std::size_t, std::uint8_t*, const FaceDistance&) const {}
};

// Voxels outside the posed mesh that the extension left empty although at least 5 of their 6
// neighbours were written: wedge gaps where the inflated boundary tets of a convex ridge do not quite
// meet. They are filled from those neighbours (the most common label, or the mean intensity), so the
// posed skin has no pinholes. Voxels inside the posed mesh are never touched. Returns the count.
template <class T, class Combine>
std::size_t fillPinholes(T* out, const std::vector<std::uint8_t>& marks, int nx, int ny, int nz, Combine combine) {
  const std::size_t sliceSize = std::size_t(nx) * ny;
  std::atomic<std::size_t> filled{0};
  parallelFor(std::size_t(nz), [&](std::size_t kb, std::size_t ke) {
    std::size_t local = 0;
    T values[6];
    for (std::size_t k = kb; k < ke; ++k)
      for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
          const std::size_t v = k * sliceSize + std::size_t(j) * nx + std::size_t(i);
          if (marks[v] != kEmpty) continue;
          int n = 0;
          auto take = [&](bool ok, std::size_t w) {
            if (ok && marks[w] != kEmpty) values[n++] = out[w];
          };
          take(i > 0, v - 1);
          take(i + 1 < nx, v + 1);
          take(j > 0, v - std::size_t(nx));
          take(j + 1 < ny, v + std::size_t(nx));
          take(k > 0, v - sliceSize);
          take(int(k) + 1 < nz, v + sliceSize);
          if (n >= 5) {
            out[v] = combine(values, n);
            ++local;
          }
        }
    filled += local;
  }, 1);
  return filled.load();
}

// Extrapolated voxels must hang on to the body: in a concave crease the inflated boundary tets fan
// out and can copy skin a voxel or two away from the posed surface. Keeps the extrapolated voxels
// 6-connected (within `reach` steps) to voxels inside the posed mesh; the others become background
// (marked empty again). Returns how many were dropped.
template <class T>
std::size_t dropDetachedExtrapolation(T* out, std::vector<std::uint8_t>& marks, int nx, int ny, int nz, int reach,
                                      T background) {
  constexpr std::uint8_t kAttached = 3;
  const std::size_t sliceSize = std::size_t(nx) * ny, n = marks.size();
  std::vector<std::uint8_t> next;
  for (int pass = 0; pass < reach; ++pass) {
    next = marks;
    std::atomic<std::size_t> changed{0};
    parallelFor(std::size_t(nz), [&](std::size_t kb, std::size_t ke) {
      std::size_t local = 0;
      for (std::size_t k = kb; k < ke; ++k)
        for (int j = 0; j < ny; ++j)
          for (int i = 0; i < nx; ++i) {
            const std::size_t v = k * sliceSize + std::size_t(j) * nx + std::size_t(i);
            if (marks[v] != kExtrapolated) continue;
            auto attached = [&](bool ok, std::size_t w) { return ok && (marks[w] == kCovered || marks[w] == kAttached); };
            if (attached(i > 0, v - 1) || attached(i + 1 < nx, v + 1) || attached(j > 0, v - std::size_t(nx)) ||
                attached(j + 1 < ny, v + std::size_t(nx)) || attached(k > 0, v - sliceSize) ||
                attached(int(k) + 1 < nz, v + sliceSize)) {
              next[v] = kAttached;
              ++local;
            }
          }
      changed += local;
    }, 1);
    marks.swap(next);
    if (changed.load() == 0) break;
  }
  std::atomic<std::size_t> dropped{0};
  parallelFor(n, [&](std::size_t b, std::size_t e) {
    std::size_t local = 0;
    for (std::size_t v = b; v < e; ++v) {
      if (marks[v] == kExtrapolated) {
        out[v] = background;
        marks[v] = kEmpty;
        ++local;
      } else if (marks[v] == kAttached) {
        marks[v] = kExtrapolated;
      }
    }
    dropped += local;
  });
  return dropped.load();
}

std::int32_t mostCommon(const std::int32_t* v, int n, std::int32_t background) {
  std::int32_t best = background;
  int bestCount = 0;
  for (int a = 0; a < n; ++a) {
    if (v[a] == background) continue;
    int c = 0;
    for (int b = 0; b < n; ++b) c += v[b] == v[a];
    if (c > bestCount || (c == bestCount && v[a] < best)) best = v[a], bestCount = c;
  }
  return best;
}

// Both passes, then (with extrapolation) detached fragments dropped and pinholes closed with
// `combine` of the neighbours (most common label, or mean intensity).
template <class T, class Kernel, class Combine>
void resamplePasses(const Prepared& pr, const Tets& tets, const Kernel& kernel, Volume<T>& out, T background,
                    Combine combine, PullResampleReport* report, std::chrono::steady_clock::time_point start) {
  std::vector<std::uint8_t> marks;
  const bool extrapolate = !pr.ext.offset.empty();
  run(pr, tets, kernel, report, start, out.grid.voxelCount(), extrapolate ? &marks : nullptr);
  if (!extrapolate) return;
  const std::size_t dropped =
      dropDetachedExtrapolation(out.data.data(), marks, pr.nx, pr.ny, pr.nz, kAttachReach, background);
  const std::size_t filled = fillPinholes(out.data.data(), marks, pr.nx, pr.ny, pr.nz, combine);
  if (report) {
    report->extrapolatedVoxels = report->extrapolatedVoxels + filled - dropped;
    report->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
}

}  // namespace

MaskVolume restMeshCoverage(const ImageGrid& restGrid, const Points& restNodes, const Tets& tets) {
  const PullResampleOptions none;
  validate(restGrid, restGrid.voxelCount(), restNodes, restNodes, tets, restGrid, none);
  const Prepared pr = prepare(restGrid, restNodes, restNodes, tets, restGrid, none);
  MaskVolume out;
  out.grid = restGrid;
  out.data.assign(restGrid.voxelCount(), 0);
  run(pr, tets, CoverageKernel{out.data.data()}, nullptr, std::chrono::steady_clock::now(), restGrid.voxelCount());
  return out;
}

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
                           rest.grid.dims[2], background,
                           options.restCoverage ? options.restCoverage->data.data() : nullptr,
                           rest.grid.spacing.maxCoeff()};
  resamplePasses(pr, tets, kernel, out, background,
                 [background](const std::int32_t* v, int n) { return mostCommon(v, n, background); }, report, start);
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
                               rest.grid.dims[2], background,
                               options.restCoverage ? options.restCoverage->data.data() : nullptr,
                               rest.grid.spacing.maxCoeff()};
  resamplePasses(pr, tets, kernel, out, background,
                 [](const float* v, int n) {
                   double sum = 0;
                   for (int i = 0; i < n; ++i) sum += v[i];
                   return float(sum / n);
                 },
                 report, start);
  return out;
}

IntensityVolume resampleIntensityPull(const IntensityVolume& rest, const Points& restNodes,
                                      const Points& posedNodes, const Tets& tets, const ImageGrid& outGrid,
                                      float background, PullResampleReport* report) {
  return resampleIntensityPull(rest, restNodes, posedNodes, tets, outGrid, PullResampleOptions{}, background,
                               report);
}

}  // namespace repose
