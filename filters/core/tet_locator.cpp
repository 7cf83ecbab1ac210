#include "tet_locator.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#include "parallel_for.h"
#include "point_tet_distance.h"

namespace repose {
namespace {

constexpr std::size_t kBlock = 1 << 15;  // fixed reduction blocks keep the grid deterministic

float roundDown(double x) {
  float f = float(x);
  return double(f) > x ? std::nextafter(f, -std::numeric_limits<float>::infinity()) : f;
}
float roundUp(double x) {
  float f = float(x);
  return double(f) < x ? std::nextafter(f, std::numeric_limits<float>::infinity()) : f;
}

}  // namespace

TetLocator::TetLocator(const Points& nodes, const Tets& tets) : nodes_(nodes), tets_(tets) {
  const std::size_t nT = std::size_t(tets.rows());
  if (tets.size() > 0 && (tets.minCoeff() < 0 || tets.maxCoeff() >= nodes.rows()))
    throw std::invalid_argument("tet locator: tet node index out of range [0, " + std::to_string(nodes.rows()) +
                                ")");
  if (!nodes.allFinite()) throw std::invalid_argument("tet locator: non-finite node coordinates");
  if (nT >= (std::size_t(1) << 30)) throw std::invalid_argument("tet locator: more than 2^30 tets");
  if (nT == 0) {
    cellStart_.assign(2, 0);
    return;
  }
  auto tetBox = [&](std::size_t t, Eigen::Vector3d& tlo, Eigen::Vector3d& thi) {
    tlo = nodes.row(tets(Eigen::Index(t), 0)).transpose();
    thi = tlo;
    for (int c = 1; c < 4; ++c) {
      tlo = tlo.cwiseMin(nodes.row(tets(Eigen::Index(t), c)).transpose());
      thi = thi.cwiseMax(nodes.row(tets(Eigen::Index(t), c)).transpose());
    }
  };
  // Bounds and mean tet size, reduced over fixed blocks (same result whatever the thread count).
  const std::size_t nBlocks = (nT + kBlock - 1) / kBlock;
  std::vector<Eigen::Vector3d> blockLo(nBlocks), blockHi(nBlocks);
  std::vector<double> blockExtent(nBlocks, 0.0);
  parallelFor(nBlocks, [&](std::size_t b0, std::size_t b1) {
    for (std::size_t b = b0; b < b1; ++b) {
      Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::max()), hi = -lo;
      double extentSum = 0;
      for (std::size_t t = b * kBlock, e = std::min(nT, (b + 1) * kBlock); t < e; ++t) {
        Eigen::Vector3d tlo, thi;
        tetBox(t, tlo, thi);
        lo = lo.cwiseMin(tlo);
        hi = hi.cwiseMax(thi);
        extentSum += std::cbrt((thi - tlo).cwiseMax(1e-9 * (thi - tlo).maxCoeff()).prod());
      }
      blockLo[b] = lo;
      blockHi[b] = hi;
      blockExtent[b] = extentSum;
    }
  }, 1);
  Eigen::Vector3d lo = blockLo[0], hi = blockHi[0];
  double extentSum = 0;
  for (std::size_t b = 0; b < nBlocks; ++b) {
    lo = lo.cwiseMin(blockLo[b]);
    hi = hi.cwiseMax(blockHi[b]);
    extentSum += blockExtent[b];
  }
  const Eigen::Vector3d ext = (hi - lo).cwiseMax(1e-12);
  // Cells about one (geometric-mean) tet across: few cells per tet and few tets per cell.
  h_ = std::max(extentSum / double(nT), std::cbrt(ext.prod() / double(nT)));
  if (!(h_ > 0)) h_ = ext.maxCoeff();
  for (int a = 0; a < 3; ++a) {
    // Keep the grid bounded for extreme aspect ratios.
    dims_[a] = int(std::min(4096.0, std::max(1.0, std::ceil(ext[a] / h_))));
  }
  lo_ = lo;
  auto cellRange = [&](std::size_t t, Eigen::Array3i& c0, Eigen::Array3i& c1) {
    Eigen::Vector3d tlo, thi;
    tetBox(t, tlo, thi);
    c0 = cellOf(tlo);
    c1 = cellOf(thi);
  };
  const std::size_t nCells = std::size_t(dims_.x()) * dims_.y() * dims_.z();
  {
    std::vector<std::atomic<std::uint32_t>> counts(nCells);
    // Calls visit(t, cell) for every grid cell that tet t's box overlaps, tets in parallel.
    auto forEachTetCell = [&](auto&& visit) {
      parallelFor(nT, [&](std::size_t t0, std::size_t t1) {
        Eigen::Array3i c0, c1;
        for (std::size_t t = t0; t < t1; ++t) {
          cellRange(t, c0, c1);
          for (int z = c0.z(); z <= c1.z(); ++z)
            for (int y = c0.y(); y <= c1.y(); ++y)
              for (int x = c0.x(); x <= c1.x(); ++x) visit(t, cellIndex({x, y, z}));
        }
      }, 4096);
    };
    forEachTetCell([&](std::size_t, std::size_t c) { counts[c].fetch_add(1, std::memory_order_relaxed); });
    cellStart_.assign(nCells + 1, 0);
    for (std::size_t c = 0; c < nCells; ++c) cellStart_[c + 1] = cellStart_[c] + counts[c].load(std::memory_order_relaxed);
    for (std::size_t c = 0; c < nCells; ++c) counts[c].store(0, std::memory_order_relaxed);
    cellTets_.resize(cellStart_.back());
    forEachTetCell([&](std::size_t t, std::size_t c) {
      cellTets_[cellStart_[c] + counts[c].fetch_add(1, std::memory_order_relaxed)] = int(t);
    });
  }
  // Ascending tet ids per cell: findContaining then returns the same tet whatever the threading.
  parallelFor(nCells, [&](std::size_t c0, std::size_t c1) {
    for (std::size_t c = c0; c < c1; ++c) std::sort(cellTets_.begin() + cellStart_[c], cellTets_.begin() + cellStart_[c + 1]);
  }, 4096);
  buildBoundary();
}

void TetLocator::buildBoundary() {
  const std::size_t nT = std::size_t(tets_.rows()), nV = std::size_t(nodes_.rows());
  // Faces bucketed by their smallest node (CSR) and matched within each bucket: a face met once is
  // on the boundary (as in tet_boundary, which lives in the volume library).
  auto faceNodes = [&](std::size_t t, int a) {
    std::array<int, 3> f;
    int n = 0;
    for (int c = 0; c < 4; ++c)
      if (c != a) f[n++] = tets_(Eigen::Index(t), c);
    if (f[0] > f[1]) std::swap(f[0], f[1]);
    if (f[1] > f[2]) std::swap(f[1], f[2]);
    if (f[0] > f[1]) std::swap(f[0], f[1]);
    return f;
  };
  struct Face {
    int b, c;
    std::uint32_t id;  // 4 * tet + local vertex opposite the face
  };
  std::vector<std::uint32_t> offset(nV + 1, 0);
  std::vector<Face> all(4 * nT);
  {
    std::vector<std::atomic<std::uint32_t>> count(nV);
    parallelFor(nT, [&](std::size_t t0, std::size_t t1) {
      for (std::size_t t = t0; t < t1; ++t)
        for (int a = 0; a < 4; ++a) count[std::size_t(faceNodes(t, a)[0])].fetch_add(1, std::memory_order_relaxed);
    }, 8192);
    for (std::size_t v = 0; v < nV; ++v) {
      offset[v + 1] = offset[v] + count[v].load(std::memory_order_relaxed);
      count[v].store(0, std::memory_order_relaxed);
    }
    parallelFor(nT, [&](std::size_t t0, std::size_t t1) {
      for (std::size_t t = t0; t < t1; ++t)
        for (int a = 0; a < 4; ++a) {
          const auto f = faceNodes(t, a);
          const std::size_t v = std::size_t(f[0]);
          all[offset[v] + count[v].fetch_add(1, std::memory_order_relaxed)] = {f[1], f[2], std::uint32_t(4 * t + a)};
        }
    }, 8192);
  }
  std::vector<std::uint8_t> isBoundary(4 * nT, 0);
  parallelFor(nV, [&](std::size_t vb, std::size_t ve) {
    for (std::size_t v = vb; v < ve; ++v) {
      auto b = all.begin() + offset[v], e = all.begin() + offset[v + 1];
      std::sort(b, e, [](const Face& x, const Face& y) {
        return x.b != y.b ? x.b < y.b : x.c != y.c ? x.c < y.c : x.id < y.id;
      });
      for (auto q = b; q != e;) {
        auto r = q + 1;
        while (r != e && r->b == q->b && r->c == q->c) ++r;
        if (r == q + 1) isBoundary[q->id] = 1;
        q = r;
      }
    }
  }, 4096);
  std::vector<Face>().swap(all);
  std::vector<std::uint32_t>().swap(offset);
  faces_.clear();
  faceTet_.clear();
  std::vector<std::uint8_t> onBoundary(nV, 0);
  for (std::size_t id = 0; id < 4 * nT; ++id) {
    if (!isBoundary[id]) continue;
    const auto f = faceNodes(id / 4, int(id % 4));
    faces_.push_back(f);
    faceTet_.push_back(int(id / 4));
    for (int v : f) onBoundary[std::size_t(v)] = 1;
  }
  // Tets around each boundary node.
  nodeTetStart_.assign(nV + 1, 0);
  for (std::size_t t = 0; t < nT; ++t)
    for (int c = 0; c < 4; ++c)
      if (onBoundary[std::size_t(tets_(Eigen::Index(t), c))]) ++nodeTetStart_[std::size_t(tets_(Eigen::Index(t), c)) + 1];
  for (std::size_t v = 0; v < nV; ++v) nodeTetStart_[v + 1] += nodeTetStart_[v];
  nodeTets_.resize(nodeTetStart_.back());
  {
    std::vector<std::size_t> fill(nodeTetStart_.begin(), nodeTetStart_.end() - 1);
    for (std::size_t t = 0; t < nT; ++t)
      for (int c = 0; c < 4; ++c) {
        const std::size_t v = std::size_t(tets_(Eigen::Index(t), c));
        if (onBoundary[v]) nodeTets_[fill[v]++] = int(t);
      }
  }
  // Hierarchy over the boundary faces, split at the median centroid along the longest axis.
  const std::size_t nF = faces_.size();
  faceOrder_.resize(nF);
  std::vector<Eigen::Vector3f> centroids(nF);
  for (std::size_t f = 0; f < nF; ++f) {
    faceOrder_[f] = int(f);
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (int v : faces_[f]) c += nodes_.row(v).transpose();
    centroids[f] = (c / 3.0).cast<float>();
  }
  bvh_.clear();
  bvh_.reserve(2 * (nF / 2 + 1));
  if (nF > 0) buildNode(0, int(nF), centroids);
}

int TetLocator::buildNode(int first, int count, std::vector<Eigen::Vector3f>& centroids) {
  const int index = int(bvh_.size());
  bvh_.push_back(BvhNode{});
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::max()), hi = -lo;
  Eigen::Vector3f clo = Eigen::Vector3f::Constant(std::numeric_limits<float>::max()), chi = -clo;
  for (int i = first; i < first + count; ++i) {
    const int f = faceOrder_[std::size_t(i)];
    for (int v : faces_[std::size_t(f)]) {
      lo = lo.cwiseMin(nodes_.row(v).transpose());
      hi = hi.cwiseMax(nodes_.row(v).transpose());
    }
    clo = clo.cwiseMin(centroids[std::size_t(f)]);
    chi = chi.cwiseMax(centroids[std::size_t(f)]);
  }
  for (int a = 0; a < 3; ++a) {
    bvh_[std::size_t(index)].box[a] = roundDown(lo[a]);
    bvh_[std::size_t(index)].box[3 + a] = roundUp(hi[a]);
  }
  constexpr int kLeafFaces = 4;
  if (count <= kLeafFaces) {
    bvh_[std::size_t(index)].right = -1;
    bvh_[std::size_t(index)].first = first;
    bvh_[std::size_t(index)].count = count;
    return index;
  }
  int axis = 0;
  (chi - clo).maxCoeff(&axis);
  const int half = count / 2;
  std::nth_element(faceOrder_.begin() + first, faceOrder_.begin() + first + half, faceOrder_.begin() + first + count,
                   [&](int x, int y) {
                     const float cx = centroids[std::size_t(x)][axis], cy = centroids[std::size_t(y)][axis];
                     return cx != cy ? cx < cy : x < y;
                   });
  buildNode(first, half, centroids);  // left child = index + 1
  const int right = buildNode(first + half, count - half, centroids);
  bvh_[std::size_t(index)].right = right;
  bvh_[std::size_t(index)].first = first;
  bvh_[std::size_t(index)].count = count;
  return index;
}

Eigen::Array3i TetLocator::cellOf(const Eigen::Vector3d& p) const {
  Eigen::Array3i c;
  for (int a = 0; a < 3; ++a) {
    const double f = std::floor((p[a] - lo_[a]) / h_);
    c[a] = int(std::min(double(dims_[a] - 1), std::max(0.0, f)));
  }
  return c;
}

Eigen::Vector4d TetLocator::barycentric(int t, const Eigen::Vector3d& p) const {
  const Eigen::Vector3d a = nodes_.row(tets_(t, 0)).transpose();
  const Eigen::Vector3d e1 = nodes_.row(tets_(t, 1)).transpose() - a;
  const Eigen::Vector3d e2 = nodes_.row(tets_(t, 2)).transpose() - a;
  const Eigen::Vector3d e3 = nodes_.row(tets_(t, 3)).transpose() - a;
  const Eigen::Vector3d q = p - a;
  const Eigen::Vector3d n23 = e2.cross(e3);
  const double det = e1.dot(n23);
  if (!(std::abs(det) > 0)) return Eigen::Vector4d::Constant(std::numeric_limits<double>::quiet_NaN());
  Eigen::Vector4d l;
  l[1] = q.dot(n23) / det;
  l[2] = e1.dot(q.cross(e3)) / det;
  l[3] = e1.dot(e2.cross(q)) / det;
  l[0] = 1.0 - l[1] - l[2] - l[3];
  return l;
}

double TetLocator::distanceToTet(int t, const Eigen::Vector3d& p) const {
  const Eigen::Vector4d l = barycentric(t, p);
  if (l.allFinite() && l.minCoeff() >= 0) return 0;
  static const int faces[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
  double best = std::numeric_limits<double>::infinity();
  for (const auto& f : faces) {
    const Eigen::Vector3d q = closestPointOnTriangle(p, nodes_.row(tets_(t, f[0])).transpose(),
                                                nodes_.row(tets_(t, f[1])).transpose(),
                                                nodes_.row(tets_(t, f[2])).transpose());
    best = std::min(best, (q - p).squaredNorm());
  }
  return std::sqrt(best);
}

bool TetLocator::findContaining(const Eigen::Vector3d& p, Hit& hit, double eps) const {
  if (tets_.rows() == 0) return false;
  // Points outside the grid clamp to a boundary cell, as the tets there were registered.
  const std::size_t c = cellIndex(cellOf(p));
  for (std::size_t q = cellStart_[c]; q < cellStart_[c + 1]; ++q) {
    const int t = cellTets_[q];
    const Eigen::Vector4d l = barycentric(t, p);
    if (l.allFinite() && l.minCoeff() >= -eps) {
      hit.tet = t;
      hit.bary = l;
      hit.distance = 0;
      return true;
    }
  }
  return false;
}

namespace {
// Tets within 5 % (and a micrometre) of the nearest distance count as equally near, so the
// best-conditioned of them can be chosen.
double tieTolerance(double best) {
  return std::isfinite(best) ? 1e-6 + 0.05 * best : 0.0;
}
}  // namespace

TetLocator::Hit TetLocator::findNearest(const Eigen::Vector3d& p) const {
  Hit hit;
  if (tets_.rows() == 0) return hit;
  if (findContaining(p, hit)) return hit;
  if (bvh_.empty()) return hit;
  auto boxDistance2 = [&](const float* box) {
    double s = 0;
    for (int a = 0; a < 3; ++a) {
      const double d = std::max({double(box[a]) - p[a], p[a] - double(box[3 + a]), 0.0});
      s += d * d;
    }
    return s;
  };
  // The nearest point of the mesh lies on its boundary: nearest boundary face, depth first, nearer
  // child first. A box is skipped unless it could hold a face kSlack nearer than the best so far, so
  // the face found is within (1 + kSlack) of the nearest: far from the body, where a large part of
  // the surface is almost equally near, this visits a few boxes instead of hundreds.
  constexpr double kSlack = 0.02;
  constexpr double kSlack2 = (1 + kSlack) * (1 + kSlack);
  double best2 = std::numeric_limits<double>::infinity();
  int bestFace = -1;
  std::pair<double, int> stack[128];
  int top = 0;
  stack[top++] = {boxDistance2(bvh_[0].box), 0};
  while (top > 0) {
    const auto [d2, n] = stack[--top];
    if (d2 * kSlack2 > best2) continue;
    const BvhNode& node = bvh_[std::size_t(n)];
    if (node.right < 0) {
      for (int i = node.first; i < node.first + node.count; ++i) {
        const int f = faceOrder_[std::size_t(i)];
        const auto& v = faces_[std::size_t(f)];
        const double fd2 = (closestPointOnTriangle(p, nodes_.row(v[0]).transpose(), nodes_.row(v[1]).transpose(),
                                              nodes_.row(v[2]).transpose()) - p).squaredNorm();
        if (fd2 < best2 || (fd2 == best2 && f < bestFace)) {
          best2 = fd2;
          bestFace = f;
        }
      }
      continue;
    }
    const int l = n + 1, r = node.right;
    const double dl = boxDistance2(bvh_[std::size_t(l)].box), dr = boxDistance2(bvh_[std::size_t(r)].box);
    if (top + 2 > 128) continue;  // cannot happen: a median split of < 2^60 faces is shallower
    if (dl <= dr) {
      stack[top++] = {dr, r};
      stack[top++] = {dl, l};
    } else {
      stack[top++] = {dl, l};
      stack[top++] = {dr, r};
    }
  }
  if (bestFace < 0) return hit;
  // Candidates: the tets around the nearest face's nodes (the nearest point is on that face, so every
  // tet touching it is among them). Within the tie band, a well-shaped tet extrapolates stably; a
  // sliver would amplify every later deformation.
  // The true nearest distance is at least best / (1 + kSlack): the band below keeps every candidate
  // within 5 % of it.
  std::vector<std::pair<double, int>> candidates;
  double best = std::sqrt(best2);
  auto band = [](double b) { return tieTolerance(b / (1 + kSlack)) + b * (1 / (1 + kSlack) - 1); };
  for (int v : faces_[std::size_t(bestFace)])
    for (std::size_t q = nodeTetStart_[std::size_t(v)]; q < nodeTetStart_[std::size_t(v) + 1]; ++q) {
      const int t = nodeTets_[q];
      const double d = distanceToTet(t, p);
      if (d > best + band(best)) continue;
      candidates.push_back({d, t});
    }
  for (const auto& c : candidates) best = std::min(best, c.first);
  double hitConditioning = std::numeric_limits<double>::infinity();
  for (const auto& [d, t] : candidates) {
    if (d > best + band(best)) continue;
    const Eigen::Vector4d l = barycentric(t, p);
    if (!l.allFinite()) continue;
    const double conditioning = l.cwiseAbs().maxCoeff();
    if (conditioning < hitConditioning || (conditioning == hitConditioning && t < hit.tet)) {
      hit.tet = t;
      hit.bary = l;
      hit.distance = d;
      hitConditioning = conditioning;
    }
  }
  if (hit.tet < 0) {  // every candidate degenerate: the face's own tet
    hit.tet = faceTet_[std::size_t(bestFace)];
    hit.bary = barycentric(hit.tet, p);
    hit.distance = distanceToTet(hit.tet, p);
  }
  return hit;
}

}  // namespace repose
