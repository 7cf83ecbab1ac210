#include "distance_transform.h"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "parallel_for.h"

namespace repose {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// One line of the squared transform: f holds the squared distances so far (inf where unknown),
// sampled every `h` mm; on return d holds min_q (f[q] + (h (p - q))^2). v, z are scratch.
void envelope1d(const std::vector<double>& f, double h, std::vector<double>& d, std::vector<int>& v,
                std::vector<double>& z) {
  const int n = int(f.size());
  int k = -1;  // index of the rightmost parabola in the envelope
  for (int q = 0; q < n; ++q) {
    if (f[q] == kInf) continue;
    const double fq = f[q] + (h * q) * (h * q);
    while (k >= 0) {
      const int r = v[k];
      const double s = (fq - (f[r] + (h * r) * (h * r))) / (2 * h * h * (q - r));  // in index units
      if (s <= z[k]) {
        --k;
        continue;
      }
      v[++k] = q;
      z[k] = s;
      break;
    }
    if (k < 0) {
      v[0] = q;
      z[0] = -kInf;
      k = 0;
    }
  }
  if (k < 0) {
    for (int p = 0; p < n; ++p) d[p] = kInf;
    return;
  }
  int j = 0;
  for (int p = 0; p < n; ++p) {
    while (j < k && z[j + 1] < p) ++j;
    const double dx = h * (p - v[j]);
    d[p] = f[v[j]] + dx * dx;
  }
}

}  // namespace

std::vector<float> distanceToFeatures(const MaskVolume& features) {
  const ImageGrid& g = features.grid;
  if (g.dims[0] <= 0 || g.dims[1] <= 0 || g.dims[2] <= 0 || features.data.size() != g.voxelCount())
    throw std::invalid_argument("distance transform: the mask's data (" + std::to_string(features.data.size()) +
                                " values) does not match its grid");
  const int nx = g.dims[0], ny = g.dims[1], nz = g.dims[2];
  // Squared distances, kept in float (4 bytes a voxel on whole-body grids; 24 bits are ample).
  std::vector<float> sq(g.voxelCount());
  for (std::size_t p = 0; p < sq.size(); ++p) sq[p] = features.data[p] ? 0.f : float(kInf);

  // One pass per axis over every line along it; `stride` steps along the line.
  auto pass = [&](int n, double h, std::size_t lines, auto lineStart, std::size_t stride) {
    parallelFor(lines, [&](std::size_t b, std::size_t e) {
      std::vector<double> f(n), d(n), z(n + 1);
      std::vector<int> v(n);
      for (std::size_t line = b; line < e; ++line) {
        const std::size_t start = lineStart(line);
        for (int p = 0; p < n; ++p) f[p] = sq[start + p * stride];
        envelope1d(f, h, d, v, z);
        for (int p = 0; p < n; ++p) sq[start + p * stride] = float(d[p]);
      }
    }, 64);
  };
  const std::size_t sy = std::size_t(nx), sz = std::size_t(nx) * ny;
  pass(nx, g.spacing[0], std::size_t(ny) * nz, [&](std::size_t l) { return l * sy; }, 1);
  pass(ny, g.spacing[1], std::size_t(nx) * nz, [&](std::size_t l) { return (l / nx) * sz + l % nx; }, sy);
  pass(nz, g.spacing[2], sz, [&](std::size_t l) { return l; }, sz);

  parallelFor(sq.size(), [&](std::size_t b, std::size_t e) {
    for (std::size_t p = b; p < e; ++p) sq[p] = std::sqrt(sq[p]);  // sqrt(inf) = inf
  }, 1 << 16);
  return sq;
}

}  // namespace repose
