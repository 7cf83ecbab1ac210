#pragma once
// The body on the grid the mesh is made from: the scan's voxels binned to the meshing spacing.
#include <cstdint>
#include <vector>

#include "image_grid.h"

namespace repose {

/// Volumes on the meshing grid. Contact separation and the surface both work here, so a gap cut
/// between two parts is one meshing voxel wide and survives into the surface.
struct MeshingVolumes {
  MaskVolume body;                ///< 1 inside the body
  Volume<std::int16_t> bone;      ///< bone index holding most of the voxel's bone voxels, -1 none
};

/// The grid with spacing max(spacingMm, native) per axis covering the same box as `native`: its
/// voxel I holds the native voxels i with floor((i + 0.5) / f) = I, f = coarse / native spacing.
/// spacingMm <= the native spacing gives the native grid itself.
ImageGrid meshingGrid(const ImageGrid& native, double spacingMm);

/// Bins `body` (native grid) and the bone voxels of `labels` (boneOfLabel: label -> bone or -1) to
/// `coarse` = meshingGrid(body.grid, ...): a coarse voxel is body when at least half of its native
/// voxels are, or when it holds any bone voxel (thin bones stay whole); its bone is the bone with
/// the most voxels in it. Throws std::invalid_argument when the inputs disagree.
MeshingVolumes binToMeshingGrid(const MaskVolume& body, const LabelVolume& labels,
                                const std::vector<int>& boneOfLabel, const ImageGrid& coarse);

}  // namespace repose
