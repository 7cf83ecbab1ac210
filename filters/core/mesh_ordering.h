#pragma once
// Spatially coherent numbering of a tet mesh. TetGen numbers nodes and tets in creation order, which
// scatters neighbours across memory; every per-pose pass (skinning, surface gathers, resampling)
// then waits on cache misses. Sorting both along a Morton (Z-order) curve keeps neighbours close.
#include "tet_mesh.h"

namespace repose {

/// Renumbers mesh.nodes (and fixedBone when filled) and mesh.tets (and tetLabel when filled) in
/// Morton order of node positions and tet centroids. The geometry and the tets' orientation are
/// unchanged. Returns the node permutation: newIndex[old] = new.
std::vector<int> reorderMeshSpatially(TetMesh& mesh);

}  // namespace repose
