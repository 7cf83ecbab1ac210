#include "fem_volume_regions.h"

#include <algorithm>
#include <cmath>

namespace repose {
namespace fem {

void VolumeRegions::setUp(const std::vector<int>& ids, const std::vector<char>& hasFree,
                          const std::vector<RestTet>& restTets, const std::vector<int>& incStart,
                          const std::vector<int>& incTet, double stiffness) {
  const std::size_t nT = hasFree.size(), nFree = incStart.size() - 1;
  count = 0;
  for (int r : ids) count = std::max(count, r + 1);
  region.assign(count > 0 ? nT : 0, -1);
  rest.assign(std::size_t(count), 0.0);
  volume.assign(std::size_t(count), 0.0);
  pressure.assign(std::size_t(count), 0.0);
  multiplier.assign(std::size_t(count), 0.0);
  coupling = LowRankTerm3{};
  if (count == 0) return;
  for (std::size_t t = 0; t < nT; ++t) {
    if (!hasFree[t] || ids[t] < 0) continue;
    region[t] = ids[t];
    rest[std::size_t(region[t])] += restTets[t].volume;
  }
  coupling.weight.resize(std::size_t(count));
  for (int r = 0; r < count; ++r)
    coupling.weight[std::size_t(r)] = rest[std::size_t(r)] > 0 ? stiffness / rest[std::size_t(r)] : 0.0;
  coupling.rowStart.assign(nFree + 1, 0);
  for (std::size_t i = 0; i < nFree; ++i) {
    const std::size_t first = coupling.term.size();
    for (int k = incStart[i]; k < incStart[i + 1]; ++k) {
      const int r = region[std::size_t(incTet[std::size_t(k)] / 4)];
      if (r >= 0 && std::find(coupling.term.begin() + std::ptrdiff_t(first), coupling.term.end(), r) == coupling.term.end())
        coupling.term.push_back(r);
    }
    coupling.rowStart[i + 1] = int(coupling.term.size());
  }
  coupling.vector.assign(3 * coupling.term.size(), 0.0);
}

void VolumeRegions::updatePressures(double& energy) {
  for (int r = 0; r < count; ++r) {
    const double excess = volume[std::size_t(r)] - rest[std::size_t(r)];
    const double penalty = coupling.weight[std::size_t(r)] * excess;
    pressure[std::size_t(r)] = multiplier[std::size_t(r)] + penalty;
    energy += (multiplier[std::size_t(r)] + 0.5 * penalty) * excess;
  }
}

double VolumeRegions::worstExcess() const {
  double worst = 0;
  for (int r = 0; r < count; ++r)
    if (rest[std::size_t(r)] > 0) worst = std::max(worst, std::abs(volume[std::size_t(r)] / rest[std::size_t(r)] - 1.0));
  return worst;
}

std::vector<double> VolumeRegions::ratios() const {
  std::vector<double> ratio(static_cast<std::size_t>(count));
  for (int r = 0; r < count; ++r)
    ratio[std::size_t(r)] = rest[std::size_t(r)] > 0 ? volume[std::size_t(r)] / rest[std::size_t(r)] : 1.0;
  return ratio;
}

}  // namespace fem
}  // namespace repose
