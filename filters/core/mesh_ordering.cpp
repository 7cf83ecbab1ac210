#include "mesh_ordering.h"

#include <algorithm>
#include <cstdint>
#include <numeric>
#include <stdexcept>

namespace repose {
namespace {

// Interleaves the low 21 bits of x with two zero bits between each.
std::uint64_t spread(std::uint64_t x) {
  x &= 0x1fffff;
  x = (x | x << 32) & 0x1f00000000ffffULL;
  x = (x | x << 16) & 0x1f0000ff0000ffULL;
  x = (x | x << 8) & 0x100f00f00f00f00fULL;
  x = (x | x << 4) & 0x10c30c30c30c30c3ULL;
  x = (x | x << 2) & 0x1249249249249249ULL;
  return x;
}

struct MortonCoder {
  Eigen::Vector3d lo, scale;
  explicit MortonCoder(const Points& p) {
    lo = p.colwise().minCoeff().transpose();
    const Eigen::Vector3d extent = (p.colwise().maxCoeff().transpose() - lo).cwiseMax(1e-12);
    scale = Eigen::Vector3d::Constant(double((1 << 21) - 1)).cwiseQuotient(extent);
  }
  std::uint64_t operator()(const Eigen::Vector3d& x) const {
    const Eigen::Vector3d q = (x - lo).cwiseProduct(scale).cwiseMax(0.0);
    return spread(std::uint64_t(q.x())) | spread(std::uint64_t(q.y())) << 1 | spread(std::uint64_t(q.z())) << 2;
  }
};

std::vector<int> sortedOrder(const std::vector<std::uint64_t>& codes) {
  std::vector<int> order(codes.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return codes[std::size_t(a)] < codes[std::size_t(b)]; });
  return order;
}

}  // namespace

std::vector<int> reorderMeshSpatially(TetMesh& mesh) {
  const Eigen::Index nv = mesh.nodes.rows(), nt = mesh.tets.rows();
  if (nt > 0 && (mesh.tets.minCoeff() < 0 || mesh.tets.maxCoeff() >= nv))
    throw std::invalid_argument("reorder mesh: a tet refers to a node index outside [0, " + std::to_string(nv) + ")");
  std::vector<int> newIndex(static_cast<std::size_t>(nv));
  if (nv == 0) return newIndex;
  const MortonCoder code(mesh.nodes);

  std::vector<std::uint64_t> nodeCodes(static_cast<std::size_t>(nv));
  for (Eigen::Index v = 0; v < nv; ++v) nodeCodes[std::size_t(v)] = code(mesh.nodes.row(v).transpose());
  const std::vector<int> nodeOrder = sortedOrder(nodeCodes);
  Points nodes(nv, 3);
  std::vector<int> fixedBone(mesh.fixedBone.empty() ? 0 : std::size_t(nv));
  for (Eigen::Index n = 0; n < nv; ++n) {
    const int old = nodeOrder[std::size_t(n)];
    newIndex[std::size_t(old)] = int(n);
    nodes.row(n) = mesh.nodes.row(old);
    if (!fixedBone.empty()) fixedBone[std::size_t(n)] = mesh.fixedBone[std::size_t(old)];
  }

  std::vector<std::uint64_t> tetCodes(static_cast<std::size_t>(nt));
  for (Eigen::Index t = 0; t < nt; ++t) {
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (int k = 0; k < 4; ++k) c += mesh.nodes.row(mesh.tets(t, k)).transpose();
    tetCodes[std::size_t(t)] = code(0.25 * c);
  }
  const std::vector<int> tetOrder = sortedOrder(tetCodes);
  Tets tets(nt, 4);
  std::vector<std::int32_t> tetLabel(mesh.tetLabel.empty() ? 0 : std::size_t(nt));
  for (Eigen::Index t = 0; t < nt; ++t) {
    const int old = tetOrder[std::size_t(t)];
    for (int k = 0; k < 4; ++k) tets(t, k) = newIndex[std::size_t(mesh.tets(old, k))];
    if (!tetLabel.empty()) tetLabel[std::size_t(t)] = mesh.tetLabel[std::size_t(old)];
  }
  mesh.nodes = std::move(nodes);
  mesh.tets = std::move(tets);
  if (!fixedBone.empty()) mesh.fixedBone = std::move(fixedBone);
  if (!tetLabel.empty()) mesh.tetLabel = std::move(tetLabel);
  return newIndex;
}

}  // namespace repose
