#pragma once
// Relaxing part of the mesh on its own (internal to corotational_fem): a neighbourhood's free nodes
// are the unknowns, every other node is held, and the part is solved as a mesh of its own. The
// untangling rounds relax the nodes they moved this way (relaxNeighbourhood, corotational_fem.h),
// and a cold start relaxes the joints' strained tissue first (strainedRegionThreshold).
#include <vector>

#include "corotational_fem.h"
#include "fem_tet_geometry.h"

namespace repose {
namespace fem {

/// The free nodes of centre and `rings` rings of free neighbours (nodes sharing a tet), as #V flags.
std::vector<char> grownNeighbourhood(const Tets& tets, const std::vector<int>& fixedBone, const std::vector<int>& centre,
                                     int rings);

/// relaxNeighbourhood on the flagged unknowns (active, #V), its checkpoint reporting `phase`;
/// returns their count (0: no part, or a part no node holds, left as it is).
int relaxPart(const Points& rest, const Tets& tets, const std::vector<int>& fixedBone, Points& posed,
              const std::vector<char>& active, const CorotationalOptions& options, RelaxationProgress::Phase phase,
              CorotationalReport* report);

/// The strained region first (see CorotationalOptions::strainedRegionThreshold), before the whole
/// mesh's matrix and per-tet state exist, so that the part's own do not sit beside them. nFree: the
/// whole solve's unknowns. Returns whether it ran (posed then holds its result); fills the report's
/// strainedRegion fields.
bool relaxStrainedRegionFirst(const Points& rest, const Tets& tets, const std::vector<int>& fixedBone,
                              const std::vector<RestTet>& restTets, std::size_t nFree, double lambda, double mu,
                              Points& posed, const CorotationalOptions& options, CorotationalReport& rep);

}  // namespace fem
}  // namespace repose
