#include "winding_inside.h"

#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>

#include "lattice_crossings.h"
#include "parallel_for.h"
#include "winding_number.h"

namespace repose {
namespace {

/// The index box of the soup and its rows along i.
struct Box : IndexBox {
  std::size_t nx = 0, ny = 0, rows = 0;  ///< rows: ny * nz lines of voxels along i
};

/// Index box of the vertices clipped to the grid (dims 0 when it misses the grid).
Box indexBox(const std::vector<Eigen::Vector3d>& points, const ImageGrid& grid, bool& cut, bool& outside) {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
  for (const auto& p : points) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  Box b;
  cut = outside = false;
  for (int a = 0; a < 3; ++a) {
    outside |= hi[a] < -0.5 || lo[a] > grid.dims[a] - 0.5;
    const int first = std::max(0, int(std::ceil(lo[a])));
    const int last = std::min(grid.dims[a] - 1, int(std::floor(hi[a])));
    cut |= lo[a] < -0.5 || hi[a] > grid.dims[a] - 0.5;
    b.min[a] = first;
    b.dims[a] = std::max(0, last - first + 1);
  }
  if (b.dims[0] == 0 || b.dims[1] == 0 || b.dims[2] == 0) b.dims = {0, 0, 0};
  b.nx = std::size_t(b.dims[0]), b.ny = std::size_t(b.dims[1]);
  b.rows = b.ny * std::size_t(b.dims[2]);
  return b;
}

/// Box-local i range [lo, hi] of row (j, k) within `radius` mm of `centre` (empty: lo > hi).
std::array<int, 2> rowInBall(const ImageGrid& g, const Box& box, int j, int k, const Eigen::Vector3d& centre,
                             double radius) {
  const Eigen::Vector3d axis = g.direction.col(0) * g.spacing.x();
  const Eigen::Vector3d d = g.indexToPhysical(Eigen::Vector3d(box.min[0], j, k)) - centre;
  const double qa = axis.squaredNorm(), qb = axis.dot(d), qc = d.squaredNorm() - radius * radius;
  const double disc = qb * qb - qa * qc;
  if (disc < 0) return {1, 0};
  const double root = std::sqrt(disc);
  return {std::max(0, int(std::ceil((-qb - root) / qa))), std::min(int(box.nx) - 1, int(std::floor((-qb + root) / qa)))};
}

/// Per-row results, summed in row order afterwards so the totals do not depend on the threads.
struct RowTally {
  std::size_t inside = 0, overlap = 0, evaluated = 0, evaluatedInside = 0;
  double windingInside = 0;
};

}  // namespace

ClosingCones closingCones(const MeshVertices& V, const MeshTriangles& F) {
  const std::vector<std::vector<std::array<int, 2>>> chain = boundaryChain(V, F);  // checks the indices
  ClosingCones c;
  std::size_t edges = 0;
  for (const auto& piece : chain) edges += piece.size();
  c.V.resize(V.rows() + Eigen::Index(chain.size()), 3);
  c.V.topRows(V.rows()) = V;
  c.F.resize(Eigen::Index(edges), 3);
  Eigen::Index t = 0;
  for (std::size_t p = 0; p < chain.size(); ++p) {
    Eigen::Vector3d apex = Eigen::Vector3d::Zero();
    for (const auto& e : chain[p]) apex += V.row(e[0]).transpose();  // each vertex leaves as often as it arrives
    apex /= double(chain[p].size());
    double radius = 0;
    for (const auto& e : chain[p]) radius = std::max(radius, (V.row(e[0]).transpose() - apex).norm());
    const int a = int(V.rows() + Eigen::Index(p));
    c.V.row(a) = apex.transpose();
    for (const auto& e : chain[p]) c.F.row(t++) << a, e[1], e[0];
    c.apex.push_back(apex);
    c.radius.push_back(radius);
  }
  return c;
}

WindingInside insideByWindingNumber(const MeshVertices& V, const MeshTriangles& F, const ImageGrid& grid,
                                    const WindingInsideOptions& options) {
  if (grid.dims[0] <= 0 || grid.dims[1] <= 0 || grid.dims[2] <= 0) throw std::invalid_argument("the voxel grid is empty");
  if (!(options.holeReach >= 2.0)) throw std::invalid_argument("the hole reach must be at least 2");
  if (V.rows() == 0 || F.rows() == 0) throw std::invalid_argument("the surface has no triangles");
  if (!V.allFinite()) throw std::invalid_argument("the surface has a vertex that is not a finite number");
  const ClosingCones cones = closingCones(V, F);  // checks the indices
  std::vector<Eigen::Vector3d> points(std::size_t(cones.V.rows()));
  for (Eigen::Index v = 0; v < cones.V.rows(); ++v)
    points[std::size_t(v)] = grid.physicalToIndex(cones.V.row(v).transpose());
  WindingInside r;
  r.cones = cones.apex.size();
  const Box box = indexBox({points.begin(), points.begin() + V.rows()}, grid, r.cutByGrid, r.outsideGrid);
  if (box.count() == 0) return r;
  r.boxMin = box.min;
  r.boxDims = box.dims;

  // 1. Crossings of the closed chain S + C with every row, bucketed by row.
  const int flip = grid.direction.determinant() < 0 ? -1 : 1;
  std::vector<RowCrossing> crossings;
  auto at = [&](int v) -> const Eigen::Vector3d& { return points[std::size_t(v)]; };
  for (Eigen::Index t = 0; t < F.rows(); ++t) crossRows(at(F(t, 0)), at(F(t, 1)), at(F(t, 2)), 0, box, crossings);
  for (Eigen::Index t = 0; t < cones.F.rows(); ++t)
    crossRows(at(cones.F(t, 0)), at(cones.F(t, 1)), at(cones.F(t, 2)), 0, box, crossings);
  std::vector<std::size_t> first(box.rows + 1, 0);
  for (const RowCrossing& c : crossings) ++first[c.row + 1];
  for (std::size_t row = 0; row < box.rows; ++row) first[row + 1] += first[row];
  std::vector<RowCrossing> byRow(crossings.size());
  {
    std::vector<std::size_t> fill(first.begin(), first.end() - 1);
    for (const RowCrossing& c : crossings) byRow[fill[c.row]++] = c;
  }

  // 2. The cones' winding number, evaluated near them only.
  std::unique_ptr<WindingNumberTree> capTree;
  std::vector<std::vector<std::size_t>> conesAtK(std::size_t(box.dims[2]));
  if (cones.F.rows() > 0) {
    WindingNumberOptions o;
    o.beta = options.beta;
    capTree = std::make_unique<WindingNumberTree>(cones.V, cones.F, o);
    for (std::size_t c = 0; c < cones.apex.size(); ++c)
      for (int k = 0; k < box.dims[2]; ++k) {
        const double reach = options.holeReach * cones.radius[c];
        const double dz = std::abs(grid.physicalToIndex(cones.apex[c]).z() - (box.min[2] + k));
        if (dz * grid.spacing.minCoeff() <= reach) conesAtK[std::size_t(k)].push_back(c);
      }
  }

  // 3. Row by row: w of the closed chain from the crossings after each voxel, minus w_C near the cones.
  r.inside.assign(box.count(), 0);
  std::vector<RowTally> tally(box.rows);
  parallelFor(
      box.rows,
      [&](std::size_t row0, std::size_t row1) {
        std::vector<int> closed(box.nx + 1);
        std::vector<char> near(box.nx);
        for (std::size_t row = row0; row < row1; ++row) {
          const int j = box.min[1] + int(row % box.ny), k = box.min[2] + int(row / box.ny);
          std::fill(closed.begin(), closed.end(), 0);
          for (std::size_t c = first[row]; c < first[row + 1]; ++c) closed[std::size_t(byRow[c].last)] += flip * byRow[c].sign;
          for (std::size_t i = box.nx - 1; i-- > 0;) closed[i] += closed[i + 1];
          std::fill(near.begin(), near.end(), 0);
          for (std::size_t c : conesAtK[std::size_t(k - box.min[2])]) {
            const auto span = rowInBall(grid, box, j, k, cones.apex[c], options.holeReach * cones.radius[c]);
            for (int i = span[0]; i <= span[1]; ++i) near[std::size_t(i)] = 1;
          }
          RowTally& s = tally[row];
          std::uint8_t* out = r.inside.data() + row * box.nx;
          for (std::size_t i = 0; i < box.nx; ++i) {
            double w = closed[i];
            if (near[i]) {
              w -= (*capTree)(grid.indexToPhysical(Eigen::Vector3d(double(box.min[0] + int(i)), j, k)));
              ++s.evaluated;
              if (w >= 0.5) ++s.evaluatedInside, s.windingInside += std::min(w, 1.0);
            }
            out[i] = w >= 0.5;
            s.inside += w >= 0.5;
            s.overlap += w >= 1.5;
          }
        }
      },
      16);
  RowTally total;
  for (const RowTally& s : tally) {
    total.inside += s.inside, total.overlap += s.overlap, total.evaluated += s.evaluated;
    total.evaluatedInside += s.evaluatedInside, total.windingInside += s.windingInside;
  }
  r.insideVoxels = total.inside;
  r.overlapVoxels = total.overlap;
  r.evaluatedVoxels = total.evaluated;
  r.meanInsideWinding = r.cones == 0 ? (total.inside > 0 ? 1.0 : 0.0)
                        : total.evaluatedInside > 0 ? total.windingInside / double(total.evaluatedInside)
                                                    : 0.0;
  return r;
}

}  // namespace repose
