#ifndef REPOSE_PULL_WORK_BOX_H
#define REPOSE_PULL_WORK_BOX_H
// Internal to the pull resampler (resample_pull.cpp): the box of output voxels it works on, their
// values and coverage marks, and its split into z-ranges written in parallel.

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <vector>

#include "parallel_for.h"

namespace repose {
namespace pull {

// Per-voxel coverage marks.
constexpr std::uint8_t kEmpty = 0, kCovered = 1, kExtrapolated = 2, kFilled = 4;
// Passes of the pinhole fill (each reads one 6-step further).
constexpr int kFillPasses = 4;

// Output voxels worked on: an index box of the output grid (bounds inclusive), stored i fastest.
struct Box {
  int lo[3], hi[3], n[3];
  Box(const int l[3], const int h[3]) {
    for (int a = 0; a < 3; ++a) {
      lo[a] = l[a];
      hi[a] = h[a];
      n[a] = h[a] - l[a] + 1;
    }
  }
  std::size_t count() const { return std::size_t(n[0]) * n[1] * n[2]; }
  std::size_t rows() const { return std::size_t(n[1]) * n[2]; }
  std::size_t index(int i, int j, int k) const {
    return (std::size_t(k - lo[2]) * n[1] + std::size_t(j - lo[1])) * n[0] + std::size_t(i - lo[0]);
  }
  bool same(const Box& o) const {
    for (int a = 0; a < 3; ++a)
      if (lo[a] != o.lo[a] || hi[a] != o.hi[a]) return false;
    return true;
  }
};

// A voxel (index in the work box, or in its z-range) and a tet it is covered by or extrapolated from.
template <class Index>
struct VoxelTet {
  Index v;
  std::uint32_t t;
};

// The work box W (the requested box `voi`, grown by `pad` voxels within the grid of `dims`), its values
// `out` (dst itself when W is voi) and marks, all background / kEmpty at first, and its z-ranges.
template <class T>
struct WorkBox {
  Box voi, W;
  int nx, ny, nz;
  std::size_t sliceSize, nW;
  bool direct;  // W == voi: values are written straight into dst
  T* dst;  // voi's voxels, i fastest
  std::vector<T> buffer;
  T* out;
  std::unique_ptr<std::uint8_t[]> marks;
  // Z-ranges: at most 16 runs of whole slices; rangeBase[g] is the first work-box index of range g
  // (every range holds at least one slice, and fewer than 2^32 voxels).
  int nRanges;
  std::vector<std::uint8_t> rangeOf;
  std::vector<std::size_t> rangeBase;

  WorkBox(const Box& voi_, const int dims[3], int pad, T* dst_, T background)
      : voi(voi_), W(grown(voi_, dims, pad)), dst(dst_) {
    nx = W.n[0], ny = W.n[1], nz = W.n[2];
    sliceSize = std::size_t(nx) * ny;
    nW = W.count();
    direct = W.same(voi);
    buffer.resize(direct ? 0 : nW);
    out = direct ? dst_ : buffer.data();
    // Background everywhere (first touch in parallel: output buffers are hundreds of MB).
    marks.reset(new std::uint8_t[nW]);
    parallelFor(nW, [&](std::size_t b, std::size_t e) {
      std::fill(out + b, out + e, background);
      std::memset(marks.get() + b, kEmpty, e - b);
    }, 1 << 18);
  }

  // Splits the slices into z-ranges; throws if a range exceeds 32-bit indices.
  void splitRanges() {
    nRanges = std::min(nz, 16);
    rangeOf.resize(static_cast<std::size_t>(nz));
    for (int k = 0; k < nz; ++k) rangeOf[std::size_t(k)] = std::uint8_t(std::size_t(k) * nRanges / nz);
    rangeBase.assign(std::size_t(nRanges) + 1, nW);
    for (int k = nz; k-- > 0;) rangeBase[rangeOf[std::size_t(k)]] = std::size_t(k) * sliceSize;
    for (int g = 0; g < nRanges; ++g)
      if (rangeBase[std::size_t(g) + 1] - rangeBase[std::size_t(g)] > 0xffffffffu)
        throw std::length_error("pull resample: output grid too large (a sixteenth of it exceeds 2^32 voxels)");
  }

  // (i, j, k) of work-box index v, relative to W.lo.
  void ijk(std::size_t v, int& i, int& j, int& k) const {
    const std::size_t row = v / std::size_t(nx);
    i = int(v - row * std::size_t(nx));
    j = int(row % std::size_t(ny));
    k = int(row / std::size_t(ny));
  }

 private:
  static Box grown(const Box& voi, const int dims[3], int pad) {
    int lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::max(0, voi.lo[a] - pad);
      hi[a] = std::min(dims[a] - 1, voi.hi[a] + pad);
    }
    return Box(lo, hi);
  }
};

}  // namespace pull
}  // namespace repose

#endif
