#include "mesh_topology.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cstdint>
#include <numeric>
#include <stdexcept>
#include <string>
#include <unordered_map>

namespace repose {

void checkTriangleIndices(const MeshVertices& V, const MeshTriangles& F) {
  for (Eigen::Index t = 0; t < F.rows(); ++t)
    for (int c = 0; c < 3; ++c)
      if (F(t, c) < 0 || F(t, c) >= V.rows())
        throw std::invalid_argument("triangle " + std::to_string(t) + " refers to vertex " + std::to_string(F(t, c)) +
                                    " of a mesh with " + std::to_string(V.rows()) + " vertices");
}

namespace {

/// For each vertex, the index of the first vertex with the same coordinates.
std::vector<int> weldExact(const MeshVertices& V) {
  std::vector<int> order(V.rows());
  std::iota(order.begin(), order.end(), 0);
  auto less = [&](int a, int b) {
    for (int c = 0; c < 3; ++c)
      if (V(a, c) != V(b, c)) return V(a, c) < V(b, c);
    return a < b;
  };
  std::sort(order.begin(), order.end(), less);
  std::vector<int> rep(V.rows());
  for (std::size_t i = 0; i < order.size(); ++i) {
    const int v = order[i];
    rep[v] = (i > 0 && V.row(v) == V.row(order[i - 1])) ? rep[order[i - 1]] : v;
  }
  return rep;
}

struct UnionFind {
  std::vector<int> parent;
  explicit UnionFind(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  int find(int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void unite(int a, int b) {
    a = find(a), b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

/// Component id (dense, in order of first triangle) of every triangle.
std::vector<int> triangleComponents(const MeshVertices& V, const MeshTriangles& F, std::size_t& count) {
  const std::vector<int> rep = weldExact(V);
  UnionFind uf(V.rows());
  for (Eigen::Index t = 0; t < F.rows(); ++t) {
    uf.unite(rep[F(t, 0)], rep[F(t, 1)]);
    uf.unite(rep[F(t, 0)], rep[F(t, 2)]);
  }
  std::unordered_map<int, int> id;
  std::vector<int> comp(F.rows());
  for (Eigen::Index t = 0; t < F.rows(); ++t) {
    const int root = uf.find(rep[F(t, 0)]);
    auto it = id.emplace(root, int(id.size())).first;
    comp[t] = it->second;
  }
  count = id.size();
  return comp;
}

}  // namespace

MeshTopology analyzeMeshTopology(const MeshVertices& V, const MeshTriangles& F) {
  checkTriangleIndices(V, F);
  MeshTopology r;
  r.vertices = std::size_t(V.rows());
  r.triangles = std::size_t(F.rows());
  const std::vector<int> rep = weldExact(V);
  std::vector<std::uint64_t> edges;
  edges.reserve(3 * F.rows());
  for (Eigen::Index t = 0; t < F.rows(); ++t) {
    const int a = rep[F(t, 0)], b = rep[F(t, 1)], c = rep[F(t, 2)];
    if (a == b || b == c || a == c) {
      ++r.degenerateTriangles;
      continue;
    }
    for (auto [p, q] : {std::pair<int, int>{a, b}, {b, c}, {c, a}})
      edges.push_back((std::uint64_t(std::min(p, q)) << 32) | std::uint64_t(std::max(p, q)));
  }
  std::sort(edges.begin(), edges.end());
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i;
    while (j < edges.size() && edges[j] == edges[i]) ++j;
    if (j - i == 1) ++r.boundaryEdges;
    if (j - i > 2) ++r.nonManifoldEdges;
    i = j;
  }
  triangleComponents(V, F, r.components);
  if (F.rows() > 0) {
    Eigen::RowVector3d centroid = Eigen::RowVector3d::Zero();
    for (Eigen::Index t = 0; t < F.rows(); ++t)
      for (int c = 0; c < 3; ++c) centroid += V.row(F(t, c));
    centroid /= double(3 * F.rows());
    double six = 0;
    for (Eigen::Index t = 0; t < F.rows(); ++t) {
      const Eigen::Vector3d a = (V.row(F(t, 0)) - centroid).transpose(), b = (V.row(F(t, 1)) - centroid).transpose(),
                            c = (V.row(F(t, 2)) - centroid).transpose();
      six += a.dot(b.cross(c));
    }
    r.enclosedVolume = std::abs(six) / 6.0;
  }
  return r;
}

std::vector<TriangleMesh> splitConnectedComponents(const MeshVertices& V, const MeshTriangles& F) {
  checkTriangleIndices(V, F);
  std::size_t count = 0;
  const std::vector<int> comp = triangleComponents(V, F, count);
  std::vector<std::vector<Eigen::Index>> tris(count);
  for (Eigen::Index t = 0; t < F.rows(); ++t) tris[comp[t]].push_back(t);
  std::vector<TriangleMesh> out(count);
  std::vector<int> local(V.rows(), -1);
  for (std::size_t c = 0; c < count; ++c) {
    std::vector<int> used;
    for (Eigen::Index t : tris[c])
      for (int k = 0; k < 3; ++k)
        if (local[F(t, k)] < 0) {
          local[F(t, k)] = int(used.size());
          used.push_back(F(t, k));
        }
    TriangleMesh& m = out[c];
    m.V.resize(Eigen::Index(used.size()), 3);
    for (std::size_t i = 0; i < used.size(); ++i) m.V.row(Eigen::Index(i)) = V.row(used[i]);
    m.F.resize(Eigen::Index(tris[c].size()), 3);
    for (std::size_t i = 0; i < tris[c].size(); ++i)
      for (int k = 0; k < 3; ++k) m.F(Eigen::Index(i), k) = local[F(tris[c][i], k)];
    for (int v : used) local[v] = -1;
  }
  return out;
}

}  // namespace repose
