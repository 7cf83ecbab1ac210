// The meshing grid (the body binned to the meshing spacing) and the spacing chosen from a tet budget.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "mesh_budget.h"
#include "meshing_grid.h"
#include "volume_test_grids.h"

using namespace repose;
using namespace repose::testing;

TEST(MeshingGrid, BinsTwoByTwoAndKeepsThinBones) {
  const ImageGrid native = makeGrid(8, 6, 5, {1, 1, 3});
  const ImageGrid coarse = meshingGrid(native, 2.0);
  EXPECT_EQ(coarse.dims, (std::array<int, 3>{4, 3, 5}));  // z is already coarser than 2 mm
  EXPECT_DOUBLE_EQ(coarse.spacing[0], 2.0);
  EXPECT_DOUBLE_EQ(coarse.spacing[2], 3.0);
  // Coarse voxel (0,0,0) is centred between native voxels 0 and 1 along i and j.
  EXPECT_TRUE(coarse.indexToPhysical(Eigen::Vector3d::Zero())
                  .isApprox(native.indexToPhysical(Eigen::Vector3d(0.5, 0.5, 0))));

  MaskVolume body = filled<std::uint8_t>(native, 0);
  LabelVolume labels = filled<std::int32_t>(native, 0);
  body.at(0, 0, 0) = body.at(1, 0, 0) = 1;  // half of coarse (0,0,0): body
  body.at(2, 0, 0) = 1;                     // a quarter of coarse (1,0,0): not body
  labels.at(5, 5, 2) = 7;                   // one bone voxel in coarse (2,2,2): body, bone 0
  body.at(5, 5, 2) = 1;
  const MeshingVolumes m = binToMeshingGrid(body, labels, {-1, -1, -1, -1, -1, -1, -1, 0}, coarse);
  EXPECT_EQ(m.body.at(0, 0, 0), 1);
  EXPECT_EQ(m.body.at(1, 0, 0), 0);
  EXPECT_EQ(m.body.at(2, 2, 2), 1);
  EXPECT_EQ(m.bone.at(2, 2, 2), 0);
  EXPECT_EQ(m.bone.at(0, 0, 0), -1);
  EXPECT_THROW(binToMeshingGrid(body, labels, {}, meshingGrid(makeGrid(8, 6, 4), 2.0)), std::invalid_argument);
  // At (or below) the scan's spacing the meshing grid is the scan's grid.
  EXPECT_TRUE(meshingGrid(native, 0.5).sameGridAs(native));
}

TEST(MeshBudget, SpacingGrowsAsTheBudgetShrinks) {
  // A solid block with a bone rod: faces scale as 1 / h^2, and so does the predicted tet count.
  const ImageGrid g = makeGrid(60, 40, 80, {1, 1, 1});
  MaskVolume body = filled<std::uint8_t>(g, 0);
  LabelVolume labels = filled<std::int32_t>(g, 0);
  for (int k = 4; k < 76; ++k)
    for (int j = 4; j < 36; ++j)
      for (int i = 4; i < 56; ++i) {
        body.at(i, j, k) = 1;
        labels.at(i, j, k) = std::hypot(i - 30, j - 20) < 4 ? 2 : 1;
      }
  const std::vector<int> boneOfLabel = {-1, -1, 0};
  EXPECT_EQ(boundaryFaces(body), std::size_t(2 * (52 * 32 + 52 * 72 + 32 * 72)));
  const MeshSpacingChoice native = chooseMeshSpacing(body, labels, boneOfLabel, 1e9);
  EXPECT_DOUBLE_EQ(native.spacingMm, 1.0);
  EXPECT_EQ(native.trials, 1);
  const MeshSpacingChoice half = chooseMeshSpacing(body, labels, boneOfLabel, native.predictedTets / 4);
  const MeshSpacingChoice tenth = chooseMeshSpacing(body, labels, boneOfLabel, native.predictedTets / 10);
  EXPECT_LE(half.predictedTets, native.predictedTets / 4);
  EXPECT_GE(half.predictedTets, 0.6 * native.predictedTets / 4);  // not far below the budget
  EXPECT_GT(half.spacingMm, 1.5);
  EXPECT_GT(tenth.spacingMm, half.spacingMm);
  EXPECT_LE(tenth.predictedTets, native.predictedTets / 10);
  EXPECT_THROW(chooseMeshSpacing(body, labels, boneOfLabel, 10), std::invalid_argument);
  EXPECT_EQ(seedSteps(g, 1.0).surface, 2);
  EXPECT_EQ(seedSteps(g, 3.0).surface, 6);
  EXPECT_EQ(seedSteps(g, 3.0).interior, 12);
}
