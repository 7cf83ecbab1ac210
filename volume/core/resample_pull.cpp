#include "resample_pull.h"

#include <Eigen/Dense>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>

#include "parallel_for.h"

namespace repose {
namespace {

// Slack on barycentric coordinates so voxel centres on shared faces are covered by at least one tet
// despite rounding (no cracks); the first tet (lowest index) to claim a voxel wins.
constexpr double kBaryEps = 1e-7;
// k-slices per slab: slabs are the unit of parallel work, each written by one thread only.
constexpr int kSlabSlices = 16;

void validate(const ImageGrid& restGrid, std::size_t restSize, const Points& restNodes,
              const Points& posedNodes, const Tets& tets, const ImageGrid& outGrid) {
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
}

// Per-tet affine maps in index space: barycentric rows (λ_a = g_a · x + c_a, x in output index space)
// and the rest point r = A x + b (rest index space).
struct TetSetup {
  Eigen::Matrix<double, 4, 4> bary;  // row a: (g_a.x, g_a.y, g_a.z, c_a)
  Eigen::Matrix3d A;
  Eigen::Vector3d b;
  double lo[3], hi[3];               // bounding box in output index space
  double vy[4], vz[4];               // node j, k coordinates (cross-sections)
  double invSlope[4];                // 1 / dλ_a/di (0 when λ_a is constant along rows)
  double edgeDyDz[6];                // dy/dz along each edge (0 for edges parallel to the k planes)
};

constexpr int kEdges[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};

bool setupTet(const std::vector<Eigen::Vector3d>& P, const std::vector<Eigen::Vector3d>& R, const Tets& tets,
              std::size_t t, TetSetup& s) {
  const Eigen::Vector3d& p0 = P[tets(t, 0)];
  Eigen::Matrix3d M;
  M.col(0) = P[tets(t, 1)] - p0;
  M.col(1) = P[tets(t, 2)] - p0;
  M.col(2) = P[tets(t, 3)] - p0;
  const double det = M.determinant();
  if (!(std::abs(det) > 0)) return false;
  const Eigen::Matrix3d Minv = M.inverse();
  // λ_{1..3} = Minv (x - p0), λ0 = 1 - Σ.
  for (int a = 0; a < 3; ++a) {
    s.bary.block<1, 3>(a + 1, 0) = Minv.row(a);
    s.bary(a + 1, 3) = -Minv.row(a).dot(p0);
  }
  s.bary.row(0) = -(s.bary.row(1) + s.bary.row(2) + s.bary.row(3));
  s.bary(0, 3) += 1.0;
  const Eigen::Vector3d& r0 = R[tets(t, 0)];
  Eigen::Matrix3d E;
  E.col(0) = R[tets(t, 1)] - r0;
  E.col(1) = R[tets(t, 2)] - r0;
  E.col(2) = R[tets(t, 3)] - r0;
  s.A = E * Minv;
  s.b = r0 - s.A * p0;
  for (int a = 0; a < 4; ++a) {
    s.vy[a] = P[tets(t, a)].y();
    s.vz[a] = P[tets(t, a)].z();
    s.invSlope[a] = std::abs(s.bary(a, 0)) > 1e-300 ? 1.0 / s.bary(a, 0) : 0.0;
  }
  for (int e = 0; e < 6; ++e) {
    const double dz = s.vz[kEdges[e][1]] - s.vz[kEdges[e][0]];
    s.edgeDyDz[e] = std::abs(dz) > 1e-12 ? (s.vy[kEdges[e][1]] - s.vy[kEdges[e][0]]) / dz : 0.0;
  }
  for (int a = 0; a < 3; ++a) {
    s.lo[a] = s.hi[a] = p0[a];
    for (int c = 1; c < 4; ++c) {
      s.lo[a] = std::min(s.lo[a], P[tets(t, c)][a]);
      s.hi[a] = std::max(s.hi[a], P[tets(t, c)][a]);
    }
  }
  return true;
}

// Scanline rasterizer shared by labels and intensities (the output is pre-filled with background). Sampler: void(const Eigen::Vector3d& restIndex,
// std::size_t outIndex) writes one voxel.
template <class Sampler>
void rasterize(const ImageGrid& restGrid, const Points& restNodes, const Points& posedNodes, const Tets& tets,
               const ImageGrid& outGrid, PullResampleReport* report, const Sampler& sample) {
  const auto start = std::chrono::steady_clock::now();
  const std::size_t nV = std::size_t(posedNodes.rows());
  const std::size_t nT = std::size_t(tets.rows());
  const int nx = outGrid.dims[0], ny = outGrid.dims[1], nz = outGrid.dims[2];

  // Node positions in index spaces (posed: output grid; rest: rest grid).
  std::vector<Eigen::Vector3d> P(nV), R(nV);
  parallelFor(nV, [&](std::size_t b, std::size_t e) {
    for (std::size_t v = b; v < e; ++v) {
      P[v] = outGrid.physicalToIndex(posedNodes.row(v).transpose());
      R[v] = restGrid.physicalToIndex(restNodes.row(v).transpose());
    }
  });

  // Orientation in index space flips with a left-handed direction matrix.
  const double orient = outGrid.direction.determinant() < 0 ? -1.0 : 1.0;
  const int nSlabs = (nz + kSlabSlices - 1) / kSlabSlices;
  // k-range of each tet -> slab range; inverted/degenerate tets get an empty range.
  std::vector<int> slabLo(nT), slabHi(nT);
  std::atomic<std::size_t> inverted{0};
  parallelFor(nT, [&](std::size_t b, std::size_t e) {
    std::size_t localInverted = 0;
    for (std::size_t t = b; t < e; ++t) {
      const Eigen::Vector3d& p0 = P[tets(t, 0)];
      Eigen::Matrix3d M;
      M.col(0) = P[tets(t, 1)] - p0;
      M.col(1) = P[tets(t, 2)] - p0;
      M.col(2) = P[tets(t, 3)] - p0;
      const double det = orient * M.determinant();
      const double scale = M.colwise().norm().prod();
      slabLo[t] = 0;
      slabHi[t] = -1;
      if (!(det > 1e-12 * scale)) {
        ++localInverted;
        continue;
      }
      double zlo = p0.z(), zhi = p0.z();
      for (int c = 1; c < 4; ++c) {
        zlo = std::min(zlo, P[tets(t, c)].z());
        zhi = std::max(zhi, P[tets(t, c)].z());
      }
      const double kLo = std::max(0.0, std::ceil(zlo - 1e-6));
      const double kHi = std::min(double(nz - 1), std::floor(zhi + 1e-6));
      if (kLo > kHi) continue;
      slabLo[t] = int(kLo) / kSlabSlices;
      slabHi[t] = int(kHi) / kSlabSlices;
    }
    inverted += localInverted;
  }, 4096);

  // Bucket tets per slab (CSR), in increasing tet order so "first writer wins" is deterministic.
  std::vector<std::size_t> offset(std::size_t(nSlabs) + 1, 0);
  for (std::size_t t = 0; t < nT; ++t)
    for (int s = slabLo[t]; s <= slabHi[t]; ++s) ++offset[std::size_t(s) + 1];
  for (int s = 0; s < nSlabs; ++s) offset[s + 1] += offset[s];
  std::vector<int> bucket(offset.back());
  {
    std::vector<std::size_t> fill(offset.begin(), offset.end() - 1);
    for (std::size_t t = 0; t < nT; ++t)
      for (int s = slabLo[t]; s <= slabHi[t]; ++s) bucket[fill[s]++] = int(t);
  }
  slabLo.clear();
  slabLo.shrink_to_fit();
  slabHi.clear();
  slabHi.shrink_to_fit();

  std::atomic<std::size_t> covered{0};
  const std::size_t sliceSize = std::size_t(nx) * ny;
  // Interleave slabs so a static two-way split still gets both ends of the body.
  parallelFor(std::size_t(nSlabs), [&](std::size_t b, std::size_t e) {
    std::vector<std::uint8_t> written(sliceSize * kSlabSlices);
    TetSetup st;
    std::size_t localCovered = 0;
    for (std::size_t w = b; w < e; ++w) {
      const std::size_t half = (std::size_t(nSlabs) + 1) / 2;
      const int s = w < half ? int(2 * w) : int(2 * (w - half) + 1);
      const int k0 = s * kSlabSlices, k1 = std::min(nz - 1, k0 + kSlabSlices - 1);
      std::fill(written.begin(), written.end(), 0);
      for (std::size_t q = offset[s]; q < offset[s + 1]; ++q) {
        const std::size_t t = std::size_t(bucket[q]);
        if (!setupTet(P, R, tets, t, st)) continue;
        const int kb = std::max(k0, int(std::ceil(st.lo[2] - 1e-6)));
        const int ke = std::min(k1, int(std::floor(st.hi[2] + 1e-6)));
        const double ib = std::max(0.0, std::ceil(st.lo[0] - 1e-6));
        const double ie = std::min(double(nx - 1), std::floor(st.hi[0] + 1e-6));
        if (ib > ie) continue;
        const Eigen::Vector3d stepI = st.A.col(0);
        for (int k = kb; k <= ke; ++k) {
          // j-range of the cross-section at plane k (edge crossings, clamped), padded: rows it adds
          // needlessly are rejected below, and the padding keeps rounding from dropping a row.
          double ylo = 1e300, yhi = -1e300;
          for (int e = 0; e < 6; ++e) {
            const int a = kEdges[e][0], b = kEdges[e][1];
            const double za = st.vz[a], zb = st.vz[b];
            if (k < std::min(za, zb) - 1e-6 || k > std::max(za, zb) + 1e-6) continue;
            if (st.edgeDyDz[e] != 0.0 || std::abs(zb - za) > 1e-12) {
              // Crossing point, clamped to the edge.
              const double zc = std::min(std::max(double(k), std::min(za, zb)), std::max(za, zb));
              const double y = st.vy[a] + (zc - za) * st.edgeDyDz[e];
              ylo = std::min(ylo, y);
              yhi = std::max(yhi, y);
            } else {
              ylo = std::min({ylo, st.vy[a], st.vy[b]});
              yhi = std::max({yhi, st.vy[a], st.vy[b]});
            }
          }
          const int jb = std::max(0, int(std::ceil(ylo - 1e-4)));
          const int je = std::min(ny - 1, int(std::floor(yhi + 1e-4)));
          double baseK[4];
          for (int a = 0; a < 4; ++a) baseK[a] = st.bary(a, 2) * k + st.bary(a, 3) + kBaryEps;
          for (int j = jb; j <= je; ++j) {
            // Each λ_a is linear in i: λ_a = slope * i + base; intersect the half-lines λ_a >= -eps.
            double lo = ib, hi = ie;
            for (int a = 0; a < 4; ++a) {
              const double base = baseK[a] + st.bary(a, 1) * j;
              const double inv = st.invSlope[a];
              if (inv > 0) {
                lo = std::max(lo, std::ceil(-base * inv));
              } else if (inv < 0) {
                hi = std::min(hi, std::floor(-base * inv));
              } else if (base < 0) {
                hi = lo - 1;
              }
            }
            if (lo > hi) continue;
            const int i0 = int(lo), i1 = int(hi);
            Eigen::Vector3d r = st.A * Eigen::Vector3d(i0, j, k) + st.b;
            std::uint8_t* wrow = written.data() + std::size_t(k - k0) * sliceSize + std::size_t(j) * nx;
            const std::size_t rowBase = std::size_t(k) * sliceSize + std::size_t(j) * nx;
            for (int i = i0; i <= i1; ++i, r += stepI) {
              if (wrow[i]) continue;
              wrow[i] = 1;
              ++localCovered;
              sample(r, rowBase + i);
            }
          }
        }
      }
    }
    covered += localCovered;
  }, 1);

  if (report) {
    report->outputVoxels = outGrid.voxelCount();
    report->coveredVoxels = covered.load();
    report->invertedTets = inverted.load();
    report->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
}

}  // namespace

LabelVolume resampleLabelsPull(const LabelVolume& rest, const Points& restNodes, const Points& posedNodes,
                               const Tets& tets, const ImageGrid& outGrid, std::int32_t background,
                               PullResampleReport* report) {
  validate(rest.grid, rest.data.size(), restNodes, posedNodes, tets, outGrid);
  LabelVolume out;
  out.grid = outGrid;
  const int dx = rest.grid.dims[0], dy = rest.grid.dims[1], dz = rest.grid.dims[2];
  const std::int32_t* src = rest.data.data();
  std::int32_t* dst = nullptr;
  // Nearest voxel: the voxel whose footprint [c-0.5, c+0.5) holds the rest point; outside = background.
  auto sample = [&](const Eigen::Vector3d& r, std::size_t o) {
    if (r.x() >= -0.5 && r.y() >= -0.5 && r.z() >= -0.5 && r.x() < dx - 0.5 && r.y() < dy - 0.5 &&
        r.z() < dz - 0.5) {
      const int i = int(r.x() + 0.5), j = int(r.y() + 0.5), k = int(r.z() + 0.5);
      dst[o] = src[(std::size_t(k) * dy + j) * dx + i];
    }
  };
  // Allocate first so dst is valid for all threads.
  out.data.assign(outGrid.voxelCount(), background);
  dst = out.data.data();
  rasterize(rest.grid, restNodes, posedNodes, tets, outGrid, report, sample);
  return out;
}

IntensityVolume resampleIntensityPull(const IntensityVolume& rest, const Points& restNodes,
                                      const Points& posedNodes, const Tets& tets, const ImageGrid& outGrid,
                                      float background, PullResampleReport* report) {
  validate(rest.grid, rest.data.size(), restNodes, posedNodes, tets, outGrid);
  IntensityVolume out;
  out.grid = outGrid;
  const int dx = rest.grid.dims[0], dy = rest.grid.dims[1], dz = rest.grid.dims[2];
  const float* src = rest.data.data();
  out.data.assign(outGrid.voxelCount(), background);
  float* dst = out.data.data();
  const std::size_t sy = std::size_t(dx), sz = std::size_t(dx) * dy;
  // Trilinear inside the voxel footprints of the rest grid (edge voxels replicated within half a voxel).
  auto sample = [&](const Eigen::Vector3d& r, std::size_t o) {
    if (!(r.x() >= -0.5 && r.y() >= -0.5 && r.z() >= -0.5 && r.x() < dx - 0.5 && r.y() < dy - 0.5 &&
          r.z() < dz - 0.5))
      return;
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
    const std::size_t base = idx[2] * sz + idx[1] * sy + idx[0];
    const std::size_t ox = dx > 1 ? 1 : 0, oy = dy > 1 ? sy : 0, oz = dz > 1 ? sz : 0;
    const double c00 = src[base] + f[0] * (src[base + ox] - src[base]);
    const double c10 = src[base + oy] + f[0] * (src[base + oy + ox] - src[base + oy]);
    const double c01 = src[base + oz] + f[0] * (src[base + oz + ox] - src[base + oz]);
    const double c11 = src[base + oz + oy] + f[0] * (src[base + oz + oy + ox] - src[base + oz + oy]);
    const double c0 = c00 + f[1] * (c10 - c00);
    const double c1 = c01 + f[1] * (c11 - c01);
    dst[o] = float(c0 + f[2] * (c1 - c0));
  };
  rasterize(rest.grid, restNodes, posedNodes, tets, outGrid, report, sample);
  return out;
}

}  // namespace repose
