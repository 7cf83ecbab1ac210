#pragma once
// Posed volume by pulling: every output voxel centre is located in a posed tet, mapped back to rest
// space with that tet's barycentric coordinates, and the rest volume is sampled there.
#include <array>
#include <optional>

#include "image_grid.h"
#include "tet_mesh.h"

namespace repose {

struct TetBoundary;

/// Counts are over the voxels produced (the sub-extent when one is requested).
struct PullResampleReport {
  std::size_t outputVoxels = 0;
  std::size_t coveredVoxels = 0;     ///< voxels whose centre lies in some posed tet
  std::size_t extrapolatedVoxels = 0;  ///< voxels written by the extrapolation pass (outside all tets)
  std::size_t invertedTets = 0;      ///< posed tets with non-positive volume (skipped)
  double seconds = 0;
};

/// The mesh usually stops short of the body's outer voxel layer (the mask is peeled before meshing), so
/// the posed mesh is extrapolated outward on the voxel grid, one layer of 6-neighbours after another
/// (ceil(d / finest spacing) + 2 layers): a voxel no tet covers takes the affine map of a tet its
/// written neighbour was covered by or extrapolated from, the one it lies least far outside of (max
/// over faces of -λ_a h_a, h_a the tet's height over face a). It writes labels only when the sampled
/// rest label is not background, intensities only when the rest point lies in the rest grid.
/// Extrapolated voxels are thus always connected to the posed body.
struct PullResampleOptions {
  /// Boundary faces of `tets` (tetBoundary(tets)); null = no extrapolation.
  const TetBoundary* boundary = nullptr;
  /// d in mm, the reach of the extrapolation (above); negative = 2 x the largest spacing of the rest
  /// grid; 0 = no extrapolation.
  double extrapolationDistance = -1.0;
  /// Optional restMeshCoverage(rest grid, restNodes, tets): the extrapolation then samples rest voxels
  /// inside the rest mesh only within one voxel (largest spacing) of its tet, so it does not copy a
  /// neighbouring part's interior (e.g. an arm resting against the torso, then raised), while points
  /// just outside the tet may still round to voxels just inside.
  const MaskVolume* restCoverage = nullptr;
  /// Optional restMeshDistance(coverage): also, a rest voxel outside the mesh belongs to the part of
  /// the mesh nearest it, and an extrapolation samples it only from a tet about that near (within a
  /// quarter of the smallest spacing more). Where two parts touched at rest and were cut apart before
  /// meshing (contact separation), each part so takes back its own side of the cut, not both.
  const MaskVolume* restDistance = nullptr;
  /// Optional output sub-extent {i0, i1, j0, j1, k0, k1} (inclusive voxel indices of outGrid), e.g. the
  /// slices a viewer shows: only those voxels are produced, and they equal the same voxels of the full
  /// resample (the extrapolation looks a few voxels beyond the extent to ensure that). The
  /// result's grid is extentGrid(outGrid, extent). Unset = the whole grid.
  std::optional<std::array<int, 6>> outputExtent;
};

/// The block {i0, i1, j0, j1, k0, k1} (inclusive) of `grid` as a grid of its own: same spacing and
/// direction, origin at voxel (i0, j0, k0). Throws if the extent is empty or not inside the grid.
ImageGrid extentGrid(const ImageGrid& grid, const std::array<int, 6>& extent);

/// How posedOutputGrid bounds the posed volume.
struct PosedGridOptions {
  int paddingVoxels = 2;  ///< voxels beyond the posed nodes' box on every side
  /// Margin of a grid that holds the body only (below); negative = paddingVoxels. Give the
  /// extrapolation's reach (extrapolationReachVoxels) so that cropping never cuts the posed body.
  int bodyPaddingVoxels = -1;
  /// The grid also holds the rest grid's extent while that keeps it within this factor of the
  /// voxels of the (padded) rest grid or of the body's own box, whichever is larger: a pose in place
  /// keeps the rest grid's voxel indices, as before. Beyond it (the root moved away, e.g. along a
  /// walk) the grid holds the posed body only. 0 = the body only.
  double restExtentFactor = 2.0;
  /// Largest voxel count; a larger grid throws std::invalid_argument saying its size and the posed
  /// body's span (a body far from where it started: root motion, or motion read in the wrong unit).
  /// 0 = no limit.
  double maxVoxels = 0;
};

/// Output grid: the rest grid's spacing and direction, on the rest lattice (shifted by whole voxels,
/// so unmoved anatomy lands on the same voxel centres), holding the posed nodes plus padding and,
/// by options.restExtentFactor, the rest extent.
ImageGrid posedOutputGrid(const ImageGrid& rest, const Points& posedNodes, const PosedGridOptions& options);
/// The same with default options and this padding.
ImageGrid posedOutputGrid(const ImageGrid& rest, const Points& posedNodes, int paddingVoxels = 2);

/// Voxels beyond the posed mesh that the pull's extrapolation may write (0 when it is off), for
/// PosedGridOptions::bodyPaddingVoxels.
int extrapolationReachVoxels(const ImageGrid& rest, double extrapolationDistance);

/// Rest-grid mask: 1 where the voxel centre lies in some rest tet. Depends on the rest mesh and grid
/// only, so compute it once per rest mesh (it costs about one resampling pass).
MaskVolume restMeshCoverage(const ImageGrid& restGrid, const Points& restNodes, const Tets& tets);

/// Distance from every rest voxel to the rest mesh, for PullResampleOptions::restDistance: 0 where
/// `coverage` (restMeshCoverage) is set, else the distance to the nearest covered voxel centre in
/// units of kRestDistanceUnit x the grid's smallest spacing, rounded up, at most 255 (= far).
constexpr double kRestDistanceUnit = 0.25;
MaskVolume restMeshDistance(const MaskVolume& coverage);

/// Labels: nearest rest voxel; voxels outside the posed mesh (and its extension) are `background`.
/// restNodes/posedNodes #V by 3, tets #T by 4. Threaded with parallelFor; deterministic (a voxel
/// covered by several tets takes the sample of the lowest-numbered one). Each tet is set up once and
/// only its own voxel centres are visited: cost O(#tets + voxels written) plus filling the output.
LabelVolume resampleLabelsPull(const LabelVolume& rest, const Points& restNodes, const Points& posedNodes,
                               const Tets& tets, const ImageGrid& outGrid, const PullResampleOptions& options,
                               std::int32_t background = 0, PullResampleReport* report = nullptr);
/// Same, written into caller memory: `out` holds the output's voxels (outGrid's, or the sub-extent's),
/// i fastest; every one of them is written.
void resampleLabelsPullInto(const LabelVolume& rest, const Points& restNodes, const Points& posedNodes,
                            const Tets& tets, const ImageGrid& outGrid, const PullResampleOptions& options,
                            std::int32_t* out, std::int32_t background = 0, PullResampleReport* report = nullptr);
/// Without extrapolation.
LabelVolume resampleLabelsPull(const LabelVolume& rest, const Points& restNodes, const Points& posedNodes,
                               const Tets& tets, const ImageGrid& outGrid, std::int32_t background = 0,
                               PullResampleReport* report = nullptr);

/// Intensities: trilinear in the rest volume; voxels outside the posed mesh (and its extension) are
/// `background`.
IntensityVolume resampleIntensityPull(const IntensityVolume& rest, const Points& restNodes,
                                      const Points& posedNodes, const Tets& tets, const ImageGrid& outGrid,
                                      const PullResampleOptions& options, float background,
                                      PullResampleReport* report = nullptr);
/// Same, written into caller memory (see resampleLabelsPullInto).
void resampleIntensityPullInto(const IntensityVolume& rest, const Points& restNodes, const Points& posedNodes,
                               const Tets& tets, const ImageGrid& outGrid, const PullResampleOptions& options,
                               float* out, float background, PullResampleReport* report = nullptr);
/// Without extrapolation.
IntensityVolume resampleIntensityPull(const IntensityVolume& rest, const Points& restNodes,
                                      const Points& posedNodes, const Tets& tets, const ImageGrid& outGrid,
                                      float background, PullResampleReport* report = nullptr);

/// The map itself: for every voxel of outGrid (or the options' sub-extent), the displacement from
/// its centre to the rest point it is pulled back to, in mm along the physical (LPS) axes, exactly
/// the map resampleIntensityPull samples the rest image through (the same tets, extrapolation and
/// pinhole filling, the latter as the mean of the neighbours' rest points). Voxels the map does not
/// reach (outside the posed body, where the posed image is background) get 0. out holds 3 floats per
/// voxel (x, y, z), i fastest. restGrid: the grid the rest nodes lie in (its voxels bound the
/// extrapolation as the rest image does).
void displacementPullInto(const ImageGrid& restGrid, const Points& restNodes, const Points& posedNodes,
                          const Tets& tets, const ImageGrid& outGrid, const PullResampleOptions& options,
                          float* out, PullResampleReport* report = nullptr);

}  // namespace repose
