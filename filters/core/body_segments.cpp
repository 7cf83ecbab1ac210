#include "body_segments.h"

#include <map>
#include <stdexcept>
#include <string>
#include <utility>

#include "parallel_for.h"

namespace repose {

std::vector<int> bodySegments(const SparseWeights& weights, const Tets& tets) {
  const Eigen::Index nodes = Eigen::Index(weights.nodeCount());
  for (Eigen::Index t = 0; t < tets.rows(); ++t)
    for (int a = 0; a < 4; ++a)
      if (tets(t, a) < 0 || tets(t, a) >= nodes)
        throw std::invalid_argument("bodySegments: tet " + std::to_string(t) + " has node " +
                                    std::to_string(tets(t, a)) + " but the weights cover " +
                                    std::to_string(nodes) + " nodes");
  std::vector<int> segment(std::size_t(tets.rows()));
  const std::size_t k = std::size_t(weights.k);
  parallelFor(segment.size(), [&](std::size_t b, std::size_t e) {
    std::vector<std::pair<int, double>> sum;  // (bone, summed weight): at most 4 k entries
    for (std::size_t t = b; t < e; ++t) {
      sum.clear();
      for (int a = 0; a < 4; ++a)
        for (std::size_t c = 0; c < k; ++c) {
          const std::size_t s = std::size_t(tets(Eigen::Index(t), a)) * k + c;
          const int bone = weights.bone[s];
          std::size_t i = 0;
          while (i < sum.size() && sum[i].first != bone) ++i;
          if (i == sum.size()) sum.push_back({bone, 0.0});
          sum[i].second += weights.weight[s];
        }
      std::pair<int, double> best{0, -1.0};
      for (const auto& [bone, w] : sum)
        if (w > best.second || (w == best.second && bone < best.first)) best = {bone, w};
      segment[t] = best.first;
    }
  });
  return segment;
}

std::vector<int> tissueSegments(const std::vector<int>& segments, const std::vector<int>& labels) {
  if (segments.size() != labels.size())
    throw std::invalid_argument("tissueSegments: " + std::to_string(segments.size()) + " segments but " +
                                std::to_string(labels.size()) + " labels");
  std::map<std::pair<int, int>, int> id;
  std::vector<int> region(segments.size(), -1);
  for (std::size_t t = 0; t < segments.size(); ++t)
    if (segments[t] >= 0) region[t] = id.emplace(std::make_pair(segments[t], labels[t]), int(id.size())).first->second;
  return region;
}

}  // namespace repose
