#include "relaxation_regions.h"

#include "body_segments.h"

namespace repose {

void setVolumeRegions(VolumeRegionChoice choice, const SparseWeights* weights, const std::vector<int>& tetLabels,
                      const Tets& tets, CorotationalOptions& options) {
  if (options.model != CorotationalOptions::FixedCorotated) choice = VolumeRegionChoice::None;
  const auto tetCount = static_cast<std::size_t>(tets.rows());
  if (choice >= VolumeRegionChoice::Segments && weights) {
    options.volumeRegions = bodySegments(*weights, tets);
    if (choice == VolumeRegionChoice::Tissues && tetLabels.size() == tetCount) {
      options.pathVolumeRegions = options.volumeRegions;
      options.volumeRegions = tissueSegments(options.volumeRegions, tetLabels);
    }
  } else if (choice != VolumeRegionChoice::None) {
    options.volumeRegions.assign(tetCount, 0);
  }
}

}  // namespace repose
