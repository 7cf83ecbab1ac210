#pragma once
// The meshing spacing chosen from a budget of tets, so a whole-body scan is meshed at the size the
// method was made for (the paper's cases: 2.5-3.4 M tets), whatever its voxel size.
#include <cstddef>
#include <vector>

#include "image_grid.h"

namespace repose {

/// Steps (in scan voxels) of the bone seed lattice for meshing at spacingMm: 2 voxels on bone
/// boundaries and 4 inside at the scan's own spacing, scaled with the meshing spacing.
struct SeedSteps {
  int surface = 2, interior = 4;
};
SeedSteps seedSteps(const ImageGrid& scan, double spacingMm);

/// Voxel faces between a set and an unset voxel (the grid's border counts as unset).
std::size_t boundaryFaces(const MaskVolume& mask);

/// Tets TetGen makes (radius-edge bound 2, surface kept) from a body whose binned mask has
/// `surfaceFaces` boundary faces (the marching-cubes surface has about one vertex per face) and
/// `seeds` bone seed points: 6.7-7.9 per face or seed on the phantoms and real scans (10.1 on the
/// large phantom), 8.5 taken so that most bodies come out a little under the budget.
constexpr double kTetsPerPoint = 8.5;
double predictTets(std::size_t surfaceFaces, std::size_t seeds, double tetsPerPoint = kTetsPerPoint);

struct MeshSpacingChoice {
  double spacingMm = 0;        ///< the meshing spacing chosen
  double predictedTets = 0;    ///< predictTets at that spacing
  std::size_t surfaceFaces = 0, seeds = 0;
  int trials = 0;              ///< spacings tried
};

/// The finest meshing spacing (not below the scan's finest spacing) whose predicted tet count is at
/// most maxTets: the scan's own spacing when it fits, else a spacing found by a few trials of binning
/// the mask (binToMeshingGrid) and counting its faces and the bone seeds (each trial one pass over
/// the scan). peeled: the body to mesh on the scan's grid; boneOfLabel: label -> bone or -1.
/// Throws std::invalid_argument when maxTets < 1000 or the inputs disagree.
/// tetsPerPoint: as predictTets; a caller that has meshed once may pass the ratio it measured.
MeshSpacingChoice chooseMeshSpacing(const MaskVolume& peeled, const LabelVolume& labels,
                                    const std::vector<int>& boneOfLabel, double maxTets,
                                    double tetsPerPoint = kTetsPerPoint);

}  // namespace repose
