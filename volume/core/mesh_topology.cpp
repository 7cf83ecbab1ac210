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
std::vector<int> triangleComponents(const std::vector<int>& rep, const MeshTriangles& F, std::size_t& count) {
  UnionFind uf(rep.size());
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

std::uint64_t edgeKey(int p, int q) {
  return (std::uint64_t(std::min(p, q)) << 32) | std::uint64_t(std::max(p, q));
}

/// One side of a triangle's edge: (from, to) as the triangle orients it.
struct HalfEdge {
  std::uint64_t key;  ///< undirected edge, smaller index first
  int triangle, from, to;
  bool operator<(const HalfEdge& o) const { return key < o.key || (key == o.key && triangle < o.triangle); }
};

/// Half-edges of the non-degenerate triangles over vertex indices `rep` (welded or not), sorted by edge.
std::vector<HalfEdge> halfEdges(const std::vector<int>& rep, const MeshTriangles& F) {
  std::vector<HalfEdge> edges;
  edges.reserve(3 * std::size_t(F.rows()));
  for (Eigen::Index t = 0; t < F.rows(); ++t) {
    const int a = rep[F(t, 0)], b = rep[F(t, 1)], c = rep[F(t, 2)];
    if (a == b || b == c || a == c) continue;
    for (auto [p, q] : {std::pair<int, int>{a, b}, {b, c}, {c, a}}) edges.push_back({edgeKey(p, q), int(t), p, q});
  }
  std::sort(edges.begin(), edges.end());
  return edges;
}

/// Calls group(first, last) for every run of half-edges on the same edge.
template <class Group>
void forEachEdge(const std::vector<HalfEdge>& edges, Group group) {
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i;
    while (j < edges.size() && edges[j].key == edges[i].key) ++j;
    group(i, j);
    i = j;
  }
}

/// Largest distance between two points of a rim (at most 512 of them, evenly spread).
double rimWidth(const MeshVertices& V, const std::vector<int>& rim) {
  const std::size_t step = std::max<std::size_t>(1, rim.size() / 512);
  double widest = 0;
  for (std::size_t a = 0; a < rim.size(); a += step)
    for (std::size_t b = a + step; b < rim.size(); b += step)
      widest = std::max(widest, (V.row(rim[a]) - V.row(rim[b])).squaredNorm());
  return std::sqrt(widest);
}

/// boundaryLoops over welded vertex indices `rep`.
std::vector<std::vector<int>> loopsOf(const std::vector<int>& rep, const MeshTriangles& F) {
  const std::vector<HalfEdge> edges = halfEdges(rep, F);
  std::vector<HalfEdge> rims;  // boundary half-edges, sorted by their first vertex
  forEachEdge(edges, [&](std::size_t i, std::size_t j) {
    if (j - i == 1) rims.push_back(edges[i]);
  });
  auto byFrom = [](const HalfEdge& x, const HalfEdge& y) { return x.from < y.from || (x.from == y.from && x.to < y.to); };
  std::sort(rims.begin(), rims.end(), byFrom);
  std::vector<char> used(rims.size(), 0);
  auto nextFrom = [&](int vertex) -> std::size_t {  // an unused rim edge leaving vertex, or rims.size()
    auto it = std::lower_bound(rims.begin(), rims.end(), HalfEdge{0, 0, vertex, -1}, byFrom);
    for (; it != rims.end() && it->from == vertex; ++it)
      if (!used[std::size_t(it - rims.begin())]) return std::size_t(it - rims.begin());
    return rims.size();
  };
  std::vector<std::vector<int>> loops;
  for (std::size_t start = 0; start < rims.size(); ++start) {
    if (used[start]) continue;
    std::vector<int> loop{rims[start].from};
    for (std::size_t e = start; e < rims.size(); e = nextFrom(rims[e].to)) {
      used[e] = 1;
      if (rims[e].to == loop.front()) break;  // closed
      loop.push_back(rims[e].to);
    }
    loops.push_back(std::move(loop));
  }
  return loops;
}

/// meshPieces over welded vertex indices `rep`.
std::vector<int> piecesOf(const std::vector<int>& rep, const MeshTriangles& F, std::size_t& count) {
  UnionFind uf(std::size_t(F.rows()));
  std::vector<int> identity(rep.size());
  std::iota(identity.begin(), identity.end(), 0);
  const std::vector<HalfEdge> stored = halfEdges(identity, F), welded = halfEdges(rep, F);
  for (std::size_t e = 1; e < stored.size(); ++e)  // sorted: triangles sharing an edge are neighbours
    if (stored[e].key == stored[e - 1].key) uf.unite(stored[e].triangle, stored[e - 1].triangle);
  forEachEdge(welded, [&](std::size_t i, std::size_t j) {
    if (j - i == 2) uf.unite(welded[i].triangle, welded[i + 1].triangle);
  });
  std::unordered_map<int, int> id;
  std::vector<int> piece(std::size_t(F.rows()));
  for (Eigen::Index t = 0; t < F.rows(); ++t)
    piece[std::size_t(t)] = id.emplace(uf.find(int(t)), int(id.size())).first->second;
  count = id.size();
  return piece;
}

/// |Signed volume| by the divergence theorem about the vertex centroid, each hole closed by a fan
/// around its rim's mean point (without the fans a hole would drop the cone it subtends).
double closedUpVolume(const MeshVertices& V, const MeshTriangles& F, const std::vector<std::vector<int>>& rims) {
  if (F.rows() == 0) return 0;
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (Eigen::Index t = 0; t < F.rows(); ++t)
    for (int c = 0; c < 3; ++c) centroid += V.row(F(t, c)).transpose();
  centroid /= double(3 * F.rows());
  auto six = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
    return (a - centroid).dot((b - centroid).cross(c - centroid));
  };
  double sum = 0;
  for (Eigen::Index t = 0; t < F.rows(); ++t)
    sum += six(V.row(F(t, 0)).transpose(), V.row(F(t, 1)).transpose(), V.row(F(t, 2)).transpose());
  for (const auto& rim : rims) {
    Eigen::Vector3d middle = Eigen::Vector3d::Zero();
    for (int v : rim) middle += V.row(v).transpose();
    middle /= double(rim.size());
    for (std::size_t n = 0; n < rim.size(); ++n)  // the rim runs as its triangles do: the fan runs back
      sum += six(middle, V.row(rim[(n + 1) % rim.size()]).transpose(), V.row(rim[n]).transpose());
  }
  return std::abs(sum) / 6.0;
}

}  // namespace

MeshTopology analyzeMeshTopology(const MeshVertices& V, const MeshTriangles& F) {
  checkTriangleIndices(V, F);
  MeshTopology r;
  r.vertices = std::size_t(V.rows());
  r.triangles = std::size_t(F.rows());
  const std::vector<int> rep = weldExact(V);
  for (Eigen::Index t = 0; t < F.rows(); ++t) {
    const int a = rep[F(t, 0)], b = rep[F(t, 1)], c = rep[F(t, 2)];
    if (a == b || b == c || a == c) ++r.degenerateTriangles;
  }
  forEachEdge(halfEdges(rep, F), [&](std::size_t i, std::size_t j) {
    if (j - i == 1) ++r.boundaryEdges;
    if (j - i > 2) ++r.nonManifoldEdges;
  });
  const auto rims = loopsOf(rep, F);
  r.holes = rims.size();
  for (const auto& rim : rims) r.largestHole = std::max(r.largestHole, rimWidth(V, rim));
  piecesOf(rep, F, r.pieces);
  triangleComponents(rep, F, r.components);
  r.enclosedVolume = closedUpVolume(V, F, rims);
  return r;
}

std::vector<std::vector<int>> boundaryLoops(const MeshVertices& V, const MeshTriangles& F) {
  checkTriangleIndices(V, F);
  return loopsOf(weldExact(V), F);
}

std::vector<std::vector<std::array<int, 2>>> boundaryChain(const MeshVertices& V, const MeshTriangles& F) {
  checkTriangleIndices(V, F);
  const std::vector<HalfEdge> edges = halfEdges(weldExact(V), F);
  std::vector<std::array<int, 2>> chain;
  forEachEdge(edges, [&](std::size_t i, std::size_t j) {
    int net = 0;  // runs from the smaller index to the larger, minus the other way
    for (std::size_t e = i; e < j; ++e) net += edges[e].from < edges[e].to ? 1 : -1;
    const int lo = int(edges[i].key >> 32), hi = int(edges[i].key & 0xffffffffu);
    const std::array<int, 2> edge = net > 0 ? std::array<int, 2>{lo, hi} : std::array<int, 2>{hi, lo};
    chain.insert(chain.end(), std::size_t(std::abs(net)), edge);
  });
  UnionFind uf(std::size_t(V.rows()));
  for (const auto& e : chain) uf.unite(e[0], e[1]);
  std::unordered_map<int, std::size_t> piece;
  std::vector<std::vector<std::array<int, 2>>> pieces;
  for (const auto& e : chain) {
    const std::size_t p = piece.emplace(uf.find(e[0]), pieces.size()).first->second;
    if (p == pieces.size()) pieces.emplace_back();
    pieces[p].push_back(e);
  }
  return pieces;
}

std::vector<int> meshPieces(const MeshVertices& V, const MeshTriangles& F, std::size_t& count) {
  checkTriangleIndices(V, F);
  return piecesOf(weldExact(V), F, count);
}

MeshTriangles consistentlyOriented(const MeshVertices& V, const MeshTriangles& F, std::size_t& turned) {
  checkTriangleIndices(V, F);
  const std::vector<HalfEdge> edges = halfEdges(weldExact(V), F);
  // Neighbours across manifold edges, and whether they run the edge the same way (disagree).
  std::vector<std::vector<std::pair<int, bool>>> next(std::size_t(F.rows()));
  forEachEdge(edges, [&](std::size_t i, std::size_t j) {
    if (j - i != 2) return;
    const bool same = edges[i].from == edges[i + 1].from;
    next[std::size_t(edges[i].triangle)].push_back({edges[i + 1].triangle, same});
    next[std::size_t(edges[i + 1].triangle)].push_back({edges[i].triangle, same});
  });
  std::vector<signed char> flip(std::size_t(F.rows()), -1);  // -1 not reached, 0 kept, 1 turned
  std::vector<int> queue;
  for (Eigen::Index seed = 0; seed < F.rows(); ++seed) {
    if (flip[std::size_t(seed)] >= 0) continue;
    flip[std::size_t(seed)] = 0;
    queue.assign(1, int(seed));
    for (std::size_t head = 0; head < queue.size(); ++head)
      for (auto [n, same] : next[std::size_t(queue[head])])
        if (flip[std::size_t(n)] < 0) {
          flip[std::size_t(n)] = static_cast<signed char>(flip[std::size_t(queue[head])] ^ int(same));
          queue.push_back(n);
        }
  }
  MeshTriangles out = F;
  turned = 0;
  for (Eigen::Index t = 0; t < F.rows(); ++t)
    if (flip[std::size_t(t)] == 1) std::swap(out(t, 1), out(t, 2)), ++turned;
  return out;
}

std::vector<TriangleMesh> splitConnectedComponents(const MeshVertices& V, const MeshTriangles& F) {
  checkTriangleIndices(V, F);
  std::size_t count = 0;
  const std::vector<int> comp = triangleComponents(weldExact(V), F, count);
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
