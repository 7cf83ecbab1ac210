#pragma once
// Boundary faces of a tet mesh: the faces that belong to exactly one tet. Computed once per rest mesh
// (topology only) and reused for every pose, e.g. by the pull resampler's extrapolation pass.
#include <cstdint>
#include <vector>

#include "tet_mesh.h"

namespace repose {

struct TetBoundary {
  /// #T: bit a (0..3) set = the face opposite local vertex a of the tet is on the mesh boundary.
  std::vector<std::uint8_t> boundaryFaceMask;
  /// #T: 1 if any node of the tet lies on a boundary face (the tets a voxel just outside the mesh is
  /// extrapolated from).
  std::vector<std::uint8_t> touchesBoundary;
  std::size_t boundaryFaces = 0;  ///< number of set bits
  std::size_t boundaryTets = 0;   ///< tets with at least one boundary face
};

/// tets #T by 4 node indices (>= 0). Faces are matched by their node sets, so orientation does not
/// matter; a face shared by three or more tets (non-manifold input) counts as interior. O(#T), threaded.
TetBoundary tetBoundary(const Tets& tets);

}  // namespace repose
