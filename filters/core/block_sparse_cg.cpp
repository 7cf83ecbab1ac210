#include "block_sparse_cg.h"

#include <Eigen/LU>
#include <algorithm>
#include <omp.h>
#include <cmath>
#include <stdexcept>
#include <string>

namespace repose {

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
#pragma omp parallel for schedule(static, 512)
  for (int i = 0; i < n; ++i) {
    double s0 = 0, s1 = 0, s2 = 0;
    for (int k = rowStart[std::size_t(i)]; k < rowStart[std::size_t(i) + 1]; ++k) {
      const float* v = values.data() + 9 * std::size_t(k);
      const double* xc = xp + 3 * std::size_t(column[std::size_t(k)]);
      const double x0 = xc[0], x1 = xc[1], x2 = xc[2];
      s0 += double(v[0]) * x0 + double(v[1]) * x1 + double(v[2]) * x2;
      s1 += double(v[3]) * x0 + double(v[4]) * x1 + double(v[5]) * x2;
      s2 += double(v[6]) * x0 + double(v[7]) * x1 + double(v[8]) * x2;
    }
    yp[3 * std::size_t(i)] = s0;
    yp[3 * std::size_t(i) + 1] = s1;
    yp[3 * std::size_t(i) + 2] = s2;
  }
  if (lowRank && !lowRank->empty()) lowRank->multiplyAdd(x, y);
}

namespace {

// Rows [begin, end) of an upper-stored product: y_i += A_ij x_j, and A_ij^T x_i added to y_j for
// j < end or to spill_j beyond. Plain arrays only (no Eigen types, whose layout may differ between
// instruction sets), so the function can be built twice: for AVX2/FMA, where most of the time goes
// into the arithmetic rather than memory, and for any x86-64, chosen when the library is loaded.
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
      double* out = (j < end ? y : spill) + 3 * std::size_t(j);
      out[0] += a0 * xi0 + a3 * xi1 + a6 * xi2;
      out[1] += a1 * xi0 + a4 * xi1 + a7 * xi2;
      out[2] += a2 * xi0 + a5 * xi1 + a8 * xi2;
    }
    y[3 * std::size_t(i)] += s0;
    y[3 * std::size_t(i) + 1] += s1;
    y[3 * std::size_t(i) + 2] += s2;
  }
}

}  // namespace

// Each thread takes a contiguous range of rows (split by stored blocks) and adds, for every block
// A_ij, A_ij x_j to y_i and A_ij^T x_i to y_j. j >= i, so the second lands in the thread's own rows
// or in later threads' rows; the latter go to the thread's spill buffer, which covers the rows from
// its range's end to the largest column it reaches (mesh orderings keep that short), and are added
// after all threads are done. Fixed ranges and order: the same sums on every run.
void BlockSparseMatrix3f::multiplyUpper(const Eigen::VectorXd& x, Eigen::VectorXd& y) const {
  const int n = rows();
  y.resize(3 * Eigen::Index(n));
  if (n == 0) return;
  std::vector<int> first, reach;
  std::vector<std::size_t> spillAt;
  const double* xp = x.data();
  double* yp = y.data();
#pragma omp parallel
  {
#pragma omp single
    {  // the ranges, for the team actually running
      const int threads = omp_get_num_threads();
      first.assign(std::size_t(threads) + 1, n);
      reach.assign(std::size_t(threads), n);
      spillAt.assign(std::size_t(threads) + 1, 0);
      const long long blocks = rowStart[std::size_t(n)];
      first[0] = 0;
      for (int t = 1; t < threads; ++t)
        first[std::size_t(t)] = std::max(first[std::size_t(t) - 1],
                                         int(std::upper_bound(rowStart.begin(), rowStart.end(),
                                                              (long long)(blocks * t / threads)) - rowStart.begin()) - 1);
      for (int t = 0; t < threads; ++t) {
        int far = first[std::size_t(t) + 1];
        for (int i = first[std::size_t(t)]; i < first[std::size_t(t) + 1]; ++i)
          if (rowStart[std::size_t(i) + 1] > rowStart[std::size_t(i)])
            far = std::max(far, column[std::size_t(rowStart[std::size_t(i) + 1]) - 1] + 1);
        reach[std::size_t(t)] = far;
        spillAt[std::size_t(t) + 1] = spillAt[std::size_t(t)] + 3 * std::size_t(far - first[std::size_t(t) + 1]);
      }
      spill_.resize(spillAt.back());
    }
    const int t = omp_get_thread_num();
    const int begin = first[std::size_t(t)], end = first[std::size_t(t) + 1];
    double* spill = spill_.data() + spillAt[std::size_t(t)] - 3 * std::size_t(end);  // indexed by 3 j
    std::fill(yp + 3 * std::size_t(begin), yp + 3 * std::size_t(end), 0.0);
    std::fill(spill_.data() + spillAt[std::size_t(t)], spill_.data() + spillAt[std::size_t(t) + 1], 0.0);
    upperRows(begin, end, rowStart.data(), column.data(), values.data(), xp, yp, spill);
#pragma omp barrier
    // This thread's rows take what earlier threads spilled into them, in thread order.
    for (int u = 0; u < t; ++u) {
      const int from = std::max(begin, first[std::size_t(u) + 1]), to = std::min(end, reach[std::size_t(u)]);
      const double* other = spill_.data() + spillAt[std::size_t(u)] - 3 * std::size_t(first[std::size_t(u) + 1]);
      for (std::size_t k = 3 * std::size_t(from); k < 3 * std::size_t(std::max(from, to)); ++k) yp[k] += other[k];
    }
  }
}

void LowRankTerm3::multiplyAdd(const Eigen::VectorXd& x, Eigen::VectorXd& y) const {
  const int n = int(rowStart.size()) - 1;
  const int terms = int(weight.size());
  if (x.size() != 3 * Eigen::Index(n) || y.size() != x.size())
    throw std::invalid_argument("LowRankTerm3: vector sizes do not match the term");
  std::vector<double> dot(std::size_t(terms), 0.0);
  double* d = dot.data();
#pragma omp parallel for schedule(static, 1024) reduction(+ : d[:terms])
  for (int i = 0; i < n; ++i)
    for (int k = rowStart[std::size_t(i)]; k < rowStart[std::size_t(i) + 1]; ++k) {
      const double* g = vector.data() + 3 * std::size_t(k);
      d[term[std::size_t(k)]] += g[0] * x[3 * i] + g[1] * x[3 * i + 1] + g[2] * x[3 * i + 2];
    }
  for (int r = 0; r < terms; ++r) dot[std::size_t(r)] *= weight[std::size_t(r)];
#pragma omp parallel for schedule(static, 1024)
  for (int i = 0; i < n; ++i)
    for (int k = rowStart[std::size_t(i)]; k < rowStart[std::size_t(i) + 1]; ++k) {
      const double* g = vector.data() + 3 * std::size_t(k);
      const double s = d[term[std::size_t(k)]];
      for (int c = 0; c < 3; ++c) y[3 * i + c] += s * g[c];
    }
}

std::vector<Eigen::Matrix3d> blockDiagonalInverses(const BlockSparseMatrix3f& A) {
  const int n = A.rows();
  std::vector<Eigen::Matrix3d> inverse(static_cast<std::size_t>(n));
#pragma omp parallel for schedule(static, 1024)
  for (int i = 0; i < n; ++i) {
    Eigen::Matrix3d D = Eigen::Matrix3d::Zero();
    for (int k = A.rowStart[std::size_t(i)]; k < A.rowStart[std::size_t(i) + 1]; ++k)
      if (A.column[std::size_t(k)] == i) {
        const float* v = A.values.data() + 9 * std::size_t(k);
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c) D(r, c) = double(v[3 * r + c]);
      }
    const double scale = D.cwiseAbs().maxCoeff();
    if (scale > 0 && std::abs(D.determinant()) > 1e-12 * scale * scale * scale) {
      inverse[std::size_t(i)] = D.inverse();
    } else {
      inverse[std::size_t(i)].setZero();
      for (int r = 0; r < 3; ++r) inverse[std::size_t(i)](r, r) = D(r, r) > 0 ? 1.0 / D(r, r) : 0.0;
    }
  }
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
  const Eigen::Index m = p.size();
#pragma omp parallel for schedule(static, 4096)
  for (Eigen::Index k = 0; k < m; ++k) p[k] = z[k] + beta * p[k];
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
  double rr = 0, rz = 0;
#pragma omp parallel for schedule(static, 512) reduction(+ : rr, rz)
  for (int i = 0; i < n; ++i) {
    const Eigen::Index o = 3 * Eigen::Index(i);
    const Eigen::Vector3d ri = b.segment<3>(o) - q.segment<3>(o);
    const Eigen::Vector3d zi = inverse[std::size_t(i)] * ri;
    r.segment<3>(o) = ri;
    z.segment<3>(o) = zi;
    p.segment<3>(o) = zi;
    rr += ri.squaredNorm();
    rz += ri.dot(zi);
  }
  const double threshold = tolerance * bNorm;
  double rNorm = std::sqrt(rr);
  int it = 0;
  while (rNorm > threshold && it < maxIterations) {
    A.multiply(p, q);
    double pq = 0;
#pragma omp parallel for schedule(static, 4096) reduction(+ : pq)
    for (Eigen::Index k = 0; k < m; ++k) pq += p[k] * q[k];
    if (!(pq > 0.0)) break;  // no descent left (semi-definite direction)
    const double alpha = rz / pq;
    double rrNew = 0, rzNew = 0;
#pragma omp parallel for schedule(static, 512) reduction(+ : rrNew, rzNew)
    for (int i = 0; i < n; ++i) {
      const Eigen::Index o = 3 * Eigen::Index(i);
      x.segment<3>(o) += alpha * p.segment<3>(o);
      const Eigen::Vector3d ri = r.segment<3>(o) - alpha * q.segment<3>(o);
      const Eigen::Vector3d zi = inverse[std::size_t(i)] * ri;
      r.segment<3>(o) = ri;
      z.segment<3>(o) = zi;
      rrNew += ri.squaredNorm();
      rzNew += ri.dot(zi);
    }
    ++it;
    rNorm = std::sqrt(rrNew);
    if (rNorm <= threshold) break;
    nextDirection(rzNew, rz, z, p);
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
  double rr = 0;
#pragma omp parallel for schedule(static, 4096) reduction(+ : rr)
  for (Eigen::Index k = 0; k < m; ++k) {
    r[k] = b[k] - q[k];
    rr += r[k] * r[k];
  }
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
    double pq = 0;
#pragma omp parallel for schedule(static, 4096) reduction(+ : pq)
    for (Eigen::Index k = 0; k < m; ++k) pq += p[k] * q[k];
    if (!(pq > 0.0)) break;
    const double alpha = rz / pq;
    double rrNew = 0;
#pragma omp parallel for schedule(static, 4096) reduction(+ : rrNew)
    for (Eigen::Index k = 0; k < m; ++k) {
      x[k] += alpha * p[k];
      r[k] -= alpha * q[k];
      rrNew += r[k] * r[k];
    }
    ++it;
    rNorm = std::sqrt(rrNew);
    if (rNorm <= threshold) break;
    const double rzNew = M.apply(r, z);
    nextDirection(rzNew, rz, z, p);
  }
  return finished(it, rNorm, bNorm);
}

}  // namespace repose
