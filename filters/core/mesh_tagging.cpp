#include "mesh_tagging.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>
#include <utility>

#include "parallel_for.h"

namespace repose {

namespace {

void checkLabels(const LabelVolume& labels) {
  if (labels.grid.voxelCount() == 0 || labels.data.size() != labels.grid.voxelCount())
    throw std::invalid_argument("label volume: data size (" + std::to_string(labels.data.size()) +
                                ") does not match the grid (" + std::to_string(labels.grid.voxelCount()) +
                                " voxels)");
}

inline int boneOf(std::int32_t label, const std::vector<int>& boneOfLabel) {
  return (label >= 0 && std::size_t(label) < boneOfLabel.size()) ? boneOfLabel[std::size_t(label)] : -1;
}

// Nearest voxel of a physical point, clamped to the grid.
inline std::size_t nearestVoxel(const ImageGrid& g, const Eigen::Vector3d& x) {
  const Eigen::Vector3d f = g.physicalToIndex(x);
  int ijk[3];
  for (int c = 0; c < 3; ++c) ijk[c] = std::clamp(int(std::lround(f[c])), 0, g.dims[c] - 1);
  return g.linearIndex(ijk[0], ijk[1], ijk[2]);
}

int findRoot(std::vector<int>& parent, int x) {
  while (parent[x] != x) {
    parent[x] = parent[parent[x]];
    x = parent[x];
  }
  return x;
}

}  // namespace

// Face seeds sit this many voxels from the bone voxel centre (< 0.5: still nearest to it).
constexpr double kFaceSeedOffset = 0.45;

Points boneSeedPoints(const LabelVolume& labels, const std::vector<int>& boneOfLabel, const MaskVolume& mask,
                      int surfaceStep, int interiorStep) {
  checkLabels(labels);
  if (!labels.grid.sameGridAs(mask.grid) || mask.data.size() != labels.data.size())
    throw std::invalid_argument("bone seeds: the mask is not on the label volume's grid");
  if (surfaceStep < 1 || interiorStep < 1)
    throw std::invalid_argument("bone seeds: the surface and interior steps must be >= 1 voxel");
  const ImageGrid& g = labels.grid;
  const auto& d = g.dims;
  const int s = surfaceStep, t = interiorStep;
  const int nbk = (d[2] + s - 1) / s, nbj = (d[1] + s - 1) / s, nbi = (d[0] + s - 1) / s;

  auto boneAt = [&](int i, int j, int k) { return boneOf(labels.at(i, j, k), boneOfLabel); };
  // A bone voxel is on the bone's boundary when a 6-neighbour is another bone, not bone, or outside.
  auto onBoundary = [&](int i, int j, int k, int b) {
    const int n[6][3] = {{i - 1, j, k}, {i + 1, j, k}, {i, j - 1, k}, {i, j + 1, k}, {i, j, k - 1}, {i, j, k + 1}};
    for (const auto& q : n)
      if (!g.contains(q[0], q[1], q[2]) || boneAt(q[0], q[1], q[2]) != b) return true;
    return false;
  };

  // One slab of surface blocks per task; results concatenated in slab order (deterministic).
  std::vector<std::vector<Eigen::Vector3d>> perSlab(static_cast<std::size_t>(nbk));
  parallelFor(std::size_t(nbk), [&](std::size_t kb0, std::size_t kb1) {
    struct Pick { int bone; double dist2; Eigen::Vector3d ijk; };
    std::vector<Pick> picks;
    for (std::size_t kb = kb0; kb < kb1; ++kb) {
      auto& outPts = perSlab[kb];
      for (int jb = 0; jb < nbj; ++jb)
        for (int ib = 0; ib < nbi; ++ib) {
          picks.clear();
          const Eigen::Vector3d centre((ib + 0.5) * s - 0.5, (jb + 0.5) * s - 0.5, (kb + 0.5) * s - 0.5);
          for (int k = int(kb) * s; k < std::min(d[2], int(kb + 1) * s); ++k)
            for (int j = jb * s; j < std::min(d[1], (jb + 1) * s); ++j)
              for (int i = ib * s; i < std::min(d[0], (ib + 1) * s); ++i) {
                const int b = boneAt(i, j, k);
                if (b < 0 || !mask.at(i, j, k)) continue;
                const bool boundary = onBoundary(i, j, k, b);
                if (!boundary) {
                  if (i % t == 0 && j % t == 0 && k % t == 0) outPts.push_back(g.indexToPhysical(Eigen::Vector3d(i, j, k)));
                  continue;
                }
                // Per block and bone, the boundary voxel nearest the block centre.
                const Eigen::Vector3d ijk(i, j, k);
                const double dist2 = (ijk - centre).squaredNorm();
                auto it = std::find_if(picks.begin(), picks.end(), [&](const Pick& p) { return p.bone == b; });
                if (it == picks.end()) picks.push_back({b, dist2, ijk});
                else if (dist2 < it->dist2) *it = {b, dist2, ijk};
              }
          for (const auto& p : picks) {
            outPts.push_back(g.indexToPhysical(p.ijk));
            // Seeds just inside the bone's voxel faces (the nearest voxel stays the bone voxel, so
            // they are fixed to it): the mesh then follows the bone's boundary, and the tets that
            // cover bone voxels have only fixed nodes and move exactly rigidly.
            const int i = int(p.ijk.x()), j = int(p.ijk.y()), k = int(p.ijk.z());
            const int n[6][3] = {{-1, 0, 0}, {1, 0, 0}, {0, -1, 0}, {0, 1, 0}, {0, 0, -1}, {0, 0, 1}};
            for (const auto& o : n) {
              const int qi = i + o[0], qj = j + o[1], qk = k + o[2];
              if (g.contains(qi, qj, qk) && boneAt(qi, qj, qk) == p.bone) continue;
              outPts.push_back(g.indexToPhysical(p.ijk + kFaceSeedOffset * Eigen::Vector3d(o[0], o[1], o[2])));
            }
          }
        }
    }
  }, 1);

  std::size_t total = 0;
  for (const auto& v : perSlab) total += v.size();
  Points seeds(Eigen::Index(total), 3);
  Eigen::Index row = 0;
  for (const auto& v : perSlab)
    for (const auto& p : v) seeds.row(row++) = p.transpose();
  return seeds;
}

void tagMesh(TetMesh& mesh, const LabelVolume& labels, const std::vector<int>& boneOfLabel) {
  checkLabels(labels);
  const Eigen::Index nv = mesh.nodes.rows(), nt = mesh.tets.rows();
  if (nt > 0 && (mesh.tets.minCoeff() < 0 || mesh.tets.maxCoeff() >= nv))
    throw std::invalid_argument("tag mesh: a tet refers to a node index outside [0, " + std::to_string(nv) + ")");
  mesh.fixedBone.assign(std::size_t(nv), -1);
  mesh.tetLabel.assign(std::size_t(nt), 0);
  const ImageGrid& g = labels.grid;
  parallelFor(std::size_t(nv), [&](std::size_t b, std::size_t e) {
    for (std::size_t v = b; v < e; ++v)
      mesh.fixedBone[v] = boneOf(labels.data[nearestVoxel(g, mesh.nodes.row(Eigen::Index(v)).transpose())], boneOfLabel);
  });
  parallelFor(std::size_t(nt), [&](std::size_t b, std::size_t e) {
    for (std::size_t t = b; t < e; ++t) {
      Eigen::Vector3d c = Eigen::Vector3d::Zero();
      for (int k = 0; k < 4; ++k) c += mesh.nodes.row(mesh.tets(Eigen::Index(t), k)).transpose();
      mesh.tetLabel[t] = labels.data[nearestVoxel(g, 0.25 * c)];
    }
  });
}

ContactReport freeBoneContacts(TetMesh& mesh) {
  const Eigen::Index nv = mesh.nodes.rows(), nt = mesh.tets.rows();
  if (mesh.fixedBone.size() != std::size_t(nv))
    throw std::invalid_argument("free bone contacts: the mesh is not tagged; call tagMesh first");
  ContactReport report;
  std::vector<std::uint8_t> freed(std::size_t(nv), 0);
  // An edge is shared by several tets: collect and deduplicate (few: only those across joints).
  std::vector<std::pair<int, int>> edges;
  for (Eigen::Index t = 0; t < nt; ++t)
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) {
        const int u = mesh.tets(t, a), v = mesh.tets(t, b);
        const int bu = mesh.fixedBone[std::size_t(u)], bv = mesh.fixedBone[std::size_t(v)];
        if (bu < 0 || bv < 0 || bu == bv) continue;
        edges.emplace_back(std::min(u, v), std::max(u, v));
        freed[std::size_t(u)] = freed[std::size_t(v)] = 1;
      }
  std::sort(edges.begin(), edges.end());
  report.edgesBetweenBones = int(std::unique(edges.begin(), edges.end()) - edges.begin());
  if (report.edgesBetweenBones == 0) return report;

  // A bone must keep some fixed node, or it could not be posed at all.
  int bones = 0;
  for (int b : mesh.fixedBone) bones = std::max(bones, b + 1);
  std::vector<int> kept(std::size_t(bones), 0);
  for (Eigen::Index v = 0; v < nv; ++v)
    if (mesh.fixedBone[std::size_t(v)] >= 0 && !freed[std::size_t(v)]) ++kept[std::size_t(mesh.fixedBone[std::size_t(v)])];
  for (Eigen::Index v = 0; v < nv; ++v) {
    const int b = mesh.fixedBone[std::size_t(v)];
    if (b < 0 || !freed[std::size_t(v)]) continue;
    if (kept[std::size_t(b)] == 0) continue;  // the whole bone touches another one: keep it rigid
    mesh.fixedBone[std::size_t(v)] = -1;
    ++report.nodesFreed;
  }
  for (int b = 0; b < bones; ++b)
    if (kept[std::size_t(b)] == 0 &&
        std::find(mesh.fixedBone.begin(), mesh.fixedBone.end(), b) != mesh.fixedBone.end())
      ++report.bonesKept;
  return report;
}

ComponentReport keepBoneComponents(TetMesh& mesh) {
  const int nv = int(mesh.nodes.rows()), nt = int(mesh.tets.rows());
  if (mesh.fixedBone.size() != std::size_t(nv))
    throw std::invalid_argument("keep bone components: the mesh is not tagged (fixedBone has " +
                                std::to_string(mesh.fixedBone.size()) + " entries for " + std::to_string(nv) +
                                " nodes); call tagMesh first");
  if (!mesh.tetLabel.empty() && mesh.tetLabel.size() != std::size_t(nt))
    throw std::invalid_argument("keep bone components: tetLabel does not have one entry per tet");
  if (nt > 0 && (mesh.tets.minCoeff() < 0 || mesh.tets.maxCoeff() >= nv))
    throw std::invalid_argument("keep bone components: a tet refers to a node index outside the mesh");

  std::vector<int> parent(static_cast<std::size_t>(nv));
  std::iota(parent.begin(), parent.end(), 0);
  for (int t = 0; t < nt; ++t) {
    const int r0 = findRoot(parent, mesh.tets(t, 0));
    for (int c = 1; c < 4; ++c) {
      const int r = findRoot(parent, mesh.tets(t, c));
      if (r != r0) parent[r] = r0;
    }
  }
  // Per root: has a tet, has a bone node.
  std::vector<std::uint8_t> hasTet(std::size_t(nv), 0), hasBone(std::size_t(nv), 0);
  for (int t = 0; t < nt; ++t) hasTet[findRoot(parent, mesh.tets(t, 0))] = 1;
  for (int v = 0; v < nv; ++v)
    if (mesh.fixedBone[v] >= 0) hasBone[findRoot(parent, v)] = 1;

  ComponentReport report;
  for (int v = 0; v < nv; ++v)
    if (parent[v] == v && hasTet[v]) (hasBone[v] ? report.componentsKept : report.componentsDropped)++;
  if (report.componentsKept == 0)
    throw std::invalid_argument("the tet mesh has no node inside a bone: check that the skeleton's labels "
                                "occur in the label volume and inside the body mask");

  std::vector<int> newIndex(std::size_t(nv), -1);
  int keptNodes = 0;
  for (int v = 0; v < nv; ++v) {
    const int r = findRoot(parent, v);
    if (hasTet[r] && hasBone[r]) newIndex[v] = keptNodes++;
  }
  int keptTets = 0;
  for (int t = 0; t < nt; ++t)
    if (newIndex[mesh.tets(t, 0)] >= 0) ++keptTets;

  TetMesh out;
  out.nodes.resize(keptNodes, 3);
  out.fixedBone.resize(std::size_t(keptNodes));
  for (int v = 0; v < nv; ++v)
    if (newIndex[v] >= 0) {
      out.nodes.row(newIndex[v]) = mesh.nodes.row(v);
      out.fixedBone[newIndex[v]] = mesh.fixedBone[v];
    }
  out.tets.resize(keptTets, 4);
  int row = 0;
  for (int t = 0; t < nt; ++t) {
    if (newIndex[mesh.tets(t, 0)] < 0) continue;
    for (int c = 0; c < 4; ++c) out.tets(row, c) = newIndex[mesh.tets(t, c)];
    if (!mesh.tetLabel.empty()) out.tetLabel.push_back(mesh.tetLabel[t]);
    ++row;
  }
  report.nodesDropped = nv - keptNodes;
  report.tetsDropped = nt - keptTets;
  mesh = std::move(out);
  return report;
}

}  // namespace repose
