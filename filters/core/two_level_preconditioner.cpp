#include "two_level_preconditioner.h"

#include <Eigen/CholmodSupport>
#include <Eigen/Eigenvalues>
#include <Eigen/Sparse>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <stdexcept>

#include "parallel_for.h"
#include "parallel_sum.h"

namespace repose {
namespace {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using Mat6 = Eigen::Matrix<double, 6, 6>;

// Rows per chunk of the threaded passes over the nodes; sums are taken per chunk of this fixed
// size and then in chunk order (parallel_sum.h), so apply() does not depend on the thread count.
constexpr std::size_t kRowChunk = 512;

/// S with S w = w x d: the displacement of a node at offset d under the infinitesimal rotation w.
Mat3 rotationModes(const Vec3& d) {
  Mat3 S;
  S << 0, d.z(), -d.y(), -d.z(), 0, d.x(), d.y(), -d.x(), 0;
  return S;
}

/// The block pattern of the symmetric completion of an upper-stored matrix (no values).
BlockSparseMatrix3f symmetricPattern(const BlockSparseMatrix3f& upper) {
  const int n = upper.rows();
  BlockSparseMatrix3f full;
  full.rowStart.assign(std::size_t(n) + 1, 0);
  for (int i = 0; i < n; ++i)
    for (int k = upper.rowStart[std::size_t(i)]; k < upper.rowStart[std::size_t(i) + 1]; ++k) {
      const int j = upper.column[std::size_t(k)];
      ++full.rowStart[std::size_t(i) + 1];
      if (j != i) ++full.rowStart[std::size_t(j) + 1];
    }
  std::partial_sum(full.rowStart.begin(), full.rowStart.end(), full.rowStart.begin());
  full.column.resize(std::size_t(full.rowStart.back()));
  std::vector<int> fill(full.rowStart.begin(), full.rowStart.end() - 1);
  // Rows in ascending order, so each row's columns come out ascending: first the lower ones (from
  // earlier rows), then the row's own stored ones.
  for (int i = 0; i < n; ++i)
    for (int k = upper.rowStart[std::size_t(i)]; k < upper.rowStart[std::size_t(i) + 1]; ++k) {
      const int j = upper.column[std::size_t(k)];
      full.column[std::size_t(fill[std::size_t(i)]++)] = j;
      if (j != i) full.column[std::size_t(fill[std::size_t(j)]++)] = i;
    }
  return full;
}

}  // namespace

struct TwoLevelPreconditioner::Impl {
  int n = 0;                        // fine block rows (nodes)
  std::vector<int> aggregateOf;     // per node
  std::vector<int> nodeStart, node; // nodes of each aggregate (CSR)
  std::vector<int> modes;           // per aggregate: 6, or 3 (translations only) if its nodes are collinear
  std::vector<int> coarseOffset;    // first coarse row of each aggregate; back() = coarse size
  std::vector<int> neighbourStart, neighbour, neighbourPrefix;  // aggregate adjacency (sorted, with self)
  std::vector<int> valueStart, rowLength;                       // Ac's layout per aggregate (see aggregate())
  std::vector<int> mirror;          // per neighbour entry (a, b): the index of the entry (b, a)
  std::vector<double> halfProduct;  // upper fine matrices: the stored blocks' part of Ac (see update())
  Eigen::SparseMatrix<double> Ac;
  Eigen::CholmodDecomposition<Eigen::SparseMatrix<double>, Eigen::Lower> llt;  // supernodal if that pays
  bool analyzed = false;
  double lastShift = 0.0;           // the diagonal shift of Ac's last factorization (see update())

  // In float, as the CG matrix: the passes of apply() are bound by memory traffic. Ac is formed
  // from the rounded offsets, so P^T and P stay each other's transposes (M stays symmetric).
  std::vector<Eigen::Matrix3f> diagonalInverse;
  std::vector<Eigen::Vector3f> offset;  // node minus its aggregate's centroid, over the aggregate's rms radius
  mutable Eigen::VectorXd coarseRhs, coarseSolution;
  bool useCoarse = true;

  // The matrix's low-rank term G K G^T, if any, joins the fine level by Woodbury's identity:
  //   (D + G K G^T)^-1 = D^-1 - D^-1 G C G^T D^-1,   C = K^1/2 (I + K^1/2 G^T D^-1 G K^1/2)^-1 K^1/2.
  // D is block diagonal, so D^-1 G has G's pattern; C is a small dense matrix.
  const LowRankTerm3* lowRank = nullptr;
  std::vector<double> scaledVectors;  // D^-1 g per entry of lowRank
  Eigen::MatrixXd lowRankSolve;        // C
  mutable Eigen::VectorXd lowRankDot;

  void prepareLowRank(const BlockSparseMatrix3f& A) {
    lowRank = A.lowRank && !A.lowRank->empty() ? A.lowRank : nullptr;
    if (!lowRank) return;
    const LowRankTerm3& L = *lowRank;
    if (int(L.rowStart.size()) != n + 1)
      throw std::invalid_argument("TwoLevelPreconditioner: the low-rank term's rows differ from the matrix's");
    const int terms = int(L.weight.size());
    scaledVectors.resize(L.vector.size());
    Eigen::MatrixXd gram = Eigen::MatrixXd::Zero(terms, terms);  // G^T D^-1 G
    for (int i = 0; i < n; ++i)
      for (int k = L.rowStart[std::size_t(i)]; k < L.rowStart[std::size_t(i) + 1]; ++k) {
        const Vec3 g(L.vector.data() + 3 * std::size_t(k));
        const Vec3 dg = diagonalInverse[std::size_t(i)].cast<double>() * g;
        for (int c = 0; c < 3; ++c) scaledVectors[3 * std::size_t(k) + std::size_t(c)] = dg(c);
        for (int k2 = L.rowStart[std::size_t(i)]; k2 < L.rowStart[std::size_t(i) + 1]; ++k2)
          gram(L.term[std::size_t(k2)], L.term[std::size_t(k)]) += Vec3(L.vector.data() + 3 * std::size_t(k2)).dot(dg);
      }
    const Eigen::VectorXd root = Eigen::Map<const Eigen::VectorXd>(L.weight.data(), terms).cwiseMax(0.0).cwiseSqrt();
    const Eigen::MatrixXd inner =
        Eigen::MatrixXd::Identity(terms, terms) + root.asDiagonal() * gram * root.asDiagonal();
    lowRankSolve = root.asDiagonal() * inner.ldlt().solve(Eigen::MatrixXd(root.asDiagonal()));
  }

  /// z -= D^-1 G C G^T D^-1 r (z holding D^-1 r and the coarse part already); returns the change of r . z.
  double subtractLowRank(const Eigen::VectorXd& r, Eigen::VectorXd& z) const {
    const LowRankTerm3& L = *lowRank;
    const int terms = int(L.weight.size());
    lowRankDot.resize(terms);
    parallelSums(std::size_t(n), kRowChunk, std::size_t(terms), [&](std::size_t begin, std::size_t end, double* t) {
      for (std::size_t i = begin; i < end; ++i)
        for (int k = L.rowStart[i]; k < L.rowStart[i + 1]; ++k)
          t[L.term[std::size_t(k)]] += Vec3(scaledVectors.data() + 3 * std::size_t(k)).dot(r.segment<3>(3 * Eigen::Index(i)));
    }, lowRankDot.data());
    const Eigen::VectorXd y = lowRankSolve * lowRankDot;
    parallelFor(std::size_t(n), [&](std::size_t begin, std::size_t end) {
      for (std::size_t i = begin; i < end; ++i)
        for (int k = L.rowStart[i]; k < L.rowStart[i + 1]; ++k)
          z.segment<3>(3 * Eigen::Index(i)) -= y[L.term[std::size_t(k)]] * Vec3(scaledVectors.data() + 3 * std::size_t(k));
    }, kRowChunk);
    return -lowRankDot.dot(y);
  }

  /// coarseRhs = P^T r, in node order (a gather per aggregate would jump through r): one coarse
  /// vector per chunk of nodes, summed afterwards. At most eight chunks, whatever n: each costs a
  /// coarse vector to clear and add.
  void restrictTo(const Eigen::VectorXd& r) const {
    const int nc = coarseOffset.back();
    coarseRhs.resize(nc);
    const std::size_t chunk = std::max<std::size_t>(1024, (std::size_t(n) + 7) / 8);
    parallelSums(std::size_t(n), chunk, std::size_t(nc), [&](std::size_t begin, std::size_t end, double* sum) {
      for (std::size_t i = begin; i < end; ++i) {
        const int a = aggregateOf[i];
        const Vec3 ri = r.segment<3>(3 * Eigen::Index(i));
        double* c = sum + coarseOffset[std::size_t(a)];
        c[0] += ri.x(), c[1] += ri.y(), c[2] += ri.z();
        if (modes[std::size_t(a)] == 6) {
          const Vec3 torque = offset[i].cast<double>().cross(ri);
          c[3] += torque.x(), c[4] += torque.y(), c[5] += torque.z();
        }
      }
    }, coarseRhs.data());
  }

  /// z = D^-1 r + P Ac^-1 P^T r; returns r . z.
  double apply(const Eigen::VectorXd& r, Eigen::VectorXd& z) const {
    if (useCoarse) {
      restrictTo(r);
      coarseSolution = llt.solve(coarseRhs);
    }
    z.resize(r.size());
    double rz = parallelSum(std::size_t(n), kRowChunk, [&](std::size_t begin, std::size_t end) {
      double sum = 0;
      for (std::size_t i = begin; i < end; ++i) {
        Vec3 zi = diagonalInverse[i].cast<double>() * r.segment<3>(3 * Eigen::Index(i));
        if (useCoarse) {
          const int a = aggregateOf[i];
          const int o = coarseOffset[std::size_t(a)];
          zi += coarseSolution.segment<3>(o);
          if (modes[std::size_t(a)] == 6) zi += coarseSolution.segment<3>(o + 3).cross(offset[i].cast<double>());
        }
        z.segment<3>(3 * Eigen::Index(i)) = zi;
        sum += zi.dot(r.segment<3>(3 * Eigen::Index(i)));
      }
      return sum;
    });
    if (lowRank) rz += subtractLowRank(r, z);
    return rz;
  }
};

TwoLevelPreconditioner::TwoLevelPreconditioner() : impl_(new Impl) {}
TwoLevelPreconditioner::~TwoLevelPreconditioner() = default;
bool TwoLevelPreconditioner::aggregated() const { return !impl_->modes.empty(); }
int TwoLevelPreconditioner::aggregates() const { return int(impl_->modes.size()); }
int TwoLevelPreconditioner::coarseSize() const { return impl_->coarseOffset.empty() ? 0 : impl_->coarseOffset.back(); }

void TwoLevelPreconditioner::aggregate(const BlockSparseMatrix3f& matrix, const Points& positions, int targetSize) {
  const int n = matrix.rows();
  if (positions.rows() != n) throw std::invalid_argument("TwoLevelPreconditioner: one position per block row needed");
  if (targetSize < 1) throw std::invalid_argument("TwoLevelPreconditioner: targetSize must be >= 1");
  impl_.reset(new Impl);
  Impl& s = *impl_;
  s.n = n;
  if (n == 0) return;
  // The adjacency of the nodes: the pattern itself, or its symmetric completion.
  BlockSparseMatrix3f completed;
  if (matrix.upper) completed = symmetricPattern(matrix);
  const BlockSparseMatrix3f& pattern = matrix.upper ? completed : matrix;

  // Grid cell size: start from the bounding box and rescale until the occupied cells hold about
  // targetSize nodes each (the body fills only part of its box).
  const Vec3 lo = positions.colwise().minCoeff().transpose(), hi = positions.colwise().maxCoeff().transpose();
  const Vec3 extent = (hi - lo).cwiseMax(1e-9 * std::max(1.0, (hi - lo).maxCoeff()));
  double h = std::cbrt(extent.prod() * targetSize / n);
  std::vector<std::int64_t> key(static_cast<std::size_t>(n)), sorted;
  auto computeKeys = [&](double cell) {
    const std::int64_t nx = std::int64_t(extent.x() / cell) + 1, ny = std::int64_t(extent.y() / cell) + 1;
    for (int i = 0; i < n; ++i) {
      const Vec3 c = (positions.row(i).transpose() - lo) / cell;
      key[std::size_t(i)] = std::int64_t(c.x()) + nx * (std::int64_t(c.y()) + ny * std::int64_t(c.z()));
    }
    sorted = key;
    std::sort(sorted.begin(), sorted.end());
    return double(n) / double(std::unique(sorted.begin(), sorted.end()) - sorted.begin());
  };
  for (int pass = 0; pass < 12; ++pass) {
    const double mean = computeKeys(h);
    if (mean > 0.8 * targetSize && mean < 1.25 * targetSize) break;
    h *= std::cbrt(targetSize / mean);
  }
  computeKeys(h);

  // Connected parts of the cells: a cell cutting through two limbs gives two aggregates.
  std::vector<int> label(std::size_t(n), -1), queue;
  int m = 0;
  for (int seed = 0; seed < n; ++seed) {
    if (label[std::size_t(seed)] >= 0) continue;
    label[std::size_t(seed)] = m;
    queue.assign(1, seed);
    for (std::size_t q = 0; q < queue.size(); ++q) {
      const int i = queue[q];
      for (int k = pattern.rowStart[std::size_t(i)]; k < pattern.rowStart[std::size_t(i) + 1]; ++k) {
        const int j = pattern.column[std::size_t(k)];
        if (label[std::size_t(j)] < 0 && key[std::size_t(j)] == key[std::size_t(i)]) {
          label[std::size_t(j)] = m;
          queue.push_back(j);
        }
      }
    }
    ++m;
  }
  key = {};
  sorted = {};

  // Slivers at cell corners would make weak (nearly singular) coarse modes: they join the
  // neighbouring aggregate they share most matrix entries with.
  std::vector<int> start(std::size_t(m) + 1, 0), members(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) ++start[std::size_t(label[std::size_t(i)]) + 1];
  std::partial_sum(start.begin(), start.end(), start.begin());
  {
    std::vector<int> fill(start.begin(), start.end() - 1);
    for (int i = 0; i < n; ++i) members[std::size_t(fill[std::size_t(label[std::size_t(i)])]++)] = i;
  }
  std::vector<int> parent(static_cast<std::size_t>(m)), size(static_cast<std::size_t>(m)), links(std::size_t(m), 0);
  std::iota(parent.begin(), parent.end(), 0);
  for (int a = 0; a < m; ++a) size[std::size_t(a)] = start[std::size_t(a) + 1] - start[std::size_t(a)];
  auto find = [&](int a) {
    while (parent[std::size_t(a)] != a) a = parent[std::size_t(a)] = parent[std::size_t(parent[std::size_t(a)])];
    return a;
  };
  const int minSize = std::max(4, targetSize / 8);
  std::vector<int> touched;
  for (int a = 0; a < m; ++a) {
    if (size[std::size_t(a)] >= minSize) continue;
    touched.clear();
    for (int k = start[std::size_t(a)]; k < start[std::size_t(a) + 1]; ++k) {
      const int i = members[std::size_t(k)];
      for (int e = pattern.rowStart[std::size_t(i)]; e < pattern.rowStart[std::size_t(i) + 1]; ++e) {
        const int b = find(label[std::size_t(pattern.column[std::size_t(e)])]);
        if (b == a) continue;
        if (links[std::size_t(b)]++ == 0) touched.push_back(b);
      }
    }
    int best = -1;
    for (int b : touched) {
      if (best < 0 || links[std::size_t(b)] > links[std::size_t(best)]) best = b;
      links[std::size_t(b)] = 0;
    }
    if (best < 0) continue;  // an isolated small part keeps its own modes
    parent[std::size_t(a)] = best;
    size[std::size_t(best)] += size[std::size_t(a)];
  }
  std::vector<int> compact(std::size_t(m), -1);
  int count = 0;
  for (int a = 0; a < m; ++a)
    if (find(a) == a) compact[std::size_t(a)] = count++;
  s.aggregateOf.resize(std::size_t(n));
  for (int i = 0; i < n; ++i) s.aggregateOf[std::size_t(i)] = compact[std::size_t(find(label[std::size_t(i)]))];
  m = count;
  s.nodeStart.assign(std::size_t(m) + 1, 0);
  s.node.resize(std::size_t(n));
  for (int i = 0; i < n; ++i) ++s.nodeStart[std::size_t(s.aggregateOf[std::size_t(i)]) + 1];
  std::partial_sum(s.nodeStart.begin(), s.nodeStart.end(), s.nodeStart.begin());
  {
    std::vector<int> fill(s.nodeStart.begin(), s.nodeStart.end() - 1);
    for (int i = 0; i < n; ++i) s.node[std::size_t(fill[std::size_t(s.aggregateOf[std::size_t(i)])]++)] = i;
  }

  // Rotations only where they are independent of each other: not for collinear (or single) nodes.
  s.modes.resize(std::size_t(m));
  s.coarseOffset.assign(std::size_t(m) + 1, 0);
  for (int a = 0; a < m; ++a) {
    Vec3 centroid = Vec3::Zero();
    for (int k = s.nodeStart[std::size_t(a)]; k < s.nodeStart[std::size_t(a) + 1]; ++k)
      centroid += positions.row(s.node[std::size_t(k)]).transpose();
    centroid /= double(s.nodeStart[std::size_t(a) + 1] - s.nodeStart[std::size_t(a)]);
    Mat3 moment = Mat3::Zero();
    for (int k = s.nodeStart[std::size_t(a)]; k < s.nodeStart[std::size_t(a) + 1]; ++k) {
      const Vec3 d = positions.row(s.node[std::size_t(k)]).transpose() - centroid;
      moment += d.squaredNorm() * Mat3::Identity() - d * d.transpose();
    }
    Eigen::SelfAdjointEigenSolver<Mat3> eig;
    eig.computeDirect(moment, Eigen::EigenvaluesOnly);
    const bool rotations = eig.eigenvalues()(2) > 0 && eig.eigenvalues()(0) > 1e-3 * eig.eigenvalues()(2);
    s.modes[std::size_t(a)] = rotations ? 6 : 3;
    s.coarseOffset[std::size_t(a) + 1] = s.coarseOffset[std::size_t(a)] + s.modes[std::size_t(a)];
  }

  // Aggregate adjacency, and Ac's storage: symmetric with both triangles, so coarse row r is stored
  // as column r (as the fine matrix is); aggregate a's rows hold its neighbours' modes in order.
  s.neighbourStart.assign(std::size_t(m) + 1, 0);
  std::vector<char> seen(std::size_t(m), 0);
  std::vector<int> list;
  for (int a = 0; a < m; ++a) {
    list.clear();
    for (int k = s.nodeStart[std::size_t(a)]; k < s.nodeStart[std::size_t(a) + 1]; ++k) {
      const int i = s.node[std::size_t(k)];
      for (int e = pattern.rowStart[std::size_t(i)]; e < pattern.rowStart[std::size_t(i) + 1]; ++e) {
        const int b = s.aggregateOf[std::size_t(pattern.column[std::size_t(e)])];
        if (!seen[std::size_t(b)]) seen[std::size_t(b)] = 1, list.push_back(b);
      }
    }
    std::sort(list.begin(), list.end());
    for (int b : list) seen[std::size_t(b)] = 0;
    s.neighbour.insert(s.neighbour.end(), list.begin(), list.end());
    s.neighbourStart[std::size_t(a) + 1] = int(s.neighbour.size());
  }
  const int nc = s.coarseOffset.back();
  s.neighbourPrefix.resize(s.neighbour.size());
  s.rowLength.resize(std::size_t(m));
  s.valueStart.assign(std::size_t(m) + 1, 0);
  for (int a = 0; a < m; ++a) {
    int len = 0;
    for (int e = s.neighbourStart[std::size_t(a)]; e < s.neighbourStart[std::size_t(a) + 1]; ++e) {
      s.neighbourPrefix[std::size_t(e)] = len;
      len += s.modes[std::size_t(s.neighbour[std::size_t(e)])];
    }
    s.rowLength[std::size_t(a)] = len;
    s.valueStart[std::size_t(a) + 1] = s.valueStart[std::size_t(a)] + s.modes[std::size_t(a)] * len;
  }
  s.Ac.resize(nc, nc);
  s.Ac.resizeNonZeros(s.valueStart.back());
  for (int a = 0; a < m; ++a)
    for (int c = 0; c < s.modes[std::size_t(a)]; ++c) {
      const int column = s.coarseOffset[std::size_t(a)] + c;
      const int first = s.valueStart[std::size_t(a)] + c * s.rowLength[std::size_t(a)];
      s.Ac.outerIndexPtr()[column] = first;
      for (int e = s.neighbourStart[std::size_t(a)]; e < s.neighbourStart[std::size_t(a) + 1]; ++e) {
        const int b = s.neighbour[std::size_t(e)];
        for (int d = 0; d < s.modes[std::size_t(b)]; ++d)
          s.Ac.innerIndexPtr()[first + s.neighbourPrefix[std::size_t(e)] + d] = s.coarseOffset[std::size_t(b)] + d;
      }
    }
  s.Ac.outerIndexPtr()[nc] = s.valueStart.back();
  s.mirror.resize(s.neighbour.size());
  for (int a = 0; a < m; ++a)
    for (int e = s.neighbourStart[std::size_t(a)]; e < s.neighbourStart[std::size_t(a) + 1]; ++e) {
      const int b = s.neighbour[std::size_t(e)];
      const auto bBegin = s.neighbour.begin() + s.neighbourStart[std::size_t(b)];
      s.mirror[std::size_t(e)] =
          int(std::lower_bound(bBegin, s.neighbour.begin() + s.neighbourStart[std::size_t(b) + 1], a) - s.neighbour.begin());
    }
}

void TwoLevelPreconditioner::updateFine(const BlockSparseMatrix3f& A) {
  Impl& s = *impl_;
  if (A.rows() != s.n) throw std::invalid_argument("TwoLevelPreconditioner::update: sizes differ from aggregate()");
  const std::vector<Mat3> inverse = blockDiagonalInverses(A);
  s.diagonalInverse.resize(inverse.size());
  for (std::size_t i = 0; i < inverse.size(); ++i) s.diagonalInverse[i] = inverse[i].cast<float>();
  s.prepareLowRank(A);
  s.useCoarse = false;
}

void TwoLevelPreconditioner::updateFineKeepingCoarse(const BlockSparseMatrix3f& A) {
  const bool coarse = impl_->useCoarse;
  updateFine(A);
  impl_->useCoarse = coarse;
}

void TwoLevelPreconditioner::update(const BlockSparseMatrix3f& A, const Points& positions) {
  Impl& s = *impl_;
  if (A.rows() != s.n || positions.rows() != s.n)
    throw std::invalid_argument("TwoLevelPreconditioner::update: sizes differ from aggregate()");
  updateFine(A);
  s.useCoarse = true;
  const int m = aggregates();

  // Rigid modes about the current centroids, offsets scaled by the aggregate's rms radius so that
  // rotation and translation entries of Ac have similar magnitudes.
  s.offset.resize(std::size_t(s.n));
  parallelFor(std::size_t(m), [&](std::size_t first, std::size_t last) {
    for (int a = int(first); a < int(last); ++a) {
      const int b = s.nodeStart[std::size_t(a)], e = s.nodeStart[std::size_t(a) + 1];
      Vec3 centroid = Vec3::Zero();
      for (int k = b; k < e; ++k) centroid += positions.row(s.node[std::size_t(k)]).transpose();
      centroid /= double(e - b);
      double r2 = 0;
      for (int k = b; k < e; ++k) r2 += (positions.row(s.node[std::size_t(k)]).transpose() - centroid).squaredNorm();
      const double scale = r2 > 0 ? 1.0 / std::sqrt(r2 / double(e - b)) : 1.0;
      for (int k = b; k < e; ++k) {
        const int i = s.node[std::size_t(k)];
        s.offset[std::size_t(i)] = (scale * (positions.row(i).transpose() - centroid)).cast<float>();
      }
    }
  }, 16);

  // Ac = P^T A P, one aggregate (block row of Ac) per task: P_i = [I | S_i]. Row i of A P is first
  // summed per neighbouring aggregate b, C_ib = sum_j A_ij [I | S_j], then P_i^T C_ib added to the
  // block (a, b): a row touches few aggregates, so this is a third of the work of P_i^T A_ij P_j.
  // An upper-stored A gives, over its stored blocks with the diagonal ones halved, R with
  // Ac = R + R^T (each lower block is a stored one transposed): R first, then the sum.
  using Mat36 = Eigen::Matrix<double, 3, 6>;
  if (A.upper) s.halfProduct.resize(std::size_t(s.valueStart.back()));
  double* values = A.upper ? s.halfProduct.data() : s.Ac.valuePtr();
  // Each task has its own scratch (slot is back at -1 for all aggregates after each one).
  parallelFor(std::size_t(m), [&](std::size_t first, std::size_t last) {
    std::vector<int> slot(std::size_t(m), -1);
    std::vector<Mat6> block;
    std::vector<Mat36> row;
    std::vector<int> touched;
    std::vector<char> inRow;
    for (int a = int(first); a < int(last); ++a) {
      const int nb = s.neighbourStart[std::size_t(a)], ne = s.neighbourStart[std::size_t(a) + 1];
      block.assign(std::size_t(ne - nb), Mat6::Zero());
      row.resize(std::size_t(ne - nb));
      inRow.assign(std::size_t(ne - nb), 0);
      for (int e = nb; e < ne; ++e) slot[std::size_t(s.neighbour[std::size_t(e)])] = e - nb;
      for (int k = s.nodeStart[std::size_t(a)]; k < s.nodeStart[std::size_t(a) + 1]; ++k) {
        const int i = s.node[std::size_t(k)];
        touched.clear();
        for (int q = A.rowStart[std::size_t(i)]; q < A.rowStart[std::size_t(i) + 1]; ++q) {
          const int j = A.column[std::size_t(q)];
          const Eigen::Map<const Eigen::Matrix<float, 3, 3, Eigen::RowMajor>> Af(A.values.data() + 9 * std::size_t(q));
          const Mat3 Aij = (A.upper && j == i ? 0.5 : 1.0) * Af.cast<double>();
          const int sl = slot[std::size_t(s.aggregateOf[std::size_t(j)])];
          Mat36& C = row[std::size_t(sl)];
          if (!inRow[std::size_t(sl)]) {
            inRow[std::size_t(sl)] = 1;
            touched.push_back(sl);
            C.setZero();
          }
          C.leftCols<3>() += Aij;
          C.rightCols<3>() += Aij * rotationModes(s.offset[std::size_t(j)].cast<double>());
        }
        const Mat3 SiT = rotationModes(s.offset[std::size_t(i)].cast<double>()).transpose();
        for (int sl : touched) {
          inRow[std::size_t(sl)] = 0;
          const Mat36& C = row[std::size_t(sl)];
          Mat6& B = block[std::size_t(sl)];
          B.topRows<3>() += C;
          B.bottomRows<3>() += SiT * C;
        }
      }
      const int ma = s.modes[std::size_t(a)], len = s.rowLength[std::size_t(a)];
      for (int e = nb; e < ne; ++e) {
        const int b = s.neighbour[std::size_t(e)];
        slot[std::size_t(b)] = -1;
        for (int c = 0; c < ma; ++c)
          for (int d = 0; d < s.modes[std::size_t(b)]; ++d)
            values[s.valueStart[std::size_t(a)] + c * len + s.neighbourPrefix[std::size_t(e)] + d] =
                block[std::size_t(e - nb)](c, d);
      }
    }
  }, 16);
  if (A.upper) {
    double* full = s.Ac.valuePtr();
    parallelFor(std::size_t(m), [&](std::size_t first, std::size_t last) {
      for (int a = int(first); a < int(last); ++a) {
        const int ma = s.modes[std::size_t(a)], len = s.rowLength[std::size_t(a)];
        for (int e = s.neighbourStart[std::size_t(a)]; e < s.neighbourStart[std::size_t(a) + 1]; ++e) {
          const int b = s.neighbour[std::size_t(e)], back = s.mirror[std::size_t(e)];
          const int mb = s.modes[std::size_t(b)], lenB = s.rowLength[std::size_t(b)];
          for (int c = 0; c < ma; ++c)
            for (int d = 0; d < mb; ++d) {
              const int here = s.valueStart[std::size_t(a)] + c * len + s.neighbourPrefix[std::size_t(e)] + d;
              const int there = s.valueStart[std::size_t(b)] + d * lenB + s.neighbourPrefix[std::size_t(back)] + c;
              full[here] = s.halfProduct[std::size_t(here)] + s.halfProduct[std::size_t(there)];
            }
        }
      }
    }, 64);
  }
  if (!s.analyzed) {
    s.llt.setMode(Eigen::CholmodAuto);
    s.llt.cholmod().print = 0;  // silent: a failed unshifted try (see below) is no message for the user
    s.llt.analyzePattern(s.Ac);
    s.analyzed = true;
  }
  // A projected Newton Hessian is only semi-definite: where every tet of an aggregate had its
  // negative eigenvalues clamped, one of its rigid modes can cost nothing, and Ac is singular.
  // Ac + shift I still makes an SPD preconditioner, which keeps CG exact and only slows that mode, so
  // the factorization is retried with a growing shift (relative to Ac's mean diagonal) instead of the
  // solve failing.
  // (CHOLMOD's simplicial LDL^T, which it picks for small matrices, succeeds on an indefinite one:
  // its D then has a negative entry, whose log makes the log-determinant NaN.)
  auto factorizedDefinite = [&]() {
    s.llt.factorize(s.Ac);
    return s.llt.info() == Eigen::Success && std::isfinite(s.llt.logDeterminant());
  };
  s.llt.setShift(0.0);
  s.lastShift = 0.0;
  bool definite = factorizedDefinite();
  const double scale = s.Ac.rows() > 0 ? s.Ac.diagonal().cwiseAbs().mean() : 0.0;
  for (double relative = 1e-10; relative <= 1e-2 && !definite && scale > 0; relative *= 100) {
    s.lastShift = relative * scale;
    s.llt.setShift(s.lastShift);
    definite = factorizedDefinite();
  }
  // Beyond that shift Ac is not semi-definite, or its rounding outweighs the shift (seen once, on a
  // start with 53 918 inverted tets): block Jacobi alone is still a valid preconditioner, and a
  // slower solve is better than none.
  if (!definite) {
    s.useCoarse = false;
    s.lastShift = 0.0;
  }
}

double TwoLevelPreconditioner::coarseShift() const { return impl_->lastShift; }

bool TwoLevelPreconditioner::coarseUsed() const { return impl_->useCoarse; }

double TwoLevelPreconditioner::apply(const Eigen::VectorXd& r, Eigen::VectorXd& z) const { return impl_->apply(r, z); }

}  // namespace repose
