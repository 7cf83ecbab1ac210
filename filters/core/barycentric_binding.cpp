#include "barycentric_binding.h"

#include <atomic>
#include <stdexcept>
#include <string>

#include "parallel_for.h"
#include "tet_locator.h"

namespace repose {

Binding bindPoints(const Points& restNodes, const Tets& tets, const Points& points) {
  if (tets.rows() == 0) throw std::invalid_argument("bind points: the tet mesh has no tets");
  if (!points.allFinite()) throw std::invalid_argument("bind points: non-finite point coordinates");
  const TetLocator locator(restNodes, tets);  // validates indices and nodes
  const std::size_t n = std::size_t(points.rows());
  Binding b;
  b.tet.assign(n, -1);
  b.bary.resize(Eigen::Index(n), 4);
  std::atomic<std::size_t> outside{0};
  parallelFor(n, [&](std::size_t begin, std::size_t end) {
    std::size_t localOutside = 0;
    for (std::size_t p = begin; p < end; ++p) {
      const Eigen::Vector3d x = points.row(Eigen::Index(p)).transpose();
      TetLocator::Hit hit;
      if (!locator.findContaining(x, hit)) {
        hit = locator.findNearest(x);
        ++localOutside;
      }
      b.tet[p] = hit.tet;
      b.bary.row(Eigen::Index(p)) = hit.bary.cast<float>().transpose();
    }
    outside += localOutside;
  }, 256);
  b.outsideCount = outside.load();
  return b;
}

void applyBinding(const Binding& binding, const Tets& tets, const Points& posedNodes, Points& posedPoints) {
  const std::size_t n = binding.tet.size();
  if (std::size_t(binding.bary.rows()) != n)
    throw std::invalid_argument("apply binding: " + std::to_string(n) + " tets but " +
                                std::to_string(binding.bary.rows()) + " barycentric rows");
  posedPoints.resize(Eigen::Index(n), 3);
  const Eigen::Index nT = tets.rows(), nV = posedNodes.rows();
  // Validated inside the pass (cheap) rather than scanning the whole mesh on every pose.
  std::atomic<std::size_t> firstBad{n};
  parallelFor(n, [&](std::size_t begin, std::size_t end) {
    for (std::size_t p = begin; p < end; ++p) {
      const int t = binding.tet[p];
      if (t < 0 || t >= nT || tets.row(t).minCoeff() < 0 || tets.row(t).maxCoeff() >= nV) {
        std::size_t cur = firstBad.load();
        while (p < cur && !firstBad.compare_exchange_weak(cur, p)) {
        }
        continue;
      }
      Eigen::RowVector3d x = Eigen::RowVector3d::Zero();
      for (int a = 0; a < 4; ++a) x += double(binding.bary(Eigen::Index(p), a)) * posedNodes.row(tets(t, a));
      posedPoints.row(Eigen::Index(p)) = x;
    }
  }, 4096);
  if (firstBad.load() < n) {
    const std::size_t p = firstBad.load();
    throw std::invalid_argument("apply binding: point " + std::to_string(p) + " is bound to tet " +
                                std::to_string(binding.tet[p]) + ", which is not a valid tet of the " +
                                std::to_string(nT) + "-tet mesh with " + std::to_string(nV) +
                                " posed nodes (binding made for another mesh?)");
  }
}

}  // namespace repose
