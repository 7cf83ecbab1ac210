#include "barycentric_binding.h"

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <unistd.h>
#include <stdexcept>
#include <string>

#include "parallel_for.h"
#include "tet_locator.h"

namespace repose {

Binding bindPoints(const Points& restNodes, const Tets& tets, const Points& points) {
  if (tets.rows() == 0) throw std::invalid_argument("bind points: the tet mesh has no tets");
  if (!points.allFinite()) throw std::invalid_argument("bind points: non-finite point coordinates");
  const TetLocator locator(restNodes, tets);  // validates indices and nodes
  return bindPoints(locator, points);
}

Binding bindPoints(const TetLocator& locator, const Points& points) {
  if (!points.allFinite()) throw std::invalid_argument("bind points: non-finite point coordinates");
  const std::size_t n = std::size_t(points.rows());
  Binding b;
  b.tet.assign(n, -1);
  b.bary.resize(Eigen::Index(n), 4);
  std::atomic<std::size_t> outside{0};
  std::atomic<bool> empty{false};
  parallelFor(n, [&](std::size_t begin, std::size_t end) {
    std::size_t localOutside = 0;
    for (std::size_t p = begin; p < end; ++p) {
      const Eigen::Vector3d x = points.row(Eigen::Index(p)).transpose();
      TetLocator::Hit hit;
      if (!locator.findContaining(x, hit)) {
        hit = locator.findNearest(x);
        ++localOutside;
        if (hit.tet < 0) empty = true;
      }
      b.tet[p] = hit.tet;
      b.bary.row(Eigen::Index(p)) = hit.bary.cast<float>().transpose();
    }
    outside += localOutside;
  }, 256);
  if (empty) throw std::invalid_argument("bind points: the tet mesh has no tets");
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

NodeBinding makeNodeBinding(const Binding& binding, const Tets& tets) {
  const std::size_t n = binding.tet.size();
  if (std::size_t(binding.bary.rows()) != n)
    throw std::invalid_argument("node binding: " + std::to_string(n) + " tets but " +
                                std::to_string(binding.bary.rows()) + " barycentric rows");
  NodeBinding nb;
  nb.node.resize(4 * n);
  nb.bary.resize(4 * n);
  for (std::size_t p = 0; p < n; ++p) {
    const int t = binding.tet[p];
    if (t < 0 || t >= tets.rows())
      throw std::invalid_argument("node binding: point " + std::to_string(p) + " is bound to tet " +
                                  std::to_string(t) + ", not a tet of the " + std::to_string(tets.rows()) +
                                  "-tet mesh (binding made for another mesh?)");
    for (int a = 0; a < 4; ++a) {
      const int v = tets(t, a);
      if (v < 0)
        throw std::invalid_argument("node binding: tet " + std::to_string(t) + " has a negative node id");
      nb.node[4 * p + a] = v;
      nb.bary[4 * p + a] = binding.bary(Eigen::Index(p), a);
      nb.maxNode = std::max(nb.maxNode, v);
    }
  }
  return nb;
}

namespace {

template <typename T>
void applyNodeBinding(const NodeBinding& b, const T* nodes, std::size_t nodeCount, float* out) {
  const std::size_t n = b.pointCount();
  if (b.node.size() != 4 * n || b.bary.size() != 4 * n)
    throw std::invalid_argument("apply binding: inconsistent NodeBinding (build it with makeNodeBinding)");
  if (n == 0) return;
  if (!nodes || !out) throw std::invalid_argument("apply binding: null node or output buffer");
  if (b.maxNode >= 0 && std::size_t(b.maxNode) >= nodeCount)
    throw std::invalid_argument("apply binding: the binding uses node " + std::to_string(b.maxNode) +
                                " but the posed mesh has " + std::to_string(nodeCount) +
                                " nodes (binding made for another mesh?)");
  const int* ids = b.node.data();
  const float* w = b.bary.data();
  // Latency bound: the 4 node gathers of a vertex miss the cache when the node array is larger
  // than the cache, so the nodes of vertex p + kAhead are prefetched (their ids are known).
  constexpr std::size_t kAhead = 64;
  parallelFor(n, [=](std::size_t begin, std::size_t end) {
    for (std::size_t p = begin; p < end; ++p) {
#if defined(__GNUC__)
      if (p + kAhead < end) {
        const int* ahead = ids + 4 * (p + kAhead);
        for (int a = 0; a < 4; ++a) __builtin_prefetch(nodes + 3 * std::size_t(ahead[a]));
      }
#endif
      const int* id = ids + 4 * p;
      const float* wp = w + 4 * p;
      const T* a = nodes + 3 * std::size_t(id[0]);
      const T* c = nodes + 3 * std::size_t(id[1]);
      const T* d = nodes + 3 * std::size_t(id[2]);
      const T* e = nodes + 3 * std::size_t(id[3]);
      for (int k = 0; k < 3; ++k)
        out[3 * p + k] = float(wp[0] * a[k] + wp[1] * c[k] + wp[2] * d[k] + wp[3] * e[k]);
    }
  }, 8192);
}

}  // namespace

void applyBinding(const NodeBinding& binding, const float* posedNodes, std::size_t nodeCount,
                  float* posedPoints) {
  applyNodeBinding(binding, posedNodes, nodeCount, posedPoints);
}

void applyBinding(const NodeBinding& binding, const double* posedNodes, std::size_t nodeCount,
                  float* posedPoints) {
  applyNodeBinding(binding, posedNodes, nodeCount, posedPoints);
}

namespace {

constexpr char kMagic[8] = {'R', 'E', 'P', 'O', 'S', 'E', 'B', 'D'};
constexpr std::uint32_t kVersion = 1;

struct CacheHeader {
  char magic[8];
  std::uint32_t version;
  std::uint32_t reserved;
  std::uint64_t pointCount, pointsHash, meshHash, nodeCount, tetCount, outsideCount;
};

}  // namespace

std::uint64_t contentHash(const void* data, std::size_t bytes, std::uint64_t seed) {
  // 64-bit multiply-xorshift over 8-byte words (splitmix64's finaliser per word).
  auto mix = [](std::uint64_t x) {
    x ^= x >> 30;
    x *= 0xbf58476d1ce4e5b9ULL;
    x ^= x >> 27;
    x *= 0x94d049bb133111ebULL;
    return x ^ (x >> 31);
  };
  std::uint64_t h = mix(seed ^ (0x9e3779b97f4a7c15ULL + bytes));
  const auto* p = static_cast<const unsigned char*>(data);
  std::size_t i = 0;
  for (; i + 8 <= bytes; i += 8) {
    std::uint64_t w;
    std::memcpy(&w, p + i, 8);
    h = mix(h ^ w) + 0x9e3779b97f4a7c15ULL;
  }
  std::uint64_t tail = 0;
  std::memcpy(&tail, p + i, bytes - i);
  return mix(h ^ tail ^ (std::uint64_t(bytes - i) << 56));
}

void writeBindingCache(const std::string& path, const Binding& binding, std::uint64_t pointsHash,
                       std::uint64_t meshHash, std::size_t nodeCount, std::size_t tetCount) {
  const std::size_t n = binding.tet.size();
  if (std::size_t(binding.bary.rows()) != n) throw std::invalid_argument("binding cache: inconsistent binding");
  CacheHeader h{};
  std::memcpy(h.magic, kMagic, 8);
  h.version = kVersion;
  h.pointCount = n;
  h.pointsHash = pointsHash;
  h.meshHash = meshHash;
  h.nodeCount = nodeCount;
  h.tetCount = tetCount;
  h.outsideCount = binding.outsideCount;
  const std::string temp = path + ".tmp" + std::to_string(::getpid());
  {
    std::ofstream out(temp, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(&h), sizeof h);
    std::vector<std::int32_t> tets(binding.tet.begin(), binding.tet.end());
    out.write(reinterpret_cast<const char*>(tets.data()), std::streamsize(n * sizeof(std::int32_t)));
    out.write(reinterpret_cast<const char*>(binding.bary.data()), std::streamsize(n * 4 * sizeof(float)));
    out.flush();
    if (!out) {
      std::remove(temp.c_str());
      throw std::runtime_error(path + ": cannot write the binding cache");
    }
  }
  if (std::rename(temp.c_str(), path.c_str()) != 0) {
    std::remove(temp.c_str());
    throw std::runtime_error(path + ": cannot write the binding cache (rename failed)");
  }
}

bool readBindingCache(const std::string& path, std::uint64_t pointsHash, std::uint64_t meshHash,
                      std::size_t pointCount, std::size_t nodeCount, std::size_t tetCount, Binding& binding) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  CacheHeader h{};
  if (!in.read(reinterpret_cast<char*>(&h), sizeof h)) return false;
  if (std::memcmp(h.magic, kMagic, 8) != 0 || h.version != kVersion || h.pointCount != pointCount ||
      h.pointsHash != pointsHash || h.meshHash != meshHash || h.nodeCount != nodeCount || h.tetCount != tetCount ||
      h.outsideCount > pointCount)
    return false;
  const std::size_t n = pointCount;
  std::vector<std::int32_t> tets(n);
  BarycentricCoords bary(Eigen::Index(n), 4);
  if (!in.read(reinterpret_cast<char*>(tets.data()), std::streamsize(n * sizeof(std::int32_t)))) return false;
  if (!in.read(reinterpret_cast<char*>(bary.data()), std::streamsize(n * 4 * sizeof(float)))) return false;
  if (in.peek() != std::char_traits<char>::eof()) return false;
  for (std::int32_t t : tets)
    if (t < 0 || std::size_t(t) >= tetCount) return false;
  if (!bary.allFinite()) return false;
  binding.tet.assign(tets.begin(), tets.end());
  binding.bary = std::move(bary);
  binding.outsideCount = std::size_t(h.outsideCount);
  return true;
}

}  // namespace repose
