#pragma once
// Volume regions of the fixed-corotated energy (internal to corotational_fem, see
// CorotationalOptions::volumeRegions): one volume term per region of tets, its pressure, and the
// augmented-Lagrangian multiplier that takes that pressure over so the region keeps its rest volume.
#include <vector>

#include "block_sparse_cg.h"
#include "fem_tet_geometry.h"

namespace repose {
namespace fem {

struct VolumeRegions {
  int count = 0;                   ///< regions (0: no term)
  std::vector<int> region;         ///< #T (empty when count is 0): the tet's region, -1 none
  std::vector<double> rest;        ///< count: V_r0, the rest volume of the region's tets (mm^3)
  std::vector<double> volume;      ///< count: V_r at the last evaluated pose
  std::vector<double> pressure;    ///< count: multiplier + penalty pressure at that pose
  std::vector<double> multiplier;  ///< count: Lambda_r, the augmented-Lagrangian term's
  /// The Hessian's coupling of each region's nodes, stiffness / V_r0 times the volume gradient's outer
  /// product: one term per (free node, region of an incident tet); assemble() fills the gradients.
  LowRankTerm3 coupling;

  /// Regions from ids (#T, or empty: none) over the tets with a free node (hasFree, #T), the others
  /// keep their volume anyway; multipliers 0. stiffness: regionVolumeStiffness * lambda. incStart,
  /// incTet: the free nodes' incidences (fem_newton_matrix.h).
  void setUp(const std::vector<int>& ids, const std::vector<char>& hasFree, const std::vector<RestTet>& restTets,
             const std::vector<int>& incStart, const std::vector<int>& incTet, double stiffness);
  /// From the summed volumes: each region's pressure, and its energy added to `energy` region by region.
  void updatePressures(double& energy);
  /// max_r |V_r / V_r0 - 1| over the regions with a rest volume.
  double worstExcess() const;
  /// V_r / V_r0 per region (1 where there is no rest volume).
  std::vector<double> ratios() const;
};

}  // namespace fem
}  // namespace repose
