#include "resample_pull.h"

#include "distance_transform.h"

#include <Eigen/Dense>
#include <algorithm>
#include <utility>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "parallel_for.h"
#include "pull_extrapolation.h"
#include "pull_pinholes.h"
#include "pull_work_box.h"
#include "tet_boundary.h"

namespace repose {
namespace {

// The work box, the extrapolation and the pinhole fill (internal headers).
using namespace pull;

// Slack on barycentric coordinates so voxel centres on shared faces are covered by at least one tet
// despite rounding (no cracks); the lowest-numbered tet covering a voxel gives its value.
constexpr double kBaryEps = 1e-7;

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
  if (options.restDistance && (options.restDistance->grid.dims != restGrid.dims ||
                               options.restDistance->data.size() != restGrid.voxelCount()))
    throw std::invalid_argument("pull resample: rest mesh distance does not match the rest grid; compute it with "
                                "restMeshDistance(restMeshCoverage(rest grid, restNodes, tets))");
  if (options.restCoverage && (options.restCoverage->grid.dims != restGrid.dims ||
                               options.restCoverage->data.size() != restGrid.voxelCount()))
    throw std::invalid_argument("pull resample: rest coverage mask does not match the rest grid; compute it with "
                                "restMeshCoverage(rest grid, restNodes, tets)");
  if (options.outputExtent) {
    const auto& e = *options.outputExtent;
    for (int a = 0; a < 3; ++a)
      if (e[2 * a] < 0 || e[2 * a + 1] < e[2 * a] || e[2 * a + 1] >= outGrid.dims[a])
        throw std::invalid_argument("pull resample: output extent [" + std::to_string(e[0]) + " " + std::to_string(e[1]) +
                                    " " + std::to_string(e[2]) + " " + std::to_string(e[3]) + " " + std::to_string(e[4]) +
                                    " " + std::to_string(e[5]) + "] is empty or not inside the output grid (dims " +
                                    std::to_string(outGrid.dims[0]) + " " + std::to_string(outGrid.dims[1]) + " " +
                                    std::to_string(outGrid.dims[2]) + ")");
  }
  if (options.boundary && (options.boundary->boundaryFaceMask.size() != std::size_t(tets.rows()) ||
                           options.boundary->touchesBoundary.size() != std::size_t(tets.rows())))
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

// floor / ceil without a libm call (baseline x86-64 has no rounding instruction); arguments are
// clamped far outside any grid first, so the conversion cannot overflow.
inline double floorFast(double x) {
  x = std::min(std::max(x, -1e9), 1e9);
  const double i = double(static_cast<long long>(x));
  return i - (i > x);
}
inline double ceilFast(double x) {
  x = std::min(std::max(x, -1e9), 1e9);
  const double i = double(static_cast<long long>(x));
  return i + (i < x);
}

// Same as int(floorFast(x)) / int(ceilFast(x)) for the integer results the lattice needs.
inline int floorInt(double x) {
  x = std::min(std::max(x, -1e9), 1e9);
  const int i = static_cast<int>(x);
  return i - (double(i) > x);
}
inline int ceilInt(double x) {
  x = std::min(std::max(x, -1e9), 1e9);
  const int i = static_cast<int>(x);
  return i + (double(i) < x);
}

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

// p: posed vertices (output index space), r: rest vertices (rest index space); n: rows of the inverse of
// the edge matrix [p1-p0 p2-p0 p3-p0] (columns) times det, i.e. cross products of the edges, and det
// (non-zero), as the caller computed them for the orientation test.
// The barycentric maps g, c of s (the rest map left to setupMap).
inline void setupBarycentrics(const Vertices& p, const double n[3][3], double det, TetSetup& s) {
  const double inv = 1.0 / det;
  for (int q = 0; q < 3; ++q) {
    for (int m = 0; m < 3; ++m) s.g[q + 1][m] = n[q][m] * inv;
    s.c[q + 1] = -(s.g[q + 1][0] * p[0][0] + s.g[q + 1][1] * p[0][1] + s.g[q + 1][2] * p[0][2]);
  }
  for (int m = 0; m < 3; ++m) s.g[0][m] = -(s.g[1][m] + s.g[2][m] + s.g[3][m]);
  s.c[0] = 1.0 - (s.c[1] + s.c[2] + s.c[3]);
  for (int a = 0; a < 4; ++a) s.c[a] += kBaryEps;
  for (int m = 0; m < 3; ++m) s.p0[m] = p[0][m];
  s.mapReady = false;
}

void setupTet(const Vertices& p, const Vertices& r, const double n[3][3], double det, TetSetup& s) {
  setupBarycentrics(p, n, det, s);
  s.rest = r;
  for (int m = 0; m < 3; ++m) {
    s.lo[m] = std::min(std::min(p[0][m], p[1][m]), std::min(p[2][m], p[3][m]));
    s.hi[m] = std::max(std::max(p[0][m], p[1][m]), std::max(p[2][m], p[3][m]));
  }
  for (int a = 0; a < 4; ++a) {
    s.vy[a] = p[a][1];
    s.vz[a] = p[a][2];
  }
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

// Calls emit(i0, i1, j, k, rk) for every run of voxel centres (i0..i1, j, k) in the box [lo, hi], with all
// λ_a >= -kBaryEps; rk = rest index of voxel (0, 0, k). Each λ_a is linear in i along a row, so a run
// is an intersection of half-lines. Tets are a few voxels wide, so rows are short: the per-row work is
// kept branch-free (fixed-size bound lists, integer rounding).
template <class Emit>
inline void scanTet(TetSetup& s, const int lo[3], const int hi[3], Emit&& emit) {
  const double kb = std::max(double(lo[2]), ceilFast(s.lo[2] - 1e-6));
  const double ke = std::min(double(hi[2]), floorFast(s.hi[2] + 1e-6));
  const double ib = std::max(double(lo[0]), ceilFast(s.lo[0] - 1e-6));
  const double ie = std::min(double(hi[0]), floorFast(s.hi[0] + 1e-6));
  if (kb > ke || ib > ie) return;
  // Tets about a voxel wide (common: meshes are often finer than the image) hold few candidate centres:
  // testing them directly is cheaper than setting up the scanlines.
  {
    const double jb0 = std::max(double(lo[1]), ceilFast(s.lo[1] - 1e-6));
    const double je0 = std::min(double(hi[1]), floorFast(s.hi[1] + 1e-6));
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
    if (!(yhi >= lo[1])) continue;
    double jb = std::max(double(lo[1]), ceilFast(ylo));
    double je = std::min(double(hi[1]), floorFast(yhi));
    for (int q = 0; q < nf; ++q) {  // flat: λ = g.y j + g.z k + c >= 0
      const int a = flat[q];
      const double base = s.g[a][2] * k + s.c[a];
      if (s.g[a][1] > 0)
        jb = std::max(jb, ceilFast(-base / s.g[a][1]));
      else if (s.g[a][1] < 0)
        je = std::min(je, floorFast(-base / s.g[a][1]));
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
      const double rlo = std::max(std::max(ib, al[0] + bl[0] * j), std::max(al[1] + bl[1] * j, al[2] + bl[2] * j));
      const double rhi = std::min(std::min(ie, au[0] + bu[0] * j), std::min(au[1] + bu[1] * j, au[2] + bu[2] * j));
      if (!(rlo <= rhi)) continue;
      // 0 <= rlo <= rhi here, so truncation is floor.
      int i0 = int(rlo);
      i0 += double(i0) < rlo;
      const int i1 = int(rhi);
      if (i0 <= i1) emit(i0, i1, j, k, rk);
    }
  }
}

// One voxel's value from one tet: `v` is the voxel's index in the work box minus the first index of its
// z-range (32 bits halve the samples' memory traffic).
template <class T>
struct Sample {
  std::uint32_t v;
  T value;
};

// Samples of a fixed chunk of consecutive tets (in tet order), split by z-range of the work box so the
// ranges can be written in parallel; `front` holds the voxels covered by tets touching the mesh
// boundary, the seeds of the extrapolation.
template <class T>
struct ChunkSamples {
  std::vector<std::vector<Sample<T>>> cover;
  std::vector<std::vector<VoxelTet<std::uint32_t>>> front;
  std::size_t inverted = 0;
};

// Voxel centres of the box within the bounding box of posed tet t (same rounding as scanTet): [lo, hi]
// per axis; false if there are none. Read straight from the float node coordinates X (the float
// extremes convert exactly): a per-tet test, and much cheaper than going through a Vertices copy.
inline bool latticeBox(const std::vector<float>& X, const Tets& tets, std::size_t t, const Box& box, int lo[3],
                       int hi[3]) {
  const float* v0 = X.data() + std::size_t(tets(t, 0)) * 3;
  const float* v1 = X.data() + std::size_t(tets(t, 1)) * 3;
  const float* v2 = X.data() + std::size_t(tets(t, 2)) * 3;
  const float* v3 = X.data() + std::size_t(tets(t, 3)) * 3;
  bool any = true;
  for (int m = 0; m < 3; ++m) {
    const double a = double(std::min(std::min(v0[m], v1[m]), std::min(v2[m], v3[m]))) - 1e-6;
    const double b = double(std::max(std::max(v0[m], v1[m]), std::max(v2[m], v3[m]))) + 1e-6;
    lo[m] = std::max(box.lo[m], ceilInt(a));
    hi[m] = std::min(box.hi[m], floorInt(b));
    any &= lo[m] <= hi[m];
  }
  return any;
}

// Rest index of voxel (i0, j, k) under the tet's map (rk: that of (0, 0, k)), plus `offset` on every axis.
inline void restStart(const TetSetup& s, int i0, int j, const double* rk, double offset, double r[3]) {
  for (int m = 0; m < 3; ++m) r[m] = rk[m] + s.A[m][1] * j + s.A[m][0] * i0 + offset;
}

// visit(i - i0, r) for each voxel of the run, r its rest index (the rest index steps by a constant vector).
template <class Visit>
inline void forRun(const TetSetup& s, int i0, int i1, int j, const double* rk, Visit&& visit) {
  double r[3];
  restStart(s, i0, j, rk, 0.0, r);
  const double sx = s.A[0][0], sy = s.A[1][0], sz = s.A[2][0];
  for (int i = i0; i <= i1; ++i, r[0] += sx, r[1] += sy, r[2] += sz) visit(i - i0, r);
}

// Kernels turn a run of voxels (i0..i1, j) of a tet into samples: push(i - i0, value).
//   cover(s, i0, i1, j, rk, push)     pass 1: every voxel of the run
//   extendAt(r, distance, restDistanceToTet, value)
//                                     extrapolation: the value at rest index r of a voxel `distance` mm
//                                     outside the tet it is extrapolated from; false = not written
// Whether an extrapolation `distance` mm outside its tet may sample rest voxel n: inside another part
// of the mesh only near the tet's face; outside the mesh only if the tet is about as near as the
// nearest part of the mesh (restDistance, see restMeshDistance).
struct RestOwnership {
  const std::uint8_t* restCovered;   // may be null
  const std::uint8_t* restDistance;  // may be null
  double nearFace;                   // mm outside its tet within which covered voxels may be sampled
  double unit;                       // mm per step of restDistance
  // `distance`: how far outside its posed tet the voxel lies; restDistanceToTet(): how far its rest
  // point lies from the rest tet (computed only where it is needed).
  template <class RestDistance>
  bool allows(std::size_t n, double distance, RestDistance&& restDistanceToTet) const {
    if (restCovered && restCovered[n] && distance > nearFace) return false;  // another part's interior
    if (restDistance && restDistance[n] > 0 && restDistance[n] < 255 &&
        restDistanceToTet() > (restDistance[n] + 1) * unit)
      return false;  // nearer to another part of the mesh: that part's to take back
    return true;
  }
};

struct LabelKernel {
  using Value = std::int32_t;
  const std::int32_t* src;
  int dx, dy, dz;
  std::int32_t background;
  RestOwnership owner;

  // Nearest voxel: the one whose footprint [c-0.5, c+0.5) holds the rest point. With r shifted by +0.5
  // the index is the truncation, and the rest index steps by a constant vector along the row.
  bool inside(const double r[3]) const {
    return r[0] >= 0 && r[1] >= 0 && r[2] >= 0 && r[0] < dx && r[1] < dy && r[2] < dz;
  }
  std::size_t index(const double r[3]) const {
    return (std::size_t(int(r[2])) * std::size_t(dy) + std::size_t(int(r[1]))) * std::size_t(dx) + std::size_t(int(r[0]));
  }
  template <class Push>
  void cover(const TetSetup& s, int i0, int i1, int j, const double* rk, Push&& push) const {
    double r[3];
    restStart(s, i0, j, rk, 0.5, r);
    const double sx = s.A[0][0], sy = s.A[1][0], sz = s.A[2][0];
    if (s.restInside) {
      for (int i = i0; i <= i1; ++i, r[0] += sx, r[1] += sy, r[2] += sz) push(i - i0, src[index(r)]);
    } else {
      for (int i = i0; i <= i1; ++i, r[0] += sx, r[1] += sy, r[2] += sz)
        push(i - i0, inside(r) ? src[index(r)] : background);
    }
  }
  template <class RestDistance>
  bool extendAt(const double r0[3], double distance, RestDistance&& restDistanceToTet, std::int32_t& value) const {
    const double r[3] = {r0[0] + 0.5, r0[1] + 0.5, r0[2] + 0.5};
    if (!inside(r)) return false;
    const std::size_t n = index(r);
    if (src[n] == background) return false;  // never paint background: another tet may reach it
    if (!owner.allows(n, distance, restDistanceToTet)) return false;
    value = src[n];
    return true;
  }
};

struct IntensityKernel {
  using Value = float;
  const float* src;
  int dx, dy, dz;
  float background;
  RestOwnership owner;

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
  template <class Push>
  void cover(const TetSetup& s, int i0, int i1, int j, const double* rk, Push&& push) const {
    forRun(s, i0, i1, j, rk, [&](int n, const double* r) { push(n, s.restInside || inside(r) ? sample(r) : background); });
  }
  // Whether an extrapolation may sample rest index r: inside the rest grid, owned by its tet.
  template <class RestDistance>
  bool extends(const double r[3], double distance, RestDistance&& restDistanceToTet) const {
    if (!inside(r)) return false;
    if (!owner.restCovered && !owner.restDistance) return true;
    const std::size_t n = (std::size_t(int(r[2] + 0.5)) * std::size_t(dy) + std::size_t(int(r[1] + 0.5))) *
                              std::size_t(dx) + std::size_t(int(r[0] + 0.5));
    return owner.allows(n, distance, restDistanceToTet);
  }
  template <class RestDistance>
  bool extendAt(const double r[3], double distance, RestDistance&& restDistanceToTet, float& value) const {
    if (!extends(r, distance, restDistanceToTet)) return false;
    value = sample(r);
    return true;
  }
};

// The rest point itself (in rest index space) in place of a sample: the map the intensity kernel
// samples through, with the same extrapolation rule (inside the rest grid, owned by the tet).
struct RestIndex {
  float r[3];
  bool operator==(const RestIndex& o) const { return r[0] == o.r[0] && r[1] == o.r[1] && r[2] == o.r[2]; }
};
constexpr float kNoRestPoint = 1e30f;

struct RestPointKernel {
  using Value = RestIndex;
  IntensityKernel bounds;  // its grid bounds and ownership (src unused)

  template <class Push>
  void cover(const TetSetup& s, int i0, int i1, int j, const double* rk, Push&& push) const {
    forRun(s, i0, i1, j, rk, [&](int n, const double* r) { push(n, RestIndex{{float(r[0]), float(r[1]), float(r[2])}}); });
  }
  template <class RestDistance>
  bool extendAt(const double r[3], double distance, RestDistance&& restDistanceToTet, RestIndex& value) const {
    if (!bounds.extends(r, distance, restDistanceToTet)) return false;
    value = RestIndex{{float(r[0]), float(r[1]), float(r[2])}};
    return true;
  }
};

RestIndex meanRestIndex(const RestIndex* v, int n) {
  double sum[3] = {0, 0, 0};
  for (int i = 0; i < n; ++i)
    for (int m = 0; m < 3; ++m) sum[m] += v[i].r[m];
  return RestIndex{{float(sum[0] / n), float(sum[1] / n), float(sum[2] / n)}};
}

// Coverage only: 1 on every voxel of a run.
struct CoverageKernel {
  using Value = std::uint8_t;
  template <class Push>
  void cover(const TetSetup&, int i0, int i1, int, const double*, Push&& push) const {
    for (int i = i0; i <= i1; ++i) push(i - i0, std::uint8_t(1));
  }
  template <class RestDistance>
  bool extendAt(const double*, double, RestDistance&&, std::uint8_t&) const { return false; }
};

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


// The whole resampling of the output voxels in `voi` (output index box) into `dst` (voi's voxels, i
// fastest), one stage per method. Work is O(#tets + written voxels) plus filling dst:
//  1. sampleTets: one pass over fixed chunks of tets (each set up once): samples of every voxel centre
//     in a tet, kept per chunk and z-range, and the voxels of tets touching the mesh boundary;
//  2. writeSamples: per z-range, the samples written from the last tet to the first (the
//     lowest-numbered tet covering a voxel wins);
//  3. with extrapolation, the mesh's outside grown layer by layer on the voxel grid from the seeds of
//     step 1 (pull_extrapolation.h), then pinholes filled, visiting only the rows that hold written
//     voxels (pull_pinholes.h);
//  4. finish: counts over voi, and voi's voxels into dst when the work box is larger.
// With extrapolation the work box is `voi` grown by the reach of step 3, so a sub-extent gets exactly
// the values of the full resample.
template <class Kernel>
class PullResampler {
 public:
  using T = typename Kernel::Value;

  PullResampler(const ImageGrid& restGrid, const Points& restNodes, const Points& posedNodes, const Tets& tets,
                const ImageGrid& outGrid, const PullResampleOptions& options, const Kernel& kernel, T background,
                const Box& voi, T* dst)
      : tets_(tets), kernel_(kernel), background_(background),
        distance_(options.extrapolationDistance < 0 ? 2.0 * restGrid.spacing.maxCoeff()
                                                    : options.extrapolationDistance),
        extrapolate_(options.boundary && distance_ > 0),
        // Layers of extrapolation: enough 6-steps to reach `distance` along an axis of the finest
        // spacing, and two more for the diagonal steps around convex corners and for meshes coarser than
        // the voxels (their boundary faces cut corners of the peeled mask).
        layers_(extrapolate_ ? int(std::min(64.0, std::ceil(distance_ / outGrid.spacing.minCoeff()))) + 2 : 0),
        touches_(extrapolate_ ? options.boundary->touchesBoundary.data() : nullptr),
        // Step 3 reads marks up to layers + kFillPasses + 1 voxels away.
        w_(voi, outGrid.dims.data(), extrapolate_ ? layers_ + kFillPasses + 1 : 0, dst, background),
        mesh_{P_, R_, tets, outGrid.direction.determinant() < 0 ? -1.0 : 1.0, outGrid.spacing.cwiseInverse(),
              restGrid.spacing} {
    // Node positions in output / rest index space. Orientation in index space flips with a
    // left-handed direction matrix (mesh_.orient).
    const std::size_t nV = std::size_t(posedNodes.rows());
    P_.resize(3 * nV);
    R_.resize(3 * nV);
    parallelFor(nV, [&](std::size_t b, std::size_t e) {
      for (std::size_t v = b; v < e; ++v) {
        const Eigen::Vector3d p = outGrid.physicalToIndex(posedNodes.row(v).transpose());
        const Eigen::Vector3d r = restGrid.physicalToIndex(restNodes.row(v).transpose());
        for (int m = 0; m < 3; ++m) {
          P_[3 * v + m] = float(p[m]);
          R_[3 * v + m] = float(r[m]);
        }
      }
    });
    for (int a = 0; a < 3; ++a) restDims_[a] = restGrid.dims[a];
    w_.splitRanges();
  }

  template <class Combine>
  void run(Combine& combine, PullResampleReport* report, std::chrono::steady_clock::time_point start) {
    sampleTets();
    writeSamples();
    std::size_t inverted = 0;
    for (auto& C : chunks_) inverted += C.inverted;
    if (extrapolate_) {
      std::vector<Seed> seeds = frontSeeds();
      std::vector<ChunkSamples<T>>().swap(chunks_);
      extrapolateLayers(w_, std::move(seeds), layers_, kernel_, mesh_);
    }
    std::vector<ChunkSamples<T>>().swap(chunks_);
    const RowSpans spans(w_);
    const std::size_t filledInVoi = extrapolate_ ? fillPinholes(w_, spans, background_, combine) : 0;
    std::size_t covered, extended;
    finish(spans, covered, extended);
    if (report) {
      report->outputVoxels = w_.voi.count();
      report->coveredVoxels = covered;
      report->extrapolatedVoxels = extended + filledInVoi;
      report->invertedTets = inverted;
      report->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }
  }

 private:
  // 1. Samples per chunk of tets and z-range.
  void sampleTets() {
    const std::size_t nT = std::size_t(tets_.rows());
    nChunks_ = std::min<std::size_t>(512, std::max<std::size_t>(1, nT / 4096));
    chunks_.resize(nChunks_);
    parallelFor(nChunks_, [&](std::size_t cb, std::size_t ce) {
      for (std::size_t c = cb; c < ce; ++c) sampleChunk(c, c * nT / nChunks_, (c + 1) * nT / nChunks_);
    }, 1);
  }

  // The samples of tets [tb, te) into chunk c.
  void sampleChunk(std::size_t c, std::size_t tb, std::size_t te) {
    const Box& W = w_.W;
    const std::vector<float>& P = P_;
    const Tets& tets = tets_;
    Vertices p, r;
    TetSetup st{}, sm{};
    ChunkSamples<T>& C = chunks_[c];
    C.cover.resize(std::size_t(w_.nRanges));
    C.front.resize(std::size_t(w_.nRanges));
    for (std::size_t t = tb; t < te; ++t) {
      // Tets finer than the voxels often hold no voxel centre at all.
      int lb[3], ub[3];
      if (!latticeBox(P, tets, t, W, lb, ub)) continue;
      const bool front = touches_ && touches_[t];
      loadVertices(P, tets, t, p);
      // Edges, and the rows of their inverse times det (for setupTet).
      double e[3][3], n[3][3];
      const double det = edgeCofactors(p, e, n);
      // Inverted or flat: orient * det <= 1e-12 x the product of the edge lengths.
      const double od = mesh_.orient * det;
      const double l2 = (e[0][0] * e[0][0] + e[0][1] * e[0][1] + e[0][2] * e[0][2]) *
                        (e[1][0] * e[1][0] + e[1][1] * e[1][1] + e[1][2] * e[1][2]) *
                        (e[2][0] * e[2][0] + e[2][1] * e[2][1] + e[2][2] * e[2][2]);
      if (!(od > 0 && od * od > 1e-24 * l2)) {
        ++C.inverted;
        continue;
      }
      const int candidates = (ub[0] - lb[0] + 1) * (ub[1] - lb[1] + 1) * (ub[2] - lb[2] + 1);
      if (candidates <= 8) {
        // Few candidate centres: test them directly; the rest map only once one is inside.
        setupBarycentrics(p, n, det, sm);
        sm.restInside = false;
        for (int k = lb[2]; k <= ub[2]; ++k)
          for (int j = lb[1]; j <= ub[1]; ++j)
            for (int i = lb[0]; i <= ub[0]; ++i) {
              bool in = true;
              for (int a = 0; a < 4; ++a)
                in = in & (sm.g[a][0] * i + sm.g[a][1] * j + sm.g[a][2] * k + sm.c[a] >= 0);
              if (!in) continue;
              if (!sm.mapReady) {
                loadVertices(R_, tets, t, r);
                sm.rest = r;
                setupMap(sm);
              }
              double rk[3];
              for (int m = 0; m < 3; ++m) rk[m] = sm.A[m][2] * k + sm.b[m];
              const std::size_t g = w_.rangeOf[std::size_t(k - W.lo[2])];
              const std::size_t base = W.index(i, j, k) - w_.rangeBase[g];
              kernel_.cover(sm, i, i, j, rk, [&](int off, T value) {
                C.cover[g].push_back({std::uint32_t(base + std::size_t(off)), value});
              });
              if (front) C.front[g].push_back({std::uint32_t(base), std::uint32_t(t)});
            }
        continue;
      }
      loadVertices(R_, tets, t, r);
      setupTet(p, r, n, det, st);
      st.restInside = restInside(r, restDims_);
      scanTet(st, W.lo, W.hi, [&](int i0, int i1, int j, int k, const double* rk) {
        const std::size_t g = w_.rangeOf[std::size_t(k - W.lo[2])];
        auto& out1 = C.cover[g];
        const std::size_t base = W.index(i0, j, k) - w_.rangeBase[g];
        kernel_.cover(st, i0, i1, j, rk, [&](int off, T value) {
          out1.push_back({std::uint32_t(base + std::size_t(off)), value});
        });
        if (front)
          for (int i = i0; i <= i1; ++i)
            C.front[g].push_back({std::uint32_t(base + std::size_t(i - i0)), std::uint32_t(t)});
      });
    }
  }

  // 2. Writes, one z-range per task.
  void writeSamples() {
    parallelFor(std::size_t(w_.nRanges), [&](std::size_t rb, std::size_t re) {
      for (std::size_t g = rb; g < re; ++g) {
        T* rangeOut = w_.out + w_.rangeBase[g];
        std::uint8_t* rangeMarks = w_.marks.get() + w_.rangeBase[g];
        for (std::size_t c = nChunks_; c-- > 0;) {
          const auto& S = chunks_[c].cover[g];
          for (std::size_t q1 = S.size(); q1-- > 0;) {
            rangeOut[S[q1].v] = S[q1].value;
            rangeMarks[S[q1].v] = kCovered;
          }
        }
      }
    }, 1);
  }

  // The extrapolation's first layer: the front voxels (covered by tets touching the mesh boundary) next
  // to an empty voxel, each with the lowest-numbered such tet, sorted by voxel.
  std::vector<Seed> frontSeeds() const {
    const int nx = w_.nx, ny = w_.ny, nz = w_.nz;
    const std::size_t sliceSize = w_.sliceSize;
    const std::uint8_t* marks = w_.marks.get();
    auto hasEmptyNeighbour = [&](std::size_t v) {
      int i, j, k;
      w_.ijk(v, i, j, k);
      return (k > 0 && marks[v - sliceSize] == kEmpty) || (j > 0 && marks[v - std::size_t(nx)] == kEmpty) ||
             (i > 0 && marks[v - 1] == kEmpty) || (i + 1 < nx && marks[v + 1] == kEmpty) ||
             (j + 1 < ny && marks[v + std::size_t(nx)] == kEmpty) || (k + 1 < nz && marks[v + sliceSize] == kEmpty);
    };
    std::vector<std::vector<Seed>> seeds(static_cast<std::size_t>(w_.nRanges));
    parallelFor(std::size_t(w_.nRanges), [&](std::size_t rb, std::size_t re) {
      for (std::size_t g = rb; g < re; ++g) {
        auto& S = seeds[g];
        const std::size_t base = w_.rangeBase[g];
        for (const auto& C : chunks_)
          for (const auto& f : C.front[g])
            if (hasEmptyNeighbour(base + f.v)) S.push_back({base + f.v, f.t});
        std::sort(S.begin(), S.end(), [](const Seed& x, const Seed& y) { return x.v != y.v ? x.v < y.v : x.t < y.t; });
        S.erase(std::unique(S.begin(), S.end(), [](const Seed& x, const Seed& y) { return x.v == y.v; }), S.end());
      }
    }, 1);
    std::vector<Seed> layer;
    for (auto& S : seeds) layer.insert(layer.end(), S.begin(), S.end());
    return layer;
  }

  // 4. Counts over the requested voxels; then those voxels into dst when the work box is larger.
  void finish(const RowSpans& spans, std::size_t& coveredCount, std::size_t& extendedCount) {
    const Box& W = w_.W;
    const Box& voi = w_.voi;
    const int nx = w_.nx, ny = w_.ny;
    const T* out = w_.out;
    T* dst = w_.direct ? nullptr : w_.dst;
    std::atomic<std::size_t> covered{0}, extended{0};
    parallelFor(std::size_t(voi.n[2]), [&](std::size_t kb, std::size_t ke) {
      std::size_t c = 0, x = 0;
      for (int k = voi.lo[2] + int(kb); k < voi.lo[2] + int(ke); ++k)
        for (int j = voi.lo[1]; j <= voi.hi[1]; ++j) {
          const std::size_t row = std::size_t(k - W.lo[2]) * ny + std::size_t(j - W.lo[1]);
          const std::size_t base = W.index(voi.lo[0], j, k);
          if (dst) std::copy(out + base, out + base + voi.n[0], dst + voi.index(voi.lo[0], j, k));
          const int ib = std::max(spans.first[row], voi.lo[0] - W.lo[0]);
          const int ie = std::min(spans.last[row], voi.hi[0] - W.lo[0]);
          for (int i = ib; i <= ie; ++i) {
            const std::uint8_t m = w_.marks[row * nx + std::size_t(i)];
            c += m == kCovered;
            x += m == kExtrapolated;
          }
        }
      covered += c;
      extended += x;
    }, 1);
    coveredCount = covered.load();
    extendedCount = extended.load();
  }

  const Tets& tets_;
  const Kernel& kernel_;
  const T background_;
  const double distance_;
  const bool extrapolate_;
  const int layers_;
  const std::uint8_t* touches_;  // per tet: touches the mesh boundary (null without extrapolation)
  WorkBox<T> w_;
  std::vector<float> P_, R_;  // node positions in output / rest index space
  IndexSpaceMesh mesh_;
  int restDims_[3];
  std::size_t nChunks_ = 0;
  std::vector<ChunkSamples<T>> chunks_;
};

template <class Kernel, class Combine>
void resampleInto(const ImageGrid& restGrid, const Points& restNodes, const Points& posedNodes, const Tets& tets,
                  const ImageGrid& outGrid, const PullResampleOptions& options, const Kernel& kernel,
                  typename Kernel::Value background, Combine combine, const Box& voi,
                  typename Kernel::Value* dst, PullResampleReport* report,
                  std::chrono::steady_clock::time_point start) {
  PullResampler<Kernel>(restGrid, restNodes, posedNodes, tets, outGrid, options, kernel, background, voi, dst)
      .run(combine, report, start);
}

Box voiOf(const ImageGrid& outGrid, const PullResampleOptions& options) {
  int lo[3], hi[3];
  for (int a = 0; a < 3; ++a) {
    lo[a] = options.outputExtent ? (*options.outputExtent)[2 * a] : 0;
    hi[a] = options.outputExtent ? (*options.outputExtent)[2 * a + 1] : outGrid.dims[a] - 1;
  }
  return Box(lo, hi);
}

RestOwnership restOwnership(const ImageGrid& rest, const PullResampleOptions& options) {
  // With the distances known, a covered voxel is taken only within half a voxel of the tet's face
  // (rounding), not a whole one: the other side of a cut contact is that far at most.
  return RestOwnership{options.restCoverage ? options.restCoverage->data.data() : nullptr,
                       options.restDistance ? options.restDistance->data.data() : nullptr,
                       (options.restDistance ? 0.5 : 1.0) * rest.spacing.maxCoeff(),
                       kRestDistanceUnit * rest.spacing.minCoeff()};
}

LabelKernel labelKernel(const LabelVolume& rest, const PullResampleOptions& options, std::int32_t background) {
  return LabelKernel{rest.data.data(), rest.grid.dims[0], rest.grid.dims[1], rest.grid.dims[2], background,
                     restOwnership(rest.grid, options)};
}

IntensityKernel intensityKernel(const IntensityVolume& rest, const PullResampleOptions& options, float background) {
  return IntensityKernel{rest.data.data(), rest.grid.dims[0], rest.grid.dims[1], rest.grid.dims[2], background,
                         restOwnership(rest.grid, options)};
}

}  // namespace

void displacementPullInto(const ImageGrid& restGrid, const Points& restNodes, const Points& posedNodes,
                          const Tets& tets, const ImageGrid& outGrid, const PullResampleOptions& options,
                          float* out, PullResampleReport* report) {
  const auto start = std::chrono::steady_clock::now();
  validate(restGrid, restGrid.voxelCount(), restNodes, posedNodes, tets, outGrid, options);
  if (!out) throw std::invalid_argument("pull resample: null output buffer");
  const Box voi = voiOf(outGrid, options);
  const ImageGrid grid = options.outputExtent ? extentGrid(outGrid, *options.outputExtent) : outGrid;
  const RestIndex none{{kNoRestPoint, kNoRestPoint, kNoRestPoint}};
  // The rest points are written into `out` itself (3 floats per voxel, as the field).
  static_assert(sizeof(RestIndex) == 3 * sizeof(float), "a rest point is three packed floats");
  RestIndex* rest = reinterpret_cast<RestIndex*>(out);
  const RestPointKernel kernel{IntensityKernel{nullptr, restGrid.dims[0], restGrid.dims[1], restGrid.dims[2], 0.0f,
                                               restOwnership(restGrid, options)}};
  resampleInto(restGrid, restNodes, posedNodes, tets, outGrid, options, kernel, none, meanRestIndex, voi, rest, report,
               start);
  // Rest index -> rest point (mm) -> displacement from the voxel's own centre.
  const Eigen::Matrix3d restToPhysical = restGrid.direction * restGrid.spacing.asDiagonal();
  parallelFor(std::size_t(grid.dims[2]), [&](std::size_t kb, std::size_t ke) {
    for (int k = int(kb); k < int(ke); ++k)
      for (int j = 0; j < grid.dims[1]; ++j)
        for (int i = 0; i < grid.dims[0]; ++i) {
          float* d = out + 3 * grid.linearIndex(i, j, k);
          if (d[0] == kNoRestPoint) {
            d[0] = d[1] = d[2] = 0.0f;
            continue;
          }
          const Eigen::Vector3d x = restGrid.origin + restToPhysical * Eigen::Vector3d(d[0], d[1], d[2]);
          const Eigen::Vector3d u = x - grid.indexToPhysical(Eigen::Vector3d(i, j, k));
          for (int m = 0; m < 3; ++m) d[m] = float(u[m]);
        }
  }, 1);
}

namespace {

float meanOf(const float* v, int n) {
  double sum = 0;
  for (int i = 0; i < n; ++i) sum += v[i];
  return float(sum / n);
}

}  // namespace

ImageGrid extentGrid(const ImageGrid& grid, const std::array<int, 6>& extent) {
  for (int a = 0; a < 3; ++a)
    if (extent[2 * a] < 0 || extent[2 * a + 1] < extent[2 * a] || extent[2 * a + 1] >= grid.dims[a])
      throw std::invalid_argument("extent grid: extent is empty or not inside the grid");
  ImageGrid g = grid;
  for (int a = 0; a < 3; ++a) g.dims[a] = extent[2 * a + 1] - extent[2 * a] + 1;
  g.origin = grid.indexToPhysical(Eigen::Vector3d(extent[0], extent[2], extent[4]));
  return g;
}

MaskVolume restMeshCoverage(const ImageGrid& restGrid, const Points& restNodes, const Tets& tets) {
  const auto start = std::chrono::steady_clock::now();
  const PullResampleOptions none;
  validate(restGrid, restGrid.voxelCount(), restNodes, restNodes, tets, restGrid, none);
  MaskVolume out;
  out.grid = restGrid;
  out.data.resize(restGrid.voxelCount());
  resampleInto(restGrid, restNodes, restNodes, tets, restGrid, none, CoverageKernel{}, std::uint8_t(0),
               [](const std::uint8_t*, int) { return std::uint8_t(0); }, voiOf(restGrid, none), out.data.data(),
               nullptr, start);
  return out;
}

MaskVolume restMeshDistance(const MaskVolume& coverage) {
  if (coverage.data.size() != coverage.grid.voxelCount())
    throw std::invalid_argument("rest mesh distance: the coverage does not match its grid");
  const std::vector<float> mm = distanceToFeatures(coverage);
  const double unit = kRestDistanceUnit * coverage.grid.spacing.minCoeff();
  MaskVolume out;
  out.grid = coverage.grid;
  out.data.resize(mm.size());
  for (std::size_t v = 0; v < mm.size(); ++v)
    out.data[v] = std::uint8_t(std::min(255.0, std::ceil(double(mm[v]) / unit)));
  return out;
}

void resampleLabelsPullInto(const LabelVolume& rest, const Points& restNodes, const Points& posedNodes,
                            const Tets& tets, const ImageGrid& outGrid, const PullResampleOptions& options,
                            std::int32_t* out, std::int32_t background, PullResampleReport* report) {
  const auto start = std::chrono::steady_clock::now();
  validate(rest.grid, rest.data.size(), restNodes, posedNodes, tets, outGrid, options);
  if (!out) throw std::invalid_argument("pull resample: null output buffer");
  resampleInto(rest.grid, restNodes, posedNodes, tets, outGrid, options, labelKernel(rest, options, background),
               background, [background](const std::int32_t* v, int n) { return mostCommon(v, n, background); },
               voiOf(outGrid, options), out, report, start);
}

LabelVolume resampleLabelsPull(const LabelVolume& rest, const Points& restNodes, const Points& posedNodes,
                               const Tets& tets, const ImageGrid& outGrid, const PullResampleOptions& options,
                               std::int32_t background, PullResampleReport* report) {
  const auto start = std::chrono::steady_clock::now();
  validate(rest.grid, rest.data.size(), restNodes, posedNodes, tets, outGrid, options);
  LabelVolume out;
  out.grid = options.outputExtent ? extentGrid(outGrid, *options.outputExtent) : outGrid;
  out.data.resize(out.grid.voxelCount());
  resampleInto(rest.grid, restNodes, posedNodes, tets, outGrid, options, labelKernel(rest, options, background),
               background, [background](const std::int32_t* v, int n) { return mostCommon(v, n, background); },
               voiOf(outGrid, options), out.data.data(), report, start);
  return out;
}

LabelVolume resampleLabelsPull(const LabelVolume& rest, const Points& restNodes, const Points& posedNodes,
                               const Tets& tets, const ImageGrid& outGrid, std::int32_t background,
                               PullResampleReport* report) {
  return resampleLabelsPull(rest, restNodes, posedNodes, tets, outGrid, PullResampleOptions{}, background, report);
}

void resampleIntensityPullInto(const IntensityVolume& rest, const Points& restNodes, const Points& posedNodes,
                               const Tets& tets, const ImageGrid& outGrid, const PullResampleOptions& options,
                               float* out, float background, PullResampleReport* report) {
  const auto start = std::chrono::steady_clock::now();
  validate(rest.grid, rest.data.size(), restNodes, posedNodes, tets, outGrid, options);
  if (!out) throw std::invalid_argument("pull resample: null output buffer");
  resampleInto(rest.grid, restNodes, posedNodes, tets, outGrid, options, intensityKernel(rest, options, background),
               background, meanOf, voiOf(outGrid, options), out, report, start);
}

IntensityVolume resampleIntensityPull(const IntensityVolume& rest, const Points& restNodes,
                                      const Points& posedNodes, const Tets& tets, const ImageGrid& outGrid,
                                      const PullResampleOptions& options, float background,
                                      PullResampleReport* report) {
  const auto start = std::chrono::steady_clock::now();
  validate(rest.grid, rest.data.size(), restNodes, posedNodes, tets, outGrid, options);
  IntensityVolume out;
  out.grid = options.outputExtent ? extentGrid(outGrid, *options.outputExtent) : outGrid;
  out.data.resize(out.grid.voxelCount());
  resampleInto(rest.grid, restNodes, posedNodes, tets, outGrid, options, intensityKernel(rest, options, background),
               background, meanOf, voiOf(outGrid, options), out.data.data(), report, start);
  return out;
}

IntensityVolume resampleIntensityPull(const IntensityVolume& rest, const Points& restNodes,
                                      const Points& posedNodes, const Tets& tets, const ImageGrid& outGrid,
                                      float background, PullResampleReport* report) {
  return resampleIntensityPull(rest, restNodes, posedNodes, tets, outGrid, PullResampleOptions{}, background,
                               report);
}

}  // namespace repose
