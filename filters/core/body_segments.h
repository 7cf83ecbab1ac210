#pragma once
// Body segments from skinning weights: each tet belongs to the bone with the largest weight summed
// over its four nodes (the regions whose volume the FEM relaxation holds as a whole).
#include <vector>

#include "sparse_weights.h"
#include "tet_mesh.h"

namespace repose {

/// Per tet, the segment's bone index. Ties go to the lower bone index.
/// Throws std::invalid_argument if a tet names a node the weights do not cover.
std::vector<int> bodySegments(const SparseWeights& weights, const Tets& tets);

/// Each segment split by tissue: one region per (segment, label) pair that occurs, numbered 0, 1, ...
/// in order of first occurrence; negative segments stay -1 (no region). Every organ then keeps its
/// own volume within its segment rather than the segment's tissues trading volume among themselves.
/// Throws std::invalid_argument if the two lists differ in length.
std::vector<int> tissueSegments(const std::vector<int>& segments, const std::vector<int>& labels);

}  // namespace repose
