#pragma once
// The relaxation of a skinned tet mesh as a pose runs it: the volume regions the user chose, the
// warm start from the last run, the solve (relaxCorotational), and the correction kept for the next.
#include <cstdint>
#include <vector>

#include "corotational_fem.h"
#include "relaxation_regions.h"
#include "relaxation_warm_start.h"
#include "sparse_weights.h"
#include "tet_mesh.h"

namespace repose {

/// The rest mesh: the stress-free shape and what the regions are made of.
struct RelaxationRestMesh {
  Points nodes;                       ///< #V by 3 rest positions
  Tets tets;                          ///< #T by 4
  std::vector<int> fixedBone;         ///< per node, the bone it is fixed to, or -1 (free)
  const SparseWeights* weights = nullptr;  ///< bone weights for Segments and Tissues (null: none)
  std::vector<int> tetLabels;         ///< #T labels for Tissues (empty: none)
  std::uint64_t key = 0;              ///< the same for the same rest mesh between runs (warm start)
};

/// Relaxes posed (#V by 3, the skinned nodes; the result in place) with options, regions set by
/// `regions` (see setVolumeRegions), started from warmStart's correction when `useWarmStart` (see
/// RelaxationWarmStart::offer), which then keeps this run's correction (forgotten when it fails).
/// Throws as relaxCorotational does; posed is then unchanged.
void relaxSkinnedMesh(const RelaxationRestMesh& rest, VolumeRegionChoice regions, CorotationalOptions options,
                      bool useWarmStart, RelaxationWarmStart& warmStart, Points& posed,
                      CorotationalReport* report);

}  // namespace repose
