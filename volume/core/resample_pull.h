#pragma once
// Posed volume by pulling: every output voxel centre is located in a posed tet, mapped back to rest
// space with that tet's barycentric coordinates, and the rest volume is sampled there.
#include "image_grid.h"
#include "tet_mesh.h"

namespace repose {

struct PullResampleReport {
  std::size_t outputVoxels = 0;
  std::size_t coveredVoxels = 0;     ///< voxels whose centre lies in some posed tet
  std::size_t invertedTets = 0;      ///< posed tets with non-positive volume (skipped)
  double seconds = 0;
};

/// Output grid: the rest grid's spacing and direction, its lattice extended (by whole voxels, so
/// unmoved anatomy lands on the same voxel centres) to hold the rest extent and the posed nodes,
/// plus `paddingVoxels` on every side.
ImageGrid posedOutputGrid(const ImageGrid& rest, const Points& posedNodes, int paddingVoxels = 2);

/// Labels: nearest rest voxel; voxels outside the posed mesh are `background`.
/// restNodes/posedNodes #V by 3, tets #T by 4. Threaded with parallelFor.
LabelVolume resampleLabelsPull(const LabelVolume& rest, const Points& restNodes, const Points& posedNodes,
                               const Tets& tets, const ImageGrid& outGrid, std::int32_t background = 0,
                               PullResampleReport* report = nullptr);

/// Intensities: trilinear in the rest volume; voxels outside the posed mesh are `background`.
IntensityVolume resampleIntensityPull(const IntensityVolume& rest, const Points& restNodes,
                                      const Points& posedNodes, const Tets& tets, const ImageGrid& outGrid,
                                      float background, PullResampleReport* report = nullptr);

}  // namespace repose
