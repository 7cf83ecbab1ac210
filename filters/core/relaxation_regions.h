#pragma once
// Which regions the relaxation holds at their rest volume as a whole (CorotationalOptions::
// volumeRegions), from the user's choice and what the rest mesh carries.
#include <vector>

#include "corotational_fem.h"
#include "sparse_weights.h"
#include "tet_mesh.h"

namespace repose {

/// None: the paper's solve; Body: the whole body as one region; Segments: body segments (see
/// bodySegments); Tissues: segments split by the tets' labels (see tissueSegments).
enum class VolumeRegionChoice { None = 0, Body = 1, Segments = 2, Tissues = 3 };

/// Sets options.volumeRegions (and, for Tissues, options.pathVolumeRegions: the continuation's path
/// keeps the segments) for the #T tets. The linear model has no region terms: nothing is set for it.
/// Segments need the rest mesh's bone weights (weights null: the body as one region); Tissues needs
/// tetLabels, one per tet (another length: Segments).
/// Throws std::invalid_argument when a tet names a node the weights do not cover.
void setVolumeRegions(VolumeRegionChoice choice, const SparseWeights* weights, const std::vector<int>& tetLabels,
                      const Tets& tets, CorotationalOptions& options);

}  // namespace repose
