#pragma once
// Skinning of the tet nodes by dual quaternions (default) or linear blending.
#include <Eigen/Geometry>
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

}  // namespace repose
