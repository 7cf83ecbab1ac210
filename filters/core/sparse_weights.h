#pragma once
// Skinning weights kept sparse: the k largest bone weights of every node, renormalised.
#include <cstdint>
#include <vector>

namespace repose {

struct SparseWeights {
  int k = 4;                          ///< weights kept per node
  std::vector<float> weight;          ///< #V*k, row-major, each row sums to 1, unused slots 0
  std::vector<std::uint16_t> bone;    ///< #V*k bone (joint) indices, unused slots 0 with weight 0
  std::size_t nodeCount() const { return k > 0 ? weight.size() / std::size_t(k) : 0; }
};

}  // namespace repose
