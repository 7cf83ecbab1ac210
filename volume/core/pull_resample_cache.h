#pragma once
// The pose-independent inputs of the posed volume, kept between poses: between two poses only the
// posed nodes change, so the rest tets, nodes and volume are converted once and the mesh boundary, the
// rest coverage and distance and the label boxes are derived once. The owner sets an input when it
// changed (the derived state that depends on it is dropped and rebuilt on first need), then calls one
// of the pulls per pose.
#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <vector>

#include "image_grid.h"
#include "resample_pull.h"
#include "tet_boundary.h"
#include "tet_mesh.h"

namespace repose {

/// Rigid-bone overlay counts of a label pull (see overlayRigidBones).
struct RigidBoneCounts {
  std::size_t changedVoxels = 0;
  std::size_t contestedVoxels = 0;
};

class PullResampleCache {
 public:
  /// The rest mesh's tets (#T x 4 node indices): drops the boundary and the coverage.
  void setTets(Tets tets);
  /// The rest mesh's nodes (#V x 3, mm): drops the coverage.
  void setRestNodes(Points nodes);
  /// The rest volume's grid: drops the coverage and the label boxes when it is not the same grid.
  void setRestGrid(const ImageGrid& grid);
  /// The rest volume as labels or as intensities (one value per voxel of the rest grid, i fastest);
  /// setting one drops the other, and the labels drop the label boxes.
  void setLabels(std::vector<std::int32_t> labels);
  void setIntensities(std::vector<float> values);
  /// Per rest node, the bone it is fixed to (-1: free), for the rigid-bone overlay.
  void setFixedBone(std::vector<int> fixedBone);

  const Tets& tets() const { return tets_; }
  const Points& restNodes() const { return restNodes_; }
  const ImageGrid& restGrid() const { return labels_.grid; }

  /// The pulls of resample_pull.h with the cached rest inputs: `options` gives the extrapolation
  /// distance and the output extent; with extrapolation on (distance != 0), its boundary, coverage
  /// and distance are taken from the cache. `out` holds the extent's voxels (3 floats each for the
  /// displacement).
  void displacementInto(const Points& posedNodes, const ImageGrid& outGrid, PullResampleOptions options, float* out,
                        PullResampleReport* report);
  void intensitiesInto(const Points& posedNodes, const ImageGrid& outGrid, PullResampleOptions options, float* out,
                       float background, PullResampleReport* report);
  /// Labels; with `rigid` (needs setFixedBone), then the bones overlaid rigidly (overlayRigidBones).
  RigidBoneCounts labelsInto(const Points& posedNodes, const ImageGrid& outGrid, PullResampleOptions options,
                             std::int32_t* out, std::int32_t background, bool rigid, PullResampleReport* report);

 private:
  // The boundary, coverage and distance into `options` when it extrapolates (built on first need).
  void extrapolationInputs(PullResampleOptions& options);

  Tets tets_;
  Points restNodes_;
  LabelVolume labels_;
  IntensityVolume values_;
  std::vector<int> fixedBone_;
  std::unique_ptr<TetBoundary> boundary_;
  std::unique_ptr<MaskVolume> coverage_, distance_;  // distance: restMeshDistance(coverage)
  std::unique_ptr<std::vector<Eigen::AlignedBox3i>> labelBoxes_;
};

}  // namespace repose
