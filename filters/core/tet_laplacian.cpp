#include "tet_laplacian.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "parallel_for.h"

namespace repose {

namespace {

void checkIndices(Eigen::Index nv, const Tets& tets) {
  for (Eigen::Index t = 0; t < tets.rows(); ++t)
    for (int c = 0; c < 4; ++c)
      if (tets(t, c) < 0 || tets(t, c) >= nv)
        throw std::invalid_argument("tetStiffnessMatrix: tet " + std::to_string(t) + " references node " +
                                    std::to_string(tets(t, c)) + " outside [0, " + std::to_string(nv) + ")");
}

// Element matrix K_e = V G G^T of tet t (G: 4x3 gradients of the barycentric shape functions);
// false for a degenerate tet: a sliver with volume far below its edge length cubed.
bool elementStiffness(const Points& nodes, const Tets& tets, Eigen::Index t, Eigen::Matrix4d& Ke) {
  const Eigen::Vector3d x0 = nodes.row(tets(t, 0));
  Eigen::Matrix3d D;
  for (int c = 0; c < 3; ++c) D.col(c) = nodes.row(tets(t, c + 1)).transpose() - x0;
  const double det = D.determinant();
  const double scale = std::max({D.col(0).squaredNorm(), D.col(1).squaredNorm(), D.col(2).squaredNorm()});
  if (!std::isfinite(det) || std::abs(det) <= 1e-12 * scale * std::sqrt(scale)) return false;
  const Eigen::Matrix3d Dinv = D.inverse();  // rows: gradients of λ1..λ3
  Eigen::Matrix<double, 4, 3> G;
  G.bottomRows<3>() = Dinv;
  G.row(0) = -Dinv.colwise().sum();
  Ke = (std::abs(det) / 6.0) * G * G.transpose();
  return true;
}

// The columns are assembled in parts, one task each: an entry is only ever written by the task of
// its column, so the result does not depend on the threads.
constexpr std::size_t kColumnParts = 16;

struct ColumnPart {
  int first, last;  // columns [first, last)
};
ColumnPart columnPart(std::size_t part, Eigen::Index nv) {
  return {int(Eigen::Index(part) * nv / Eigen::Index(kColumnParts)),
          int(Eigen::Index(part + 1) * nv / Eigen::Index(kColumnParts))};
}

// tetsOfNode[firstTet[v] .. firstTet[v + 1]): the tets using node v, in increasing order.
void nodeTets(Eigen::Index nv, const Tets& tets, std::vector<int>& firstTet, std::vector<int>& tetsOfNode) {
  firstTet.assign(std::size_t(nv) + 1, 0);
  for (Eigen::Index t = 0; t < tets.rows(); ++t)
    for (int c = 0; c < 4; ++c) ++firstTet[std::size_t(tets(t, c)) + 1];
  for (std::size_t v = 0; v < std::size_t(nv); ++v) firstTet[v + 1] += firstTet[v];
  tetsOfNode.resize(std::size_t(tets.size()));
  std::vector<int> fill(firstTet.begin(), firstTet.end() - 1);
  for (Eigen::Index t = 0; t < tets.rows(); ++t)
    for (int c = 0; c < 4; ++c) tetsOfNode[std::size_t(fill[std::size_t(tets(t, c))]++)] = int(t);
}

// K's pattern, compressed column-major with sorted rows (the pattern setFromTriplets makes): column j
// holds every node that shares a tet with j. Values are -0.0, the identity of IEEE addition (-0.0 + x
// is x for every x, -0.0 too), so adding the element terms onto them gives the bits of assigning the
// first one.
Eigen::SparseMatrix<double> stiffnessPattern(Eigen::Index nv, const Tets& tets) {
  std::vector<int> firstTet, tetsOfNode;
  nodeTets(nv, tets, firstTet, tetsOfNode);
  std::vector<std::vector<int>> rowsOfPart(kColumnParts), sizesOfPart(kColumnParts);
  parallelFor(kColumnParts, [&](std::size_t begin, std::size_t end) {
    std::vector<int> lastColumn(std::size_t(nv), -1);
    for (std::size_t part = begin; part < end; ++part) {
      std::vector<int>& rows = rowsOfPart[part];
      for (int j = columnPart(part, nv).first; j < columnPart(part, nv).last; ++j) {
        const auto first = rows.size();
        for (int k = firstTet[std::size_t(j)]; k < firstTet[std::size_t(j) + 1]; ++k)
          for (int c = 0; c < 4; ++c) {
            const int i = tets(tetsOfNode[std::size_t(k)], c);
            if (lastColumn[std::size_t(i)] == j) continue;  // already in this column
            lastColumn[std::size_t(i)] = j;
            rows.push_back(i);
          }
        std::sort(rows.begin() + std::ptrdiff_t(first), rows.end());
        sizesOfPart[part].push_back(int(rows.size() - first));
      }
    }
  }, 1);
  Eigen::SparseMatrix<double> K(nv, nv);
  std::size_t nnz = 0;
  for (const auto& rows : rowsOfPart) nnz += rows.size();
  K.resizeNonZeros(Eigen::Index(nnz));
  int* outer = K.outerIndexPtr();
  int* inner = K.innerIndexPtr();
  outer[0] = 0;
  for (std::size_t part = 0; part < kColumnParts; ++part) {
    inner = std::copy(rowsOfPart[part].begin(), rowsOfPart[part].end(), inner);
    std::vector<int>().swap(rowsOfPart[part]);
    for (int size : sizesOfPart[part]) outer[1] = outer[0] + size, ++outer;
  }
  std::fill_n(K.valuePtr(), nnz, -0.0);
  return K;
}

// Adds tet t's element terms to the columns in `part`, each entry found in its sorted column.
void addElement(Eigen::SparseMatrix<double>& K, const Eigen::Matrix4d& Ke, const int idx[4], ColumnPart part) {
  const int* rows = K.innerIndexPtr();
  for (int b = 0; b < 4; ++b) {
    const int j = idx[b];
    if (j < part.first || j >= part.last) continue;
    for (int a = 0; a < 4; ++a) {
      const int* row = std::lower_bound(rows + K.outerIndexPtr()[j], rows + K.outerIndexPtr()[j + 1], idx[a]);
      K.valuePtr()[row - rows] += Ke(a, b);
    }
  }
}

}  // namespace

Eigen::SparseMatrix<double> tetStiffnessMatrix(const Points& nodes, const Tets& tets) {
  checkIndices(nodes.rows(), tets);
  // Assembled in place, tet by tet in order: each entry sums its tets' terms in the order a
  // triplet list would (setFromTriplets), without the list (16 triplets of 16 bytes per tet) and
  // its transposed copy, which were the peak memory of the weights. A tet spanning two parts of
  // the columns is computed by both (few: the mesh is in spatial order).
  Eigen::SparseMatrix<double> K = stiffnessPattern(nodes.rows(), tets);
  std::vector<Eigen::Index> firstDegenerate(kColumnParts, tets.rows());
  parallelFor(kColumnParts, [&](std::size_t begin, std::size_t end) {
    Eigen::Matrix4d Ke;
    for (std::size_t p = begin; p < end; ++p) {
      const ColumnPart part = columnPart(p, nodes.rows());
      for (Eigen::Index t = 0; t < tets.rows(); ++t) {
        const int idx[4] = {tets(t, 0), tets(t, 1), tets(t, 2), tets(t, 3)};
        if (std::none_of(idx, idx + 4, [&](int v) { return v >= part.first && v < part.last; })) continue;
        if (!elementStiffness(nodes, tets, t, Ke)) {
          firstDegenerate[p] = t;
          break;
        }
        addElement(K, Ke, idx, part);
      }
    }
  }, 1);
  const Eigen::Index degenerate = *std::min_element(firstDegenerate.begin(), firstDegenerate.end());
  if (degenerate < tets.rows())
    throw std::invalid_argument("tetStiffnessMatrix: tet " + std::to_string(degenerate) +
                                " is degenerate (zero volume); remesh or remove it");
  return K;
}

}  // namespace repose
