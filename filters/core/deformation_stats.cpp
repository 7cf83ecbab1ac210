#include "deformation_stats.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>
#include <stdexcept>
#include <string>

namespace repose {

namespace {

Eigen::Matrix3d edgeMatrix(const Points& p, const Tets& tets, Eigen::Index t) {
  Eigen::Matrix3d d;
  for (int e = 0; e < 3; ++e) d.col(e) = (p.row(tets(t, e + 1)) - p.row(tets(t, 0))).transpose();
  return d;
}

/// Largest singular value of the deformation gradient F = posed edges * rest edges^-1.
double largestStretch(const Eigen::Matrix3d& restEdges, const Eigen::Matrix3d& posedEdges) {
  const Eigen::Matrix3d F = posedEdges * restEdges.inverse();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
  eig.computeDirect(F.transpose() * F, Eigen::EigenvaluesOnly);
  return std::sqrt(std::max(0.0, eig.eigenvalues().maxCoeff()));
}

}  // namespace

DeformationStats deformationStats(const Points& rest, const Points& posed, const Tets& tets,
                                  const std::vector<std::int32_t>& tetLabel) {
  if (rest.rows() != posed.rows()) throw std::invalid_argument("deformation stats: rest and posed node counts differ");
  if (!tetLabel.empty() && tetLabel.size() != std::size_t(tets.rows()))
    throw std::invalid_argument("deformation stats: one label per tet is needed");
  if (tets.rows() > 0 && (tets.minCoeff() < 0 || tets.maxCoeff() >= rest.rows()))
    throw std::invalid_argument("deformation stats: a tet refers to a node index outside [0, " +
                                std::to_string(rest.rows()) + ")");
  DeformationStats s;
  s.tets = std::size_t(tets.rows());
  double restTotal = 0, posedTotal = 0, sumDev = 0;
  std::map<std::int32_t, std::pair<double, double>> perLabel;  // rest, posed
  for (Eigen::Index t = 0; t < tets.rows(); ++t) {
    const double v0 = tetVolume(rest.row(tets(t, 0)), rest.row(tets(t, 1)), rest.row(tets(t, 2)), rest.row(tets(t, 3)));
    const double v = tetVolume(posed.row(tets(t, 0)), posed.row(tets(t, 1)), posed.row(tets(t, 2)), posed.row(tets(t, 3)));
    if (!(v0 > 0)) throw std::invalid_argument("deformation stats: rest tet " + std::to_string(t) + " is degenerate or inverted");
    restTotal += v0;
    posedTotal += v;
    if (v <= 0) ++s.invertedTets;
    const double stretch = largestStretch(edgeMatrix(rest, tets, t), edgeMatrix(posed, tets, t));
    s.maxStretch = std::max(s.maxStretch, stretch);
    if (stretch > kWebStretch) s.stretchedVolumeMm3 += v0;
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
