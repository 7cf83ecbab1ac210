#ifndef REPOSE_PULL_PINHOLES_H
#define REPOSE_PULL_PINHOLES_H
// Internal to the pull resampler (resample_pull.cpp): the rows of the work box that hold written
// voxels, and the pinhole fill of the voxels the extrapolation left empty between written ones.

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <cstring>
#include <utility>
#include <vector>

#include "parallel_for.h"
#include "pull_work_box.h"

namespace repose {
namespace pull {

// First and last non-empty mark of a row ([n, -1] if none), by 8-byte words.
inline void rowSpan(const std::uint8_t* m, int n, int& first, int& last) {
  first = n;
  last = -1;
  int i = 0;
  for (; i + 8 <= n; i += 8) {
    std::uint64_t w;
    std::memcpy(&w, m + i, 8);
    if (w) break;
  }
  for (; i < n; ++i)
    if (m[i]) break;
  if (i >= n) return;
  first = i;
  int e = n;
  for (; e - 8 >= first; e -= 8) {
    std::uint64_t w;
    std::memcpy(&w, m + e - 8, 8);
    if (w) break;
  }
  for (; e > first; --e)
    if (m[e - 1]) break;
  last = e - 1;
}

// Rows of the work box holding written voxels: [first, last] of each (first > last if none), row
// = k * ny + j.
struct RowSpans {
  std::vector<int> first, last;

  template <class T>
  explicit RowSpans(const WorkBox<T>& w) : first(w.W.rows()), last(w.W.rows()) {
    parallelFor(w.W.rows(), [&](std::size_t b, std::size_t e) {
      for (std::size_t row = b; row < e; ++row) rowSpan(w.marks.get() + row * w.nx, w.nx, first[row], last[row]);
    }, 256);
  }
};

// Voxels outside the posed mesh that the extrapolation left empty (or background) although at least 5
// of their 6 neighbours were written with tissue: gaps where the rest point of every candidate tet fell
// on background or outside the rest grid, e.g. in a crease where two skin surfaces of the posed body
// meet. They are filled from those neighbours (combine: the most common label, or the mean intensity),
// so the posed skin has no pinholes. Voxels inside the posed mesh are never touched. Such a voxel has
// at least 3 written neighbours in the 4 adjacent rows, so only rows next to written rows are visited.
// Repeated while it fills anything, kFillPasses times at most: a voxel filled in one pass counts as
// written in the next (within a pass marks do not change, so the result does not depend on the thread
// count). Returns how many of the filled voxels lie in w.voi.
template <class T, class Combine>
std::size_t fillPinholes(WorkBox<T>& w, const RowSpans& spans, T background, Combine& combine) {
  const int nx = w.nx, ny = w.ny, nz = w.nz;
  const std::size_t sliceSize = w.sliceSize;
  T* out = w.out;
  std::uint8_t* marks = w.marks.get();
  const std::vector<int>& first = spans.first;
  const std::vector<int>& last = spans.last;
  std::atomic<std::size_t> filledInVoi{0};
  auto hasSpan = [&](int j, int k) {
    if (j < 0 || j >= ny || k < 0 || k >= nz) return false;
    const std::size_t row = std::size_t(k) * ny + std::size_t(j);
    return first[row] <= last[row];
  };
  // The 4 rows adjacent to row (j, k): how many hold written voxels, and the union [ib, ie] of
  // their spans.
  auto adjacentSpans = [&](int j, int k, int& ib, int& ie) {
    const int nbr[4][2] = {{j - 1, k}, {j + 1, k}, {j, k - 1}, {j, k + 1}};
    int count = 0;
    ib = nx, ie = -1;
    for (const auto& jk : nbr)
      if (hasSpan(jk[0], jk[1])) {
        ++count;
        const std::size_t row = std::size_t(jk[1]) * ny + std::size_t(jk[0]);
        ib = std::min(ib, first[row]);
        ie = std::max(ie, last[row]);
      }
    return count;
  };
  // The row test for voxel (i, j, k): at least 3 of the 4 adjacent rows hold written voxels and
  // i lies within their spans.
  auto inSpans = [&](int i, int j, int k) {
    int ib, ie;
    return adjacentSpans(j, k, ib, ie) >= 3 && i >= ib && i <= ie;
  };
  const Box& W = w.W;
  const Box& voi = w.voi;
  // Voxel v = (i, j, k) filled in this pass: appended to `to` (written after the pass).
  auto tryFill = [&](int i, int j, int k, std::vector<std::pair<std::size_t, T>>& to, std::size_t& local) {
    const std::size_t v = std::size_t(k) * sliceSize + std::size_t(j) * nx + std::size_t(i);
    // Also an extrapolated intensity voxel that equals the background value.
    if (marks[v] != kEmpty && !(marks[v] == kExtrapolated && out[v] == background)) return;
    T values[6];
    int n = 0;
    auto take = [&](bool ok, std::size_t u) {
      if (ok && marks[u] != kEmpty && !(out[u] == background)) values[n++] = out[u];
    };
    take(i > 0, v - 1);
    take(i + 1 < nx, v + 1);
    take(j > 0, v - std::size_t(nx));
    take(j + 1 < ny, v + std::size_t(nx));
    take(k > 0, v - sliceSize);
    take(k + 1 < nz, v + sliceSize);
    if (n < 5) return;
    to.emplace_back(v, combine(values, n));
    const int gi = i + W.lo[0], gj = j + W.lo[1], gk = k + W.lo[2];
    local += gi >= voi.lo[0] && gi <= voi.hi[0] && gj >= voi.lo[1] && gj <= voi.hi[1] && gk >= voi.lo[2] &&
             gk <= voi.hi[2];
  };
  // The first pass visits all rows next to written rows; later passes only the neighbours of the
  // voxels the previous pass filled (no other voxel's neighbourhood changed).
  std::vector<std::vector<std::pair<std::size_t, T>>> filled(static_cast<std::size_t>(nz));
  parallelFor(std::size_t(nz), [&](std::size_t kb, std::size_t ke) {
    std::size_t local = 0;
    for (int k = int(kb); k < int(ke); ++k)
      for (int j = 0; j < ny; ++j) {
        int ib, ie;
        if (adjacentSpans(j, k, ib, ie) < 3) continue;
        for (int i = ib; i <= ie; ++i) tryFill(i, j, k, filled[std::size_t(k)], local);
      }
    filledInVoi += local;
  }, 1);
  std::vector<std::size_t> prev;
  for (int pass = 0; pass < kFillPasses; ++pass) {
    prev.clear();
    for (auto& f : filled) {
      for (const auto& [v, value] : f) {
        out[v] = value;
        marks[v] = kFilled;
        prev.push_back(v);
      }
      f.clear();
    }
    if (prev.empty() || pass == kFillPasses - 1) break;
    std::vector<std::size_t> next;
    next.reserve(6 * prev.size());
    for (const std::size_t v : prev) {
      int i, j, k;
      w.ijk(v, i, j, k);
      if (i > 0) next.push_back(v - 1);
      if (i + 1 < nx) next.push_back(v + 1);
      if (j > 0) next.push_back(v - std::size_t(nx));
      if (j + 1 < ny) next.push_back(v + std::size_t(nx));
      if (k > 0) next.push_back(v - sliceSize);
      if (k + 1 < nz) next.push_back(v + sliceSize);
    }
    std::sort(next.begin(), next.end());
    next.erase(std::unique(next.begin(), next.end()), next.end());
    // Candidates in slice order, so `filled` stays per slice.
    std::size_t local = 0;
    for (const std::size_t v : next) {
      int i, j, k;
      w.ijk(v, i, j, k);
      if (inSpans(i, j, k)) tryFill(i, j, k, filled[std::size_t(k)], local);
    }
    filledInVoi += local;
  }
  return filledInVoi.load();
}

}  // namespace pull
}  // namespace repose

#endif
