#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cstdio>
#include <filesystem>
#include <map>
#include <unistd.h>
#include <random>
#include <set>
#include <stdexcept>
#include <string>

#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>

#include "image_grid.h"
#include "vdb_volume_writer.h"

namespace {

std::string tempPath(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("repose_test_" + std::to_string(::getpid()) + "_" + name)).string();
}

// A tilted, anisotropic grid so the transform check covers origin, spacing and direction.
repose::ImageGrid tiltedGrid() {
  repose::ImageGrid g;
  g.dims = {23, 17, 30};
  g.origin = Eigen::Vector3d(-120.5, 33.25, 7.0);
  g.spacing = Eigen::Vector3d(0.8, 1.1, 2.5);
  g.direction = Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  return g;
}

// A few labelled blobs in a zero background.
repose::LabelVolume blobs() {
  repose::LabelVolume v;
  v.grid = tiltedGrid();
  v.data.assign(v.grid.voxelCount(), 0);
  for (int k = 0; k < v.grid.dims[2]; ++k)
    for (int j = 0; j < v.grid.dims[1]; ++j)
      for (int i = 0; i < v.grid.dims[0]; ++i) {
        const double r1 = std::hypot(i - 8.0, j - 8.0, k - 10.0), r2 = std::hypot(i - 15.0, j - 9.0, k - 20.0);
        std::int32_t l = 0;
        if (r1 < 6) l = r1 < 3 ? 7 : 2;
        else if (r2 < 5) l = 40000;  // labels beyond 16 bits survive
        else if (i == 22 && j == 16 && k == 29) l = -3;  // corner voxel, negative label
        v.at(i, j, k) = l;
      }
  return v;
}

openvdb::GridPtrVecPtr readAll(const std::string& path) {
  openvdb::initialize();
  openvdb::io::File file(path);
  file.open();
  auto grids = file.getGrids();
  file.close();
  return grids;
}

template <class GridT>
typename GridT::Ptr findGrid(const openvdb::GridPtrVec& grids, const std::string& name) {
  for (const auto& g : grids)
    if (g->getName() == name) return openvdb::gridPtrCast<GridT>(g);
  return nullptr;
}

void expectSameTransform(const openvdb::GridBase& grid, const repose::ImageGrid& g) {
  for (const Eigen::Vector3d ijk : {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(22, 16, 29), Eigen::Vector3d(3.5, 7, 11)}) {
    const openvdb::Vec3d w = grid.transform().indexToWorld(openvdb::Vec3d(ijk.x(), ijk.y(), ijk.z()));
    const Eigen::Vector3d x = g.indexToPhysical(ijk);
    for (int a = 0; a < 3; ++a) EXPECT_NEAR(w[a], x[a], 1e-9);
  }
}

}  // namespace

TEST(VdbVolumeWriter, LabelsRoundTripEveryVoxel) {
  const repose::LabelVolume v = blobs();
  const std::string path = tempPath("labels.vdb");
  const repose::VdbWriteReport r = repose::writeLabelsVdb(v, path);
  std::size_t nonZero = 0;
  std::set<std::int32_t> labels;
  for (auto l : v.data)
    if (l != 0) ++nonZero, labels.insert(l);
  EXPECT_EQ(r.activeVoxels, nonZero);
  EXPECT_EQ(r.grids, 1 + labels.size());
  EXPECT_GT(r.memoryBytes, 0u);

  const auto grids = readAll(path);
  auto labelGrid = findGrid<openvdb::Int32Grid>(*grids, "labels");
  ASSERT_TRUE(labelGrid);
  EXPECT_EQ(labelGrid->background(), 0);
  EXPECT_EQ(std::size_t(labelGrid->activeVoxelCount()), nonZero);
  expectSameTransform(*labelGrid, v.grid);
  std::map<std::int32_t, openvdb::FloatGrid::Ptr> fog;
  for (auto l : labels) {
    fog[l] = findGrid<openvdb::FloatGrid>(*grids, "label_" + std::to_string(l));
    ASSERT_TRUE(fog[l]) << l;
    EXPECT_EQ(fog[l]->getGridClass(), openvdb::GRID_FOG_VOLUME);
    expectSameTransform(*fog[l], v.grid);
  }
  auto acc = labelGrid->getConstAccessor();
  for (int k = 0; k < v.grid.dims[2]; ++k)
    for (int j = 0; j < v.grid.dims[1]; ++j)
      for (int i = 0; i < v.grid.dims[0]; ++i) {
        const openvdb::Coord c(i, j, k);
        const std::int32_t l = v.at(i, j, k);
        ASSERT_EQ(acc.getValue(c), l) << i << " " << j << " " << k;
        ASSERT_EQ(acc.isValueOn(c), l != 0);
        for (const auto& [fl, grid] : fog) ASSERT_EQ(grid->tree().getValue(c), fl == l ? 1.0f : 0.0f);
      }
  // Nothing outside the volume's extent.
  const openvdb::CoordBBox box = labelGrid->evalActiveVoxelBoundingBox();
  EXPECT_GE(box.min().x(), 0);
  EXPECT_LE(box.max().z(), v.grid.dims[2] - 1);
  std::remove(path.c_str());
}

TEST(VdbVolumeWriter, WithoutFogGridsOnlyLabels) {
  const repose::LabelVolume v = blobs();
  const std::string path = tempPath("labels_only.vdb");
  repose::VdbWriteOptions o;
  o.labelFogGrids = false;
  EXPECT_EQ(repose::writeLabelsVdb(v, path, o).grids, 1u);
  EXPECT_EQ(readAll(path)->size(), 1u);
  std::remove(path.c_str());
}

TEST(VdbVolumeWriter, IntensityRoundTripEveryVoxel) {
  repose::IntensityVolume v;
  v.grid = tiltedGrid();
  v.data.assign(v.grid.voxelCount(), -1024.0f);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-900.0f, 1500.0f);
  for (int k = 4; k < 20; ++k)
    for (int j = 2; j < 12; ++j)
      for (int i = 1; i < 21; ++i) v.at(i, j, k) = u(rng);
  const std::string path = tempPath("ct.vdb");
  const repose::VdbWriteReport r = repose::writeIntensityVdb(v, -1024.0f, path, "ct");
  EXPECT_EQ(r.activeVoxels, std::size_t(16 * 10 * 20));
  const auto grids = readAll(path);
  auto ct = findGrid<openvdb::FloatGrid>(*grids, "ct");
  ASSERT_TRUE(ct);
  EXPECT_EQ(ct->background(), -1024.0f);
  expectSameTransform(*ct, v.grid);
  auto acc = ct->getConstAccessor();
  for (int k = 0; k < v.grid.dims[2]; ++k)
    for (int j = 0; j < v.grid.dims[1]; ++j)
      for (int i = 0; i < v.grid.dims[0]; ++i) ASSERT_EQ(acc.getValue(openvdb::Coord(i, j, k)), v.at(i, j, k));
  std::remove(path.c_str());
}

TEST(VdbVolumeWriter, BadInputThrows) {
  repose::LabelVolume v = blobs();
  const std::string path = tempPath("bad.vdb");
  v.data.pop_back();
  EXPECT_THROW(repose::writeLabelsVdb(v, path), std::invalid_argument);
  v = blobs();
  v.grid.spacing.z() = 0;
  EXPECT_THROW(repose::writeLabelsVdb(v, path), std::invalid_argument);
  EXPECT_FALSE(std::filesystem::exists(path));
  v = blobs();
  EXPECT_THROW(repose::writeLabelsVdb(v, "/nonexistent-dir/x.vdb"), std::runtime_error);
}
