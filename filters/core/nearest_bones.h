#pragma once
// Geodesic distances, inside the body, from every body voxel to its two nearest bones.
#include <cstdint>
#include <vector>

#include "image_grid.h"

namespace repose {

/// Per voxel (i fastest): the nearest bone and the second nearest (another bone), with their
/// distances in mm along paths through body voxels (26-neighbour steps of their physical length).
/// Bone -1 / distance +inf where none is reachable; background voxels have none.
struct NearestBones {
  std::vector<std::int16_t> first, second;
  std::vector<float> firstMm, secondMm;
};

/// Sources are the voxels with bone[v] >= 0 (distance 0 to their own bone); paths run through
/// body[v] != 0 voxels only. Dijkstra with each voxel settled at most twice (once per bone it
/// keeps); ties go to the lower voxel index, so the result is deterministic.
/// Throws std::invalid_argument when the volumes are on different grids.
NearestBones nearestBones(const MaskVolume& body, const Volume<std::int16_t>& bone);

}  // namespace repose
