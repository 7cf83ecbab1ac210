#ifndef REPOSE_PULL_EXTRAPOLATION_H
#define REPOSE_PULL_EXTRAPOLATION_H
// Internal to the pull resampler (resample_pull.cpp): the posed mesh's outside grown on the voxel grid,
// layer by layer, each voxel through the affine map of a tet of its written neighbour.

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "parallel_for.h"
#include "point_tet_distance.h"
#include "pull_work_box.h"
#include "tet_mesh.h"

namespace repose {
namespace pull {

using Vertices = double[4][3];

// The tet mesh in index space: node positions P (output index space) and R (rest index space), three
// floats per node; orient is -1 when the output's direction matrix is left-handed (it flips the sign of
// index-space volumes).
struct IndexSpaceMesh {
  const std::vector<float>& P;
  const std::vector<float>& R;
  const Tets& tets;
  double orient;
  Eigen::Vector3d invSpacing;   // of the output grid (1/mm)
  Eigen::Vector3d restSpacing;  // of the rest grid (mm)
};

inline void loadVertices(const std::vector<float>& X, const Tets& tets, std::size_t t, Vertices& p) {
  for (int a = 0; a < 4; ++a) {
    const std::size_t v = std::size_t(tets(t, a)) * 3;
    for (int m = 0; m < 3; ++m) p[a][m] = X[v + m];
  }
}

// Edges e_q = p_{q+1} - p_0 of a tet and n_q = e_{q+1} x e_{q+2} (the rows of the inverse of the edge
// matrix times its determinant); returns the determinant e_0 . n_0.
inline double edgeCofactors(const Vertices& p, double e[3][3], double n[3][3]) {
  for (int q = 0; q < 3; ++q)
    for (int m = 0; m < 3; ++m) e[q][m] = p[q + 1][m] - p[0][m];
  for (int q = 0; q < 3; ++q) {
    const double* u = e[(q + 1) % 3];
    const double* w = e[(q + 2) % 3];
    n[q][0] = u[1] * w[2] - u[2] * w[1];
    n[q][1] = u[2] * w[0] - u[0] * w[2];
    n[q][2] = u[0] * w[1] - u[1] * w[0];
  }
  return e[0][0] * n[0][0] + e[0][1] * n[0][1] + e[0][2] * n[0][2];
}

// The posed tet t's barycentric coordinates at x (output index space) give `distance`, how far (mm) x
// lies outside the tet (the largest of -λ_a times the tet's height over face a; 0 inside), and r, the
// rest index of x under the tet's affine map. False for a flat or inverted tet.
inline bool tetExtension(const IndexSpaceMesh& mesh, std::size_t t, const double x[3], double& distance,
                         double r[3]) {
  const Tets& tets = mesh.tets;
  Vertices p;
  loadVertices(mesh.P, tets, t, p);
  double e[3][3], n[3][3];
  const double det = edgeCofactors(p, e, n);
  if (!(mesh.orient * det > 0)) return false;
  const double d[3] = {x[0] - p[0][0], x[1] - p[0][1], x[2] - p[0][2]};
  double lambda[4], g[4][3];
  lambda[0] = 1.0;
  for (int m = 0; m < 3; ++m) g[0][m] = 0;
  for (int q = 0; q < 3; ++q) {
    lambda[q + 1] = (n[q][0] * d[0] + n[q][1] * d[1] + n[q][2] * d[2]) / det;
    lambda[0] -= lambda[q + 1];
    for (int m = 0; m < 3; ++m) {
      g[q + 1][m] = n[q][m] / det;
      g[0][m] -= g[q + 1][m];
    }
  }
  distance = 0;
  const Eigen::Vector3d& invSpacing = mesh.invSpacing;
  for (int a = 0; a < 4; ++a)
    if (lambda[a] < 0) {
      // |physical gradient of λ_a| = 1 / height (the direction matrix is orthonormal).
      const double gx = g[a][0] * invSpacing[0], gy = g[a][1] * invSpacing[1], gz = g[a][2] * invSpacing[2];
      distance = std::max(distance, -lambda[a] / std::sqrt(gx * gx + gy * gy + gz * gz));
    }
  for (int m = 0; m < 3; ++m) r[m] = 0;
  for (int a = 0; a < 4; ++a) {
    const std::size_t v = std::size_t(tets(t, a)) * 3;
    for (int m = 0; m < 3; ++m) r[m] += lambda[a] * double(mesh.R[v + m]);
  }
  return true;
}

using Seed = VoxelTet<std::size_t>;

// The mesh stops short of the body's outer voxel layer (the mask is peeled before meshing), so the
// outside of the posed mesh is grown on the voxel grid, `layers` layers of 6-neighbours: a voxel of the
// next layer is extrapolated from the tets of its neighbours in the current one (`layer` at first: the
// covered voxels next to empty ones, each with the lowest-numbered tet touching the mesh boundary that
// covers it, sorted by voxel); of those, the tet it lies least far outside of and whose sample the
// kernel accepts (labels never write background) wins. Each extrapolated voxel is thus connected to
// the posed body, and the work is proportional to the voxels written.
template <class T, class Kernel>
void extrapolateLayers(WorkBox<T>& w, std::vector<Seed> layer, int layers, const Kernel& kernel,
                       const IndexSpaceMesh& mesh) {
  const int nx = w.nx, ny = w.ny, nz = w.nz;
  const std::size_t sliceSize = w.sliceSize;
  std::uint8_t* marks = w.marks.get();
  const Tets& tets = mesh.tets;
  std::vector<Seed> candidates, merged, streams[6];
  std::vector<std::size_t> groups;
  std::vector<std::uint32_t> bestTet;
  std::vector<T> bestValue;
  for (int step = 0; step < layers && !layer.empty(); ++step) {
    // Candidates (voxel, tet) sorted by voxel then tet: six sorted lists, one per neighbour offset,
    // merged.
    for (auto& S : streams) S.clear();
    for (const Seed& s : layer) {
      int i, j, k;
      w.ijk(s.v, i, j, k);
      const bool ok[6] = {k > 0, j > 0, i > 0, i + 1 < nx, j + 1 < ny, k + 1 < nz};
      const std::ptrdiff_t off[6] = {-std::ptrdiff_t(sliceSize), -std::ptrdiff_t(nx), -1, 1, std::ptrdiff_t(nx),
                                     std::ptrdiff_t(sliceSize)};
      for (int q = 0; q < 6; ++q)
        if (ok[q]) {
          const std::size_t n = std::size_t(std::ptrdiff_t(s.v) + off[q]);
          if (marks[n] == kEmpty) streams[q].push_back({n, s.t});
        }
    }
    auto less = [](const Seed& x, const Seed& y) { return x.v != y.v ? x.v < y.v : x.t < y.t; };
    candidates = streams[0];
    for (int q = 1; q < 6; ++q) {
      merged.resize(candidates.size() + streams[q].size());
      std::merge(candidates.begin(), candidates.end(), streams[q].begin(), streams[q].end(), merged.begin(), less);
      candidates.swap(merged);
    }
    groups.clear();
    for (std::size_t q = 0; q < candidates.size(); ++q)
      if (q == 0 || candidates[q].v != candidates[q - 1].v) groups.push_back(q);
    const std::size_t nGroups = groups.size();
    groups.push_back(candidates.size());
    bestTet.assign(nGroups, std::numeric_limits<std::uint32_t>::max());
    bestValue.resize(nGroups);
    parallelFor(nGroups, [&](std::size_t gb, std::size_t ge) {
      for (std::size_t q = gb; q < ge; ++q) {
        int i, j, k;
        w.ijk(candidates[groups[q]].v, i, j, k);
        const double x[3] = {double(w.W.lo[0] + i), double(w.W.lo[1] + j), double(w.W.lo[2] + k)};
        double best = std::numeric_limits<double>::infinity();  // the layers bound the reach
        for (std::size_t c = groups[q]; c < groups[q + 1]; ++c) {
          const std::uint32_t t = candidates[c].t;
          if (c > groups[q] && t == candidates[c - 1].t) continue;
          double dist, r[3];
          T value;
          if (!tetExtension(mesh, t, x, dist, r) || !(dist <= best)) continue;
          if (dist == best && bestTet[q] != std::numeric_limits<std::uint32_t>::max()) continue;
          auto restDistanceToTet = [&] {
            const Eigen::Vector3d& restSpacing = mesh.restSpacing;
            Eigen::Vector3d v[4];
            for (int a = 0; a < 4; ++a)
              for (int m = 0; m < 3; ++m) v[a][m] = double(mesh.R[std::size_t(tets(t, a)) * 3 + m]) * restSpacing[m];
            return pointTetDistance(Eigen::Vector3d(r[0], r[1], r[2]).cwiseProduct(restSpacing), v[0], v[1], v[2], v[3]);
          };
          if (!kernel.extendAt(r, dist, restDistanceToTet, value)) continue;
          best = dist;
          bestTet[q] = t;
          bestValue[q] = value;
        }
      }
    }, 256);
    layer.clear();
    for (std::size_t q = 0; q < nGroups; ++q)
      if (bestTet[q] != std::numeric_limits<std::uint32_t>::max()) {
        const std::size_t v = candidates[groups[q]].v;
        w.out[v] = bestValue[q];
        marks[v] = kExtrapolated;
        layer.push_back({v, bestTet[q]});
      }
  }
}

}  // namespace pull
}  // namespace repose

#endif
