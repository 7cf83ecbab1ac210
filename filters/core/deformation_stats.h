#pragma once
// Volume fidelity of a posed tet mesh: how far skinning (or relaxation) is from keeping the tissue's
// volume, per body and per label, and how many tets turned inside out.
#include <cstdint>
#include <map>
#include <vector>

#include "tet_mesh.h"

namespace repose {

struct DeformationStats {
  double volumeRatio = 1;                          ///< posed mesh volume / rest
  std::map<std::int32_t, double> labelVolumeRatio; ///< per tet label: posed / rest volume of its tets
  std::size_t tets = 0;                            ///< tets measured
  std::size_t invertedTets = 0;                    ///< posed signed volume <= 0
  double meanAbsDetFMinus1 = 0;                    ///< mean over tets of |det F - 1| (det F = V / V0)
  double maxAbsDetFMinus1 = 0;
  double maxStretch = 1;          ///< largest principal stretch (singular value of F) of any tet
  double stretchedVolumeMm3 = 0;  ///< rest volume (mm^3) of the tets stretched past kWebStretch
};

/// A tet stretched past this many times its rest length along some direction is tissue pulled into
/// a web (two parts welded at rest and posed apart); a joint's own deformation stays well below.
constexpr double kWebStretch = 3.0;

/// rest/posed #V by 3, tets #T by 4 (positive at rest), tetLabel #T (may be empty: no per-label ratios).
/// Throws std::invalid_argument on size mismatches or degenerate rest tets.
DeformationStats deformationStats(const Points& rest, const Points& posed, const Tets& tets,
                                  const std::vector<std::int32_t>& tetLabel);

}  // namespace repose
