#pragma once
// Skinning of the tet nodes by dual quaternions (default) or linear blending.
#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "sparse_weights.h"
#include "tet_mesh.h"

namespace repose {

enum class SkinningMethod { DualQuaternion, LinearBlend };

/// posed(i) = blend_j w_ij T_j applied to rest(i). Nodes with fixedBone >= 0 move exactly with their
/// bone. Threaded with parallelFor. rest and posed are #V by 3; posed is resized.
/// Throws std::invalid_argument when sizes disagree or a bone index is out of range.
void skinNodes(const Points& rest, const SparseWeights& weights, const std::vector<int>& fixedBone,
               const std::vector<Eigen::Isometry3d>& boneTransforms, SkinningMethod method,
               Points& posed);

/// Single-precision copy of what skinning needs per node, built once per rest mesh and reused for
/// every pose (the interactive fast path). Float positions cost ~1e-4 mm at 1 m coordinates.
/// Each node's slots are sorted by decreasing weight (slot 0 is the DQS antipodality pivot); fixed
/// nodes are folded in as (their bone, weight 1); nodes whose weights are all zero stay at rest.
struct SkinningCache {
  int k = 0;
  std::vector<float> x, y, z;          ///< #V rest positions, structure of arrays
  std::vector<float> weight;           ///< #V*k, row-major, sorted decreasing per node
  std::vector<std::uint16_t> bone;     ///< #V*k
  std::vector<std::size_t> restNodes;  ///< nodes with no weight (left at rest)
  int maxBone = -1;                    ///< largest bone index used
  std::size_t maxBoneNode = 0;         ///< a node using maxBone (for the error message)
  std::size_t nodeCount() const { return x.size(); }
};

/// Builds the cache; same arguments and checks as skinNodes (bone range is checked per pose).
SkinningCache makeSkinningCache(const Points& rest, const SparseWeights& weights,
                                const std::vector<int>& fixedBone);

/// Float fast path of skinNodes: writes #V*3 floats (x y z per node) to posed, which the caller
/// allocates. Same results as skinNodes up to float rounding. Threaded, vectorised (AVX2 when the
/// CPU has it). Throws std::invalid_argument when a bone index is >= boneTransforms.size().
void skinNodes(const SkinningCache& cache, const std::vector<Eigen::Isometry3d>& boneTransforms,
               SkinningMethod method, float* posed);

}  // namespace repose
