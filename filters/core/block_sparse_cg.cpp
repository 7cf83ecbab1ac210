#include "block_sparse_cg.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "parallel_for.h"
#include "parallel_sum.h"

namespace repose {

namespace {

// Rows and scalars per chunk of the threaded loops; the sums are taken per chunk of these fixed
// sizes and then in chunk order (parallel_sum.h), so no result depends on the thread count.
constexpr std::size_t kRowChunk = 512;
constexpr std::size_t kScalarChunk = 4096;

double dot(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return parallelSum(std::size_t(a.size()), kScalarChunk, [&](std::size_t begin, std::size_t end) {
    double s = 0;
    for (std::size_t k = begin; k < end; ++k) s += a[Eigen::Index(k)] * b[Eigen::Index(k)];
    return s;
  });
}

}  // namespace

void BlockSparseMatrix3f::multiply(const Eigen::VectorXd& x, Eigen::VectorXd& y) const {
  if (upper) {
    multiplyUpper(x, y);
    if (lowRank && !lowRank->empty()) lowRank->multiplyAdd(x, y);
    return;
  }
  const int n = rows();
  y.resize(3 * Eigen::Index(n));
  const double* xp = x.data();
  double* yp = y.data();
  parallelFor(std::size_t(n), [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      double s0 = 0, s1 = 0, s2 = 0;
      for (int k = rowStart[i]; k < rowStart[i + 1]; ++k) {
        const float* v = values.data() + 9 * std::size_t(k);
        const double* xc = xp + 3 * std::size_t(column[std::size_t(k)]);
        const double x0 = xc[0], x1 = xc[1], x2 = xc[2];
        s0 += double(v[0]) * x0 + double(v[1]) * x1 + double(v[2]) * x2;
        s1 += double(v[3]) * x0 + double(v[4]) * x1 + double(v[5]) * x2;
        s2 += double(v[6]) * x0 + double(v[7]) * x1 + double(v[8]) * x2;
      }
      yp[3 * i] = s0;
      yp[3 * i + 1] = s1;
      yp[3 * i + 2] = s2;
    }
  }, kRowChunk);
  if (lowRank && !lowRank->empty()) lowRank->multiplyAdd(x, y);
}

namespace {

// Rows [begin, end) of an upper-stored product: y_i += A_ij x_j, and A_ij^T x_i added to y_j for
// j < end or to spill[3 (j - end)] beyond. Plain arrays only (no Eigen types, whose layout may differ
// between instruction sets), so the function can be built twice: for AVX2/FMA, where most of the
// time goes into the arithmetic rather than memory, and for any x86-64, chosen when the library is
// loaded.
#if defined(__GNUC__) && defined(__x86_64__) && !defined(__clang__)
__attribute__((target_clones("arch=x86-64-v3", "default")))
#endif
void upperRows(int begin, int end, const int* rowStart, const int* column, const float* values, const double* x,
               double* y, double* spill) {
  for (int i = begin; i < end; ++i) {
    const double xi0 = x[3 * std::size_t(i)], xi1 = x[3 * std::size_t(i) + 1], xi2 = x[3 * std::size_t(i) + 2];
    double s0 = 0, s1 = 0, s2 = 0;
    for (int k = rowStart[i]; k < rowStart[i + 1]; ++k) {
      const float* v = values + 9 * std::size_t(k);
      const int j = column[k];
      const double* xc = x + 3 * std::size_t(j);
      const double x0 = xc[0], x1 = xc[1], x2 = xc[2];
      const double a0 = v[0], a1 = v[1], a2 = v[2], a3 = v[3], a4 = v[4], a5 = v[5], a6 = v[6], a7 = v[7], a8 = v[8];
      s0 += a0 * x0 + a1 * x1 + a2 * x2;
      s1 += a3 * x0 + a4 * x1 + a5 * x2;
      s2 += a6 * x0 + a7 * x1 + a8 * x2;
      if (j == i) continue;
      double* out = j < end ? y + 3 * std::size_t(j) : spill + 3 * std::size_t(j - end);
      out[0] += a0 * xi0 + a3 * xi1 + a6 * xi2;
      out[1] += a1 * xi0 + a4 * xi1 + a7 * xi2;
      out[2] += a2 * xi0 + a5 * xi1 + a8 * xi2;
    }
    y[3 * std::size_t(i)] += s0;
    y[3 * std::size_t(i) + 1] += s1;
    y[3 * std::size_t(i) + 2] += s2;
  }
}

// Stored blocks per chunk of an upper-stored product, before chunks are merged to bound the spill.
constexpr long long kBlocksPerChunk = 8192;

// The row chunks of an upper-stored product, from the matrix alone: chunk c holds rows
// [first[c], first[c + 1]) and spills into rows [first[c + 1], reach[c]).
struct UpperChunks {
  std::vector<int> first, reach;
  std::vector<std::size_t> spillAt;  // chunks + 1: chunk c's spill starts at 3 spillAt[c]
};

// A power of two of chunks of about kBlocksPerChunk stored blocks each, halved (merging neighbours)
// while all spills together would cover more rows than the matrix has: an ordering whose blocks reach
// far gets fewer, longer chunks instead of a spill buffer many times the vector.
UpperChunks upperChunks(const std::vector<int>& rowStart, const std::vector<int>& column, int n) {
  const long long blocks = rowStart[std::size_t(n)];
  std::size_t count = 1;
  while ((long long)count * kBlocksPerChunk < blocks && count < (std::size_t(1) << 16)) count *= 2;
  UpperChunks chunks;
  chunks.first.resize(count + 1);
  for (std::size_t c = 0; c < count; ++c)  // the row holding block blocks * c / count
    chunks.first[c] = int(std::upper_bound(rowStart.begin(), rowStart.end(), (long long)(blocks * (long long)c / (long long)count)) -
                          rowStart.begin()) - 1;
  chunks.first[0] = 0;
  chunks.first[count] = n;
  chunks.reach.resize(count);
  parallelFor(count, [&](std::size_t begin, std::size_t end) {
    for (std::size_t c = begin; c < end; ++c) {
      int far = chunks.first[c + 1];
      for (int i = chunks.first[c]; i < chunks.first[c + 1]; ++i)
        if (rowStart[std::size_t(i) + 1] > rowStart[std::size_t(i)])
          far = std::max(far, column[std::size_t(rowStart[std::size_t(i) + 1]) - 1] + 1);
      chunks.reach[c] = far;
    }
  }, 1);
  auto spillRows = [&] {
    std::size_t rows = 0;
    for (std::size_t c = 0; c < chunks.reach.size(); ++c) rows += std::size_t(chunks.reach[c] - chunks.first[c + 1]);
    return rows;
  };
  while (chunks.reach.size() > 1 && spillRows() > std::size_t(n)) {
    const std::size_t half = chunks.reach.size() / 2;
    for (std::size_t c = 0; c < half; ++c) {
      chunks.first[c] = chunks.first[2 * c];
      chunks.reach[c] = std::max(chunks.reach[2 * c], chunks.reach[2 * c + 1]);
    }
    chunks.first[half] = n;
    chunks.first.resize(half + 1);
    chunks.reach.resize(half);
  }
  chunks.spillAt.assign(chunks.reach.size() + 1, 0);
  for (std::size_t c = 0; c < chunks.reach.size(); ++c)
    chunks.spillAt[c + 1] = chunks.spillAt[c] + std::size_t(chunks.reach[c] - chunks.first[c + 1]);
  return chunks;
}

}  // namespace

// Each chunk of rows (a split of the stored blocks that depends on the matrix only) adds, for every
// block A_ij, A_ij x_j to y_i and A_ij^T x_i to y_j. j >= i, so the second lands in the chunk's own
// rows or in later chunks' rows; the latter go to the chunk's spill buffer, which covers the rows
// from its end to the largest column it reaches. A second pass adds to each chunk's rows what earlier
// chunks spilled into them, in chunk order: the same sums whatever the threads.
void BlockSparseMatrix3f::multiplyUpper(const Eigen::VectorXd& x, Eigen::VectorXd& y) const {
  const int n = rows();
  y.resize(3 * Eigen::Index(n));
  if (n == 0) return;
  const UpperChunks chunks = upperChunks(rowStart, column, n);
  const std::size_t count = chunks.reach.size();
  spill_.resize(3 * chunks.spillAt.back());
  const double* xp = x.data();
  double* yp = y.data();
  parallelFor(count, [&](std::size_t first, std::size_t last) {
    for (std::size_t c = first; c < last; ++c) {
      const int begin = chunks.first[c], end = chunks.first[c + 1];
      double* spill = spill_.data() + 3 * chunks.spillAt[c];
      std::fill(yp + 3 * std::size_t(begin), yp + 3 * std::size_t(end), 0.0);
      std::fill(spill, spill_.data() + 3 * chunks.spillAt[c + 1], 0.0);
      upperRows(begin, end, rowStart.data(), column.data(), values.data(), xp, yp, spill);
    }
  }, 1);
  parallelFor(count, [&](std::size_t first, std::size_t last) {
    for (std::size_t t = first; t < last; ++t) {
      const int begin = chunks.first[t], end = chunks.first[t + 1];
      for (std::size_t u = 0; u < t; ++u) {
        const int spillBegin = chunks.first[u + 1];  // row of chunk u's spill entry 0
        const int from = std::max(begin, spillBegin), to = std::min(end, chunks.reach[u]);
        const double* other = spill_.data() + 3 * chunks.spillAt[u];
        for (int j = from; j < to; ++j)
          for (int c = 0; c < 3; ++c) yp[3 * std::size_t(j) + std::size_t(c)] += other[3 * std::size_t(j - spillBegin) + std::size_t(c)];
      }
    }
  }, 1);
}

void LowRankTerm3::multiplyAdd(const Eigen::VectorXd& x, Eigen::VectorXd& y) const {
  const int n = int(rowStart.size()) - 1;
  const std::size_t terms = weight.size();
  if (x.size() != 3 * Eigen::Index(n) || y.size() != x.size())
    throw std::invalid_argument("LowRankTerm3: vector sizes do not match the term");
  std::vector<double> dot(terms, 0.0);
  parallelSums(std::size_t(n), kRowChunk, terms, [&](std::size_t begin, std::size_t end, double* d) {
    for (std::size_t i = begin; i < end; ++i)
      for (int k = rowStart[i]; k < rowStart[i + 1]; ++k) {
        const double* g = vector.data() + 3 * std::size_t(k);
        const Eigen::Index o = 3 * Eigen::Index(i);
        d[term[std::size_t(k)]] += g[0] * x[o] + g[1] * x[o + 1] + g[2] * x[o + 2];
      }
  }, dot.data());
  for (std::size_t r = 0; r < terms; ++r) dot[r] *= weight[r];
  parallelFor(std::size_t(n), [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i)
      for (int k = rowStart[i]; k < rowStart[i + 1]; ++k) {
        const double* g = vector.data() + 3 * std::size_t(k);
        const double s = dot[std::size_t(term[std::size_t(k)])];
        for (int c = 0; c < 3; ++c) y[3 * Eigen::Index(i) + c] += s * g[c];
      }
  }, kRowChunk);
}

std::vector<Eigen::Matrix3d> blockDiagonalInverses(const BlockSparseMatrix3f& A) {
  const int n = A.rows();
  std::vector<Eigen::Matrix3d> inverse(static_cast<std::size_t>(n));
  parallelFor(std::size_t(n), [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      Eigen::Matrix3d D = Eigen::Matrix3d::Zero();
      for (int k = A.rowStart[i]; k < A.rowStart[i + 1]; ++k)
        if (std::size_t(A.column[std::size_t(k)]) == i) {
          const float* v = A.values.data() + 9 * std::size_t(k);
          for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) D(r, c) = double(v[3 * r + c]);
        }
      const double scale = D.cwiseAbs().maxCoeff();
      if (scale > 0 && std::abs(D.determinant()) > 1e-12 * scale * scale * scale) {
        inverse[i] = D.inverse();
      } else {
        inverse[i].setZero();
        for (int r = 0; r < 3; ++r) inverse[i](r, r) = D(r, r) > 0 ? 1.0 / D(r, r) : 0.0;
      }
    }
  }, kRowChunk);
  return inverse;
}

namespace {

// |b|, after checking the sizes; a zero right-hand side has the solution x = 0 (set here).
double rightHandSideNorm(const char* solver, const BlockSparseMatrix3f& A, const Eigen::VectorXd& b,
                         Eigen::VectorXd& x) {
  if (b.size() != 3 * Eigen::Index(A.rows()) || x.size() != b.size())
    throw std::invalid_argument(std::string(solver) + ": vector sizes do not match the matrix");
  const double bNorm = b.norm();
  if (!(bNorm > 0.0)) x.setZero();
  return bNorm;
}

// The next search direction p = z + (rzNew / rz) p, and rz = rzNew.
void nextDirection(double rzNew, double& rz, const Eigen::VectorXd& z, Eigen::VectorXd& p) {
  const double beta = rzNew / rz;
  rz = rzNew;
  parallelFor(std::size_t(p.size()), [&](std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k) p[Eigen::Index(k)] = z[Eigen::Index(k)] + beta * p[Eigen::Index(k)];
  }, kScalarChunk);
}

BlockCgResult finished(int iterations, double rNorm, double bNorm) {
  BlockCgResult result;
  result.iterations = iterations;
  result.relativeResidual = rNorm / bNorm;
  return result;
}

}  // namespace

BlockCgResult blockJacobiCg(const BlockSparseMatrix3f& A, const Eigen::VectorXd& b, Eigen::VectorXd& x,
                            double tolerance, int maxIterations) {
  const int n = A.rows();
  BlockCgResult result;
  const double bNorm = rightHandSideNorm("blockJacobiCg", A, b, x);
  if (!(bNorm > 0.0)) return result;
  const std::vector<Eigen::Matrix3d> inverse = blockDiagonalInverses(A);
  // The vector updates are fused into two threaded passes per iteration (besides the product): on
  // two cores CG is bound by memory traffic, and serial vector operations would leave a core idle.
  const Eigen::Index m = b.size();
  Eigen::VectorXd r(m), z(m), p(m), q(m);
  A.multiply(x, q);
  double sums[2];  // r . r, r . z
  parallelSums(std::size_t(n), kRowChunk, 2, [&](std::size_t begin, std::size_t end, double* s) {
    for (std::size_t i = begin; i < end; ++i) {
      const Eigen::Index o = 3 * Eigen::Index(i);
      const Eigen::Vector3d ri = b.segment<3>(o) - q.segment<3>(o);
      const Eigen::Vector3d zi = inverse[i] * ri;
      r.segment<3>(o) = ri;
      z.segment<3>(o) = zi;
      p.segment<3>(o) = zi;
      s[0] += ri.squaredNorm();
      s[1] += ri.dot(zi);
    }
  }, sums);
  double rz = sums[1];
  const double threshold = tolerance * bNorm;
  double rNorm = std::sqrt(sums[0]);
  int it = 0;
  while (rNorm > threshold && it < maxIterations) {
    A.multiply(p, q);
    const double pq = dot(p, q);
    if (!(pq > 0.0)) break;  // no descent left (semi-definite direction)
    const double alpha = rz / pq;
    parallelSums(std::size_t(n), kRowChunk, 2, [&](std::size_t begin, std::size_t end, double* s) {
      for (std::size_t i = begin; i < end; ++i) {
        const Eigen::Index o = 3 * Eigen::Index(i);
        x.segment<3>(o) += alpha * p.segment<3>(o);
        const Eigen::Vector3d ri = r.segment<3>(o) - alpha * q.segment<3>(o);
        const Eigen::Vector3d zi = inverse[i] * ri;
        r.segment<3>(o) = ri;
        z.segment<3>(o) = zi;
        s[0] += ri.squaredNorm();
        s[1] += ri.dot(zi);
      }
    }, sums);
    ++it;
    rNorm = std::sqrt(sums[0]);
    if (rNorm <= threshold) break;
    nextDirection(sums[1], rz, z, p);
  }
  return finished(it, rNorm, bNorm);
}

BlockCgResult preconditionedBlockCg(const BlockSparseMatrix3f& A, const Eigen::VectorXd& b, Eigen::VectorXd& x,
                                    double tolerance, int maxIterations, const BlockPreconditioner& M) {
  BlockCgResult result;
  const double bNorm = rightHandSideNorm("preconditionedBlockCg", A, b, x);
  if (!(bNorm > 0.0)) return result;
  const Eigen::Index m = b.size();
  Eigen::VectorXd r(m), z(m), p(m), q(m);
  A.multiply(x, q);
  const double rr = parallelSum(std::size_t(m), kScalarChunk, [&](std::size_t begin, std::size_t end) {
    double s = 0;
    for (Eigen::Index k = Eigen::Index(begin); k < Eigen::Index(end); ++k) {
      r[k] = b[k] - q[k];
      s += r[k] * r[k];
    }
    return s;
  });
  const double threshold = tolerance * bNorm;
  double rNorm = std::sqrt(rr);
  int it = 0;
  double rz = 0;
  if (rNorm > threshold) {
    rz = M.apply(r, z);
    p = z;
  }
  while (rNorm > threshold && it < maxIterations) {
    A.multiply(p, q);
    const double pq = dot(p, q);
    if (!(pq > 0.0)) break;
    const double alpha = rz / pq;
    const double rrNew = parallelSum(std::size_t(m), kScalarChunk, [&](std::size_t begin, std::size_t end) {
      double s = 0;
      for (Eigen::Index k = Eigen::Index(begin); k < Eigen::Index(end); ++k) {
        x[k] += alpha * p[k];
        r[k] -= alpha * q[k];
        s += r[k] * r[k];
      }
      return s;
    });
    ++it;
    rNorm = std::sqrt(rrNew);
    if (rNorm <= threshold) break;
    const double rzNew = M.apply(r, z);
    nextDirection(rzNew, rz, z, p);
  }
  return finished(it, rNorm, bNorm);
}

}  // namespace repose
