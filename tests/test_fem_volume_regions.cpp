// The fixed-corotated energy's volume regions: each region keeps its volume as a whole.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "corotational_test_meshes.h"

namespace {

using repose::CorotationalOptions;
using repose::CorotationalReport;
using repose::Points;

// A block indented by a stamp on part of its top: linear tets at nu = 0.45 lose volume under the
// stamp. A volume term per region (two halves of the block) holds each half's volume as a whole,
// and the minimum does not depend on the solver (CHOLMOD's Newton matrix omits the term's low-rank
// part, so its iterates differ; the two-level CG includes it).
TEST(FixedCorotatedFem, RegionVolumeTermsKeepEachRegionsVolume) {
  const StampedBlock block = stampedBlock(8, 4, 4, 2, 5, 0.6);
  const Box& b = block.b;
  const std::vector<int>& fixed = block.fixed;
  const Points& stamped = block.stamped;
  std::vector<int> half(std::size_t(b.tets.rows()));
  std::vector<double> restVolume(2, 0.0);
  for (Eigen::Index t = 0; t < b.tets.rows(); ++t) {
    double cx = 0;
    for (int a = 0; a < 4; ++a) cx += 0.25 * b.nodes(b.tets(t, a), 0);
    half[std::size_t(t)] = cx < 4.0 ? 0 : 1;
    restVolume[std::size_t(half[std::size_t(t)])] += repose::tetVolume(
        b.nodes.row(b.tets(t, 0)).transpose(), b.nodes.row(b.tets(t, 1)).transpose(),
        b.nodes.row(b.tets(t, 2)).transpose(), b.nodes.row(b.tets(t, 3)).transpose());
  }
  auto halfRatios = [&](const Points& x) {
    std::vector<double> v(2, 0.0);
    for (Eigen::Index t = 0; t < b.tets.rows(); ++t)
      v[std::size_t(half[std::size_t(t)])] += repose::tetVolume(
          x.row(b.tets(t, 0)).transpose(), x.row(b.tets(t, 1)).transpose(), x.row(b.tets(t, 2)).transpose(),
          x.row(b.tets(t, 3)).transpose());
    return std::vector<double>{v[0] / restVolume[0], v[1] / restVolume[1]};
  };
  CorotationalOptions opt = fixedCorotated(CorotationalOptions::TwoLevel);
  opt.poisson = 0.45;
  opt.coarseAggregateSize = 20;
  Points plain = stamped;
  repose::relaxCorotational(b.nodes, b.tets, fixed, plain, opt);
  const std::vector<double> without = halfRatios(plain);
  opt.volumeRegions = half;
  opt.regionVolumeStiffness = 10.0;
  opt.regionVolumeTolerance = 1.0;  // the penalty alone here; the multiplier updates are tested below
  Points held[2] = {stamped, stamped};
  for (int k = 0; k < 2; ++k) {
    opt.preconditioner = k == 0 ? CorotationalOptions::TwoLevel : CorotationalOptions::Cholmod;
    CorotationalReport rep;
    repose::relaxCorotational(b.nodes, b.tets, fixed, held[k], opt, &rep);
    EXPECT_TRUE(rep.converged) << "preconditioner " << opt.preconditioner;
    EXPECT_EQ(rep.invertedAfter, 0);
    const std::vector<double> with = halfRatios(held[k]);
    ASSERT_EQ(rep.regionVolumeRatio.size(), 2u);
    for (int r = 0; r < 2; ++r) {
      EXPECT_NEAR(rep.regionVolumeRatio[std::size_t(r)], with[std::size_t(r)], 1e-9);
      EXPECT_LT(std::abs(with[std::size_t(r)] - 1), 0.25 * std::abs(without[std::size_t(r)] - 1)) << "half " << r;
    }
    std::printf("stamped block, nu = 0.45, volume ratio of the halves: %.5f %.5f, with region terms %.5f %.5f\n",
                without[0], without[1], with[0], with[1]);
  }
  EXPECT_LT(without[0], 0.99);
  EXPECT_LT((held[0] - held[1]).cwiseAbs().maxCoeff(), 1e-4);
  EXPECT_GT((held[0] - plain).cwiseAbs().maxCoeff(), 1e-2);
  // The penalty leaves each half short by about its pressure / stiffness; the multiplier updates
  // (augmented Lagrangian) take each half to its rest volume within the tolerance.
  const std::vector<double> penaltyOnly = halfRatios(held[0]);
  EXPECT_GT(std::max(std::abs(penaltyOnly[0] - 1), std::abs(penaltyOnly[1] - 1)), 1e-3);
  opt.preconditioner = CorotationalOptions::TwoLevel;
  opt.regionVolumeTolerance = 1e-5;
  for (double stiffness : {10.0, 30.0}) {
    opt.regionVolumeStiffness = stiffness;
    Points exact = stamped;
    CorotationalReport rep;
    repose::relaxCorotational(b.nodes, b.tets, fixed, exact, opt, &rep);
    const std::vector<double> ratio = halfRatios(exact);
    std::printf("stiffness %.0f: after %d multiplier updates the halves keep %.7f %.7f of their volume\n", stiffness,
                rep.regionVolumeUpdates, ratio[0], ratio[1]);
    EXPECT_GE(rep.regionVolumeUpdates, 1);
    EXPECT_LE(rep.regionVolumeUpdates, opt.maxRegionVolumeUpdates);
    EXPECT_EQ(rep.invertedAfter, 0);
    for (int r = 0; r < 2; ++r) EXPECT_NEAR(ratio[std::size_t(r)], 1.0, 1e-5) << "stiffness " << stiffness << " half " << r;
    for (Eigen::Index v = 0; v < exact.rows(); ++v)
      if (fixed[std::size_t(v)] >= 0) EXPECT_EQ(exact.row(v), stamped.row(v));
  }
  opt.maxRegionVolumeUpdates = -1;
  EXPECT_THROW(repose::relaxCorotational(b.nodes, b.tets, fixed, plain, opt), std::invalid_argument);
  opt.maxRegionVolumeUpdates = 4;
  opt.regionVolumeTolerance = -1e-5;
  EXPECT_THROW(repose::relaxCorotational(b.nodes, b.tets, fixed, plain, opt), std::invalid_argument);
  opt.regionVolumeTolerance = 1e-5;
  // Bad regions: one entry per tet, each below the tet count.
  Points x = stamped;
  opt.volumeRegions.back() = int(b.tets.rows());
  EXPECT_THROW(repose::relaxCorotational(b.nodes, b.tets, fixed, x, opt), std::invalid_argument);
  opt.volumeRegions.pop_back();
  EXPECT_THROW(repose::relaxCorotational(b.nodes, b.tets, fixed, x, opt), std::invalid_argument);
  EXPECT_EQ(x, stamped);
}

}  // namespace
