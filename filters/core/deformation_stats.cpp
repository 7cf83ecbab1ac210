#include "deformation_stats.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace repose {

DeformationStats deformationStats(const Points& rest, const Points& posed, const Tets& tets,
                                  const std::vector<std::int32_t>& tetLabel) {
  if (rest.rows() != posed.rows()) throw std::invalid_argument("deformation stats: rest and posed node counts differ");
  if (!tetLabel.empty() && tetLabel.size() != std::size_t(tets.rows()))
    throw std::invalid_argument("deformation stats: one label per tet is needed");
  if (tets.rows() > 0 && (tets.minCoeff() < 0 || tets.maxCoeff() >= rest.rows()))
    throw std::invalid_argument("deformation stats: a tet refers to a node index outside [0, " +
                                std::to_string(rest.rows()) + ")");
  DeformationStats s;
  double restTotal = 0, posedTotal = 0, sumDev = 0;
  std::map<std::int32_t, std::pair<double, double>> perLabel;  // rest, posed
  for (Eigen::Index t = 0; t < tets.rows(); ++t) {
    const double v0 = tetVolume(rest.row(tets(t, 0)), rest.row(tets(t, 1)), rest.row(tets(t, 2)), rest.row(tets(t, 3)));
    const double v = tetVolume(posed.row(tets(t, 0)), posed.row(tets(t, 1)), posed.row(tets(t, 2)), posed.row(tets(t, 3)));
    if (!(v0 > 0)) throw std::invalid_argument("deformation stats: rest tet " + std::to_string(t) + " is degenerate or inverted");
    restTotal += v0;
    posedTotal += v;
    if (v <= 0) ++s.invertedTets;
    const double dev = std::abs(v / v0 - 1);
    sumDev += dev;
    s.maxAbsDetFMinus1 = std::max(s.maxAbsDetFMinus1, dev);
    if (!tetLabel.empty()) {
      auto& acc = perLabel[tetLabel[std::size_t(t)]];
      acc.first += v0;
      acc.second += v;
    }
  }
  if (tets.rows() > 0) {
    s.volumeRatio = posedTotal / restTotal;
    s.meanAbsDetFMinus1 = sumDev / double(tets.rows());
  }
  for (const auto& [label, acc] : perLabel) s.labelVolumeRatio[label] = acc.second / acc.first;
  return s;
}

}  // namespace repose
