#include "skinned_relaxation.h"

namespace repose {

void relaxSkinnedMesh(const RelaxationRestMesh& rest, VolumeRegionChoice regions, CorotationalOptions options,
                      bool useWarmStart, RelaxationWarmStart& warmStart, Points& posed,
                      CorotationalReport* report) {
  setVolumeRegions(regions, rest.weights, rest.tetLabels, rest.tets, options);
  warmStart.offer(useWarmStart, rest.key, posed.rows(), options);
  const Points input = posed;
  warmStart.forget();
  relaxCorotational(rest.nodes, rest.tets, rest.fixedBone, posed, options, report);
  warmStart.remember(rest.key, input, posed);
}

}  // namespace repose
