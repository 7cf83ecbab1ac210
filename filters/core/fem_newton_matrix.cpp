#include "fem_newton_matrix.h"

#include <algorithm>
#include <stdexcept>
#include <utility>

#include "parallel_for.h"

namespace repose {
namespace fem {

std::vector<int> unknownNodes(const Tets& tets, const std::vector<int>& fixedBone, Eigen::Index nV) {
  std::vector<char> inTet(std::size_t(nV), 0);
  for (Eigen::Index t = 0; t < tets.rows(); ++t)
    for (int a = 0; a < 4; ++a)
      if (fixedBone[std::size_t(tets(t, a))] < 0) inTet[std::size_t(tets(t, a))] = 1;
  std::vector<int> freeNodes;
  for (Eigen::Index i = 0; i < nV; ++i)
    if (inTet[std::size_t(i)]) freeNodes.push_back(int(i));
  return freeNodes;
}

void NewtonMatrix::setRow(std::size_t i, const double* rowBlocks) {
  const int len = rowLength(i);
  if (blocked) {
    float* dst = blocks.values.data() + 9 * std::size_t(blocks.rowStart[i]);
    for (int k = 0; k < 9 * len; ++k) dst[k] = float(rowBlocks[k]);
    return;
  }
  double* v0 = scalar.valuePtr() + scalar.outerIndexPtr()[3 * i];
  for (int k = 0; k < len; ++k)
    for (int c = 0; c < 3; ++c)
      for (int d = 0; d < 3; ++d) v0[3 * c * len + 3 * k + d] = rowBlocks[9 * k + 3 * c + d];
}

namespace {

// Node -> incident (tet, local index) lists, for free nodes only (CSR).
void incidences(const Tets& tets, const std::vector<int>& fixedBone, const std::vector<int>& dof, FreeNodeSystem& s) {
  const Eigen::Index nT = tets.rows();
  const std::size_t nFree = s.freeNodes.size();
  s.incStart.assign(nFree + 1, 0);
  for (Eigen::Index t = 0; t < nT; ++t)
    for (int a = 0; a < 4; ++a) {
      const int d = dof[std::size_t(tets(t, a))];
      if (d >= 0 && fixedBone[std::size_t(tets(t, a))] < 0) ++s.incStart[std::size_t(d) + 1];
    }
  for (std::size_t i = 0; i < nFree; ++i) s.incStart[i + 1] += s.incStart[i];
  s.incTet.resize(static_cast<std::size_t>(s.incStart[nFree]));
  std::vector<int> fill(s.incStart);  // next write position per free node
  for (Eigen::Index t = 0; t < nT; ++t)
    for (int a = 0; a < 4; ++a) {
      const int v = tets(t, a);
      if (fixedBone[std::size_t(v)] < 0) s.incTet[std::size_t(fill[std::size_t(dof[std::size_t(v)])]++)] = int(t) * 4 + a;
    }
}

// The columns of row i's blocks: free nodes by their unknown's index; an upper matrix stores only
// those from i on.
struct RowColumns {
  const Tets& tets;
  const std::vector<int>& fixedBone;
  const std::vector<int>& dof;
  const FreeNodeSystem& s;
  bool blocked;

  int stored(std::size_t i, int v) const {  // the column of node v in row i, or -1
    const int d = fixedBone[std::size_t(v)] < 0 ? dof[std::size_t(v)] : -1;
    return blocked && d < int(i) ? -1 : d;
  }
  // Row i's distinct columns, in the order met, written to out (if given); returns their count. mark:
  // a per-thread mark (last row that listed a column).
  int distinct(std::size_t i, std::vector<int>& mark, int* out) const {
    int len = 0;
    for (int k = s.incStart[i]; k < s.incStart[i + 1]; ++k) {
      const int t = s.incTet[std::size_t(k)] / 4;
      for (int c = 0; c < 4; ++c) {
        const int col = stored(i, tets(t, c));
        if (col >= 0 && mark[std::size_t(col)] != int(i)) {
          mark[std::size_t(col)] = int(i);
          if (out) out[len] = col;
          ++len;
        }
      }
    }
    return len;
  }
};

// A's scalar CSR with both triangles from the block pattern. Symmetric, so the column-major arrays
// are filled row by row: column 3i+c holds row 3i+c.
void scalarPattern(const std::vector<int>& rowStart, const std::vector<int>& column, std::size_t nFree,
                   Eigen::SparseMatrix<double>& S) {
  const Eigen::Index n = Eigen::Index(3 * nFree);
  S.resize(n, n);
  S.resizeNonZeros(Eigen::Index(9) * rowStart[nFree]);
  for (std::size_t i = 0; i < nFree; ++i)
    for (int c = 0; c < 3; ++c) S.outerIndexPtr()[3 * i + c] = 9 * rowStart[i] + 3 * c * (rowStart[i + 1] - rowStart[i]);
  S.outerIndexPtr()[n] = 9 * rowStart[nFree];
  parallelFor(nFree, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i)
      for (int c = 0; c < 3; ++c) {
        int* inner = S.innerIndexPtr() + S.outerIndexPtr()[3 * i + c];
        for (int k = rowStart[i]; k < rowStart[i + 1]; ++k)
          for (int d = 0; d < 3; ++d) inner[3 * (k - rowStart[i]) + d] = 3 * column[std::size_t(k)] + d;
      }
  });
}

}  // namespace

FreeNodeSystem freeNodeSystem(const Tets& tets, const std::vector<int>& fixedBone, std::vector<int> freeNodes,
                              bool blocked) {
  FreeNodeSystem s;
  s.freeNodes = std::move(freeNodes);
  const std::size_t nFree = s.freeNodes.size();
  std::vector<int> dof(fixedBone.size(), -1);  // node -> its unknown's index
  for (std::size_t i = 0; i < nFree; ++i) dof[std::size_t(s.freeNodes[i])] = int(i);
  incidences(tets, fixedBone, dof, s);

  // Block sparsity pattern. Two passes over each row's tets, the first to count, the second to fill:
  // the per-thread mark leaves only the row's distinct columns to sort, and then maps each to its
  // place in the row.
  s.A.blocked = blocked;
  const RowColumns columns{tets, fixedBone, dof, s, blocked};
  // (Chunks of at least a 32nd of the rows: each allocates its own mark.)
  const std::size_t patternGrain = std::max<std::size_t>(1024, nFree / 32);
  std::vector<int> rowStart(nFree + 1, 0);
  parallelFor(nFree, [&](std::size_t b, std::size_t e) {
    std::vector<int> mark(nFree, -1);
    for (std::size_t i = b; i < e; ++i) rowStart[i + 1] = columns.distinct(i, mark, nullptr);
  }, patternGrain);
  for (std::size_t i = 0; i < nFree; ++i) {
    if (rowStart[i + 1] >= kNotStored)  // over 65534 neighbours: not a tet mesh a skinning could come from
      throw std::invalid_argument("relaxCorotational: a node has too many neighbours");
    rowStart[i + 1] += rowStart[i];
  }
  // Where each (free node, incident tet, tet node) block goes in the node's row: its index there
  // (kNotStored: not stored), found once here instead of by a search in every assembly.
  std::vector<int> column(static_cast<std::size_t>(rowStart[nFree]));
  s.incColumn.assign(4 * s.incTet.size(), kNotStored);
  parallelFor(nFree, [&](std::size_t b, std::size_t e) {
    std::vector<int> mark(nFree, -1), place(nFree);
    for (std::size_t i = b; i < e; ++i) {
      int* cols = column.data() + rowStart[i];
      const int len = columns.distinct(i, mark, cols);
      std::sort(cols, cols + len);
      for (int q = 0; q < len; ++q) place[std::size_t(cols[q])] = q;
      for (int k = s.incStart[i]; k < s.incStart[i + 1]; ++k) {
        const int t = s.incTet[std::size_t(k)] / 4;
        for (int c = 0; c < 4; ++c) {
          const int col = columns.stored(i, tets(t, c));
          if (col >= 0) s.incColumn[4 * std::size_t(k) + std::size_t(c)] = std::uint16_t(place[std::size_t(col)]);
        }
      }
    }
  }, patternGrain);
  if (blocked) {
    s.A.blocks.upper = true;
    s.A.blocks.rowStart = rowStart;
    s.A.blocks.column = std::move(column);
    s.A.blocks.values.assign(9 * std::size_t(rowStart[nFree]), 0.0f);
  } else {
    scalarPattern(rowStart, column, nFree, s.A.scalar);
  }
  return s;
}

}  // namespace fem
}  // namespace repose
