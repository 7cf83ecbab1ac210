#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <vector>

#include "box_tet_mesh.h"
#include "pull_resample_cache.h"
#include "resample_pull.h"
#include "tet_boundary.h"

namespace {

using repose::ImageGrid;
using repose::Points;
using repose::PullResampleCache;
using repose::PullResampleOptions;
using repose::Tets;

ImageGrid restGrid() {
  ImageGrid g;
  g.dims = {24, 20, 18};
  g.origin = {-5.0, 3.0, 10.0};
  g.spacing = {1.0, 1.25, 0.8};
  return g;
}

// The grid minus its outer voxel layer, like the peeled body masks the real meshes are built from.
void peeledMesh(const ImageGrid& g, Points& V, Tets& T) {
  kuhnBoxMesh(Eigen::Vector3d(1, 1, 1), Eigen::Vector3d(g.dims[0] - 2, g.dims[1] - 2, g.dims[2] - 2), {5, 6, 4}, V, T);
  for (Eigen::Index v = 0; v < V.rows(); ++v) V.row(v) = g.indexToPhysical(V.row(v).transpose()).transpose();
}

std::vector<std::int32_t> blockLabels(const ImageGrid& g) {
  std::vector<std::int32_t> L(g.voxelCount());
  for (int k = 0; k < g.dims[2]; ++k)
    for (int j = 0; j < g.dims[1]; ++j)
      for (int i = 0; i < g.dims[0]; ++i) L[g.linearIndex(i, j, k)] = 1 + (i / 3 + 3 * (j / 4) + 7 * (k / 5)) % 13;
  return L;
}

// The rest nodes turned 10 degrees about z through the grid's centre.
Points turned(const Points& V, const ImageGrid& g) {
  const Eigen::Vector3d c = g.indexToPhysical(Eigen::Vector3d(g.dims[0], g.dims[1], g.dims[2]) * 0.5);
  const Eigen::Matrix3d R = Eigen::AngleAxisd(10.0 * M_PI / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  Points P = V;
  for (Eigen::Index v = 0; v < V.rows(); ++v) P.row(v) = (R * (V.row(v).transpose() - c) + c).transpose();
  return P;
}

// The peeled mesh of restGrid(), and a cache holding it.
class CachedPull : public ::testing::Test {
 protected:
  ImageGrid g = restGrid();
  Points V;
  Tets T;
  PullResampleCache cache;
  CachedPull() {
    peeledMesh(g, V, T);
    cache.setTets(T);
    cache.setRestNodes(V);
    cache.setRestGrid(g);
  }
};

// The rest inputs of the extrapolation derived here, as the cache should derive them.
struct DerivedInputs {
  repose::TetBoundary boundary;
  repose::MaskVolume coverage, distance;
  DerivedInputs(const ImageGrid& g, const Points& V, const Tets& T)
      : boundary(repose::tetBoundary(T)), coverage(repose::restMeshCoverage(g, V, T)),
        distance(repose::restMeshDistance(coverage)) {}
  PullResampleOptions options() const {
    PullResampleOptions o;
    o.boundary = &boundary;
    o.restCoverage = &coverage;
    o.restDistance = &distance;
    return o;
  }
};

// The pull with every rest input derived here, as the cache should derive it.
std::vector<std::int32_t> directLabels(const ImageGrid& g, const std::vector<std::int32_t>& labels, const Points& V,
                                       const Tets& T, const Points& P, const ImageGrid& out,
                                       repose::PullResampleReport* report) {
  repose::LabelVolume rest;
  rest.grid = g;
  rest.data = labels;
  const DerivedInputs derived(g, V, T);
  const PullResampleOptions options = derived.options();
  std::vector<std::int32_t> result(out.voxelCount());
  repose::resampleLabelsPullInto(rest, V, P, T, out, options, result.data(), 0, report);
  return result;
}

TEST_F(CachedPull, LabelsMatchThePullWithTheRestInputsDerivedOnce) {
  const Points P = turned(V, g);
  cache.setLabels(blockLabels(g));
  repose::PullResampleReport expectedReport, report;
  const auto expected = directLabels(g, blockLabels(g), V, T, P, g, &expectedReport);
  ASSERT_GT(expectedReport.extrapolatedVoxels, 0u);  // the boundary and coverage were used
  for (int pose = 0; pose < 2; ++pose) {  // the second pose reuses the derived inputs
    std::vector<std::int32_t> got(g.voxelCount(), -7);
    const auto counts = cache.labelsInto(P, g, PullResampleOptions{}, got.data(), 0, false, &report);
    EXPECT_EQ(got, expected);
    EXPECT_EQ(report.coveredVoxels, expectedReport.coveredVoxels);
    EXPECT_EQ(report.extrapolatedVoxels, expectedReport.extrapolatedVoxels);
    EXPECT_EQ(counts.changedVoxels, 0u);
  }
}

TEST_F(CachedPull, NewRestNodesOrTetsRebuildTheCoverage) {
  cache.setLabels(blockLabels(g));
  std::vector<std::int32_t> got(g.voxelCount());
  cache.labelsInto(turned(V, g), g, PullResampleOptions{}, got.data(), 0, false, nullptr);
  // Rest nodes shrunk towards the centre: the old coverage would let the extrapolation sample voxels
  // the new rest mesh no longer covers differently.
  Points V2 = V;
  const Eigen::RowVector3d c = V.colwise().mean();
  for (Eigen::Index v = 0; v < V.rows(); ++v) V2.row(v) = c + 0.7 * (V.row(v) - c);
  cache.setRestNodes(V2);
  cache.labelsInto(turned(V2, g), g, PullResampleOptions{}, got.data(), 0, false, nullptr);
  EXPECT_EQ(got, directLabels(g, blockLabels(g), V2, T, turned(V2, g), g, nullptr));
  // Half the tets: a new boundary too.
  const Tets T2 = T.topRows(T.rows() / 2);
  cache.setTets(T2);
  cache.labelsInto(turned(V2, g), g, PullResampleOptions{}, got.data(), 0, false, nullptr);
  EXPECT_EQ(got, directLabels(g, blockLabels(g), V2, T2, turned(V2, g), g, nullptr));
}

TEST_F(CachedPull, IntensitiesAndDisplacementUseTheSameRestInputs) {
  const Points P = turned(V, g);
  repose::IntensityVolume rest;
  rest.grid = g;
  rest.data.resize(g.voxelCount());
  for (std::size_t v = 0; v < rest.data.size(); ++v) rest.data[v] = float(v % 97) * 0.5f;
  cache.setIntensities(rest.data);
  const DerivedInputs derived(g, V, T);
  const PullResampleOptions options = derived.options();
  std::vector<float> expected(g.voxelCount()), got(g.voxelCount());
  repose::resampleIntensityPullInto(rest, V, P, T, g, options, expected.data(), -1.0f, nullptr);
  cache.intensitiesInto(P, g, PullResampleOptions{}, got.data(), -1.0f, nullptr);
  EXPECT_EQ(got, expected);
  std::vector<float> expectedField(3 * g.voxelCount()), field(3 * g.voxelCount());
  repose::displacementPullInto(g, V, P, T, g, options, expectedField.data(), nullptr);
  cache.displacementInto(P, g, PullResampleOptions{}, field.data(), nullptr);
  EXPECT_EQ(field, expectedField);
}

}  // namespace
