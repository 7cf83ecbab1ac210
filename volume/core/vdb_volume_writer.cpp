#include "vdb_volume_writer.h"
#include "written_file.h"

#include <chrono>
#include <cstdio>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <unistd.h>
#include <vector>

#include <Eigen/LU>
#include <openvdb/openvdb.h>
#include <openvdb/io/File.h>

#include "parallel_for.h"

namespace repose {
namespace {

using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

void initializeOnce() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

// x = origin + direction * diag(spacing) * ijk, as OpenVDB's row-vector matrix (translation in row 3).
openvdb::math::Transform::Ptr gridTransform(const ImageGrid& g) {
  const Eigen::Matrix3d a = g.direction * g.spacing.asDiagonal();
  if (!(std::abs(a.determinant()) > 0) || !a.allFinite() || !g.origin.allFinite())
    throw std::invalid_argument("vdb output: the volume's spacing/direction is singular or not finite");
  openvdb::math::Mat4d m = openvdb::math::Mat4d::identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) m[c][r] = a(r, c);
    m[3][r] = g.origin[r];
  }
  return openvdb::math::Transform::createLinearTransform(m);
}

template <class T>
void checkVolume(const Volume<T>& v, const char* what) {
  if (v.grid.dims[0] <= 0 || v.grid.dims[1] <= 0 || v.grid.dims[2] <= 0)
    throw std::invalid_argument(std::string("vdb output: the ") + what + " volume is empty");
  if (v.data.size() != v.grid.voxelCount())
    throw std::invalid_argument(std::string("vdb output: the ") + what + " volume has " +
                                std::to_string(v.data.size()) + " values for " +
                                std::to_string(v.grid.voxelCount()) + " voxels");
}

// Slabs of whole leaf nodes (8 voxels) in k, converted in parallel into trees of their own and then
// merged (disjoint leaves, so merging only moves nodes).
template <class T, class Visit>
void forEachSlab(const Volume<T>& v, std::size_t slabs, Visit visit) {
  const int nk = v.grid.dims[2];
  parallelFor(slabs, [&](std::size_t s0, std::size_t s1) {
    for (std::size_t s = s0; s < s1; ++s) {
      const int k0 = int(s) * 8, k1 = std::min(nk, k0 + 8);
      visit(s, k0, k1);
    }
  }, 1);
}

void writeGrids(const openvdb::GridPtrVec& grids, const std::string& path) {
  const std::string temp = path + ".tmp" + std::to_string(::getpid());
  try {
    openvdb::io::File file(temp);
    file.write(grids);
    file.close();
    requireWritten(path, temp);  // OpenVDB's stream can lose a short write on a full disk
  } catch (const WriteFailure&) {
    std::remove(temp.c_str());
    throw;
  } catch (const std::exception& e) {
    std::remove(temp.c_str());
    throw std::runtime_error(path + ": cannot write OpenVDB file (" + e.what() + ")");
  }
  if (std::rename(temp.c_str(), path.c_str()) != 0) {
    std::remove(temp.c_str());
    throw std::runtime_error(path + ": cannot write OpenVDB file (rename failed)");
  }
}

std::size_t memoryOf(const openvdb::GridPtrVec& grids) {
  std::size_t bytes = 0;
  for (const auto& g : grids) bytes += std::size_t(g->memUsage());
  return bytes;
}

// One grid from the slabs' trees (disjoint leaves), named and placed in LPS millimetres.
template <class GridT>
typename GridT::Ptr mergedGrid(const std::vector<typename GridT::TreeType::Ptr>& trees,
                               typename GridT::ValueType background, const std::string& name, const ImageGrid& g) {
  auto grid = GridT::create(background);
  for (auto& t : trees) grid->tree().merge(*t, openvdb::MERGE_ACTIVE_STATES);
  grid->tree().prune();
  grid->setName(name);
  grid->setTransform(gridTransform(g));
  grid->setGridClass(openvdb::GRID_UNKNOWN);
  grid->insertMeta("space", openvdb::StringMetadata("LPS millimetres"));
  return grid;
}

// Fills the report's sizes and times and writes the grids.
void finishAndWrite(const openvdb::GridPtrVec& grids, Clock::time_point buildStart, const std::string& path,
                    VdbWriteReport& report) {
  report.grids = grids.size();
  report.memoryBytes = memoryOf(grids);
  report.buildSeconds = secondsSince(buildStart);
  const auto t0 = Clock::now();
  writeGrids(grids, path);
  report.writeSeconds = secondsSince(t0);
}

}  // namespace

VdbWriteReport writeLabelsVdb(const LabelVolume& labels, const std::string& path, const VdbWriteOptions& options) {
  checkVolume(labels, "label");
  initializeOnce();
  VdbWriteReport report;
  const auto t0 = Clock::now();
  const ImageGrid& g = labels.grid;
  const std::size_t slabs = std::size_t((g.dims[2] + 7) / 8);
  std::vector<openvdb::Int32Tree::Ptr> labelTrees(slabs);
  std::vector<std::map<std::int32_t, openvdb::FloatTree::Ptr>> fogTrees(slabs);
  forEachSlab(labels, slabs, [&](std::size_t s, int k0, int k1) {
    auto tree = std::make_shared<openvdb::Int32Tree>(0);
    openvdb::tree::ValueAccessor<openvdb::Int32Tree> acc(*tree);
    std::map<std::int32_t, std::pair<openvdb::FloatTree::Ptr, std::unique_ptr<openvdb::tree::ValueAccessor<openvdb::FloatTree>>>> fog;
    std::int32_t lastLabel = 0;
    openvdb::tree::ValueAccessor<openvdb::FloatTree>* lastFog = nullptr;
    for (int k = k0; k < k1; ++k)
      for (int j = 0; j < g.dims[1]; ++j) {
        const std::int32_t* row = &labels.data[g.linearIndex(0, j, k)];
        for (int i = 0; i < g.dims[0]; ++i) {
          const std::int32_t l = row[i];
          if (l == 0) continue;
          const openvdb::Coord c(i, j, k);
          acc.setValue(c, l);
          if (!options.labelFogGrids) continue;
          if (!lastFog || l != lastLabel) {
            auto& entry = fog[l];
            if (!entry.first) {
              entry.first = std::make_shared<openvdb::FloatTree>(0.0f);
              entry.second = std::make_unique<openvdb::tree::ValueAccessor<openvdb::FloatTree>>(*entry.first);
            }
            lastFog = entry.second.get();
            lastLabel = l;
          }
          lastFog->setValue(c, 1.0f);
        }
      }
    labelTrees[s] = tree;
    for (auto& [l, entry] : fog) {
      entry.second.reset();  // release the accessor before the tree leaves this slab
      fogTrees[s][l] = entry.first;
    }
  });
  auto labelGrid = mergedGrid<openvdb::Int32Grid>(labelTrees, 0, "labels", g);
  openvdb::GridPtrVec grids{labelGrid};
  report.activeVoxels = std::size_t(labelGrid->activeVoxelCount());
  if (options.labelFogGrids) {
    std::map<std::int32_t, openvdb::FloatGrid::Ptr> fogGrids;
    for (auto& slab : fogTrees)
      for (auto& [l, tree] : slab) {
        auto& grid = fogGrids[l];
        if (!grid) grid = openvdb::FloatGrid::create(0.0f);
        grid->tree().merge(*tree, openvdb::MERGE_ACTIVE_STATES);
      }
    for (auto& [l, grid] : fogGrids) {
      grid->tree().prune();
      grid->setName("label_" + std::to_string(l));
      grid->setTransform(gridTransform(g));
      grid->setGridClass(openvdb::GRID_FOG_VOLUME);
      grid->insertMeta("label", openvdb::Int32Metadata(l));
      grids.push_back(grid);
    }
  }
  finishAndWrite(grids, t0, path, report);
  return report;
}

VdbWriteReport writeIntensityVdb(const IntensityVolume& image, float background, const std::string& path,
                                 const std::string& gridName) {
  checkVolume(image, "intensity");
  if (gridName.empty()) throw std::invalid_argument("vdb output: the grid needs a name");
  initializeOnce();
  VdbWriteReport report;
  const auto t0 = Clock::now();
  const ImageGrid& g = image.grid;
  const std::size_t slabs = std::size_t((g.dims[2] + 7) / 8);
  std::vector<openvdb::FloatTree::Ptr> trees(slabs);
  forEachSlab(image, slabs, [&](std::size_t s, int k0, int k1) {
    auto tree = std::make_shared<openvdb::FloatTree>(background);
    openvdb::tree::ValueAccessor<openvdb::FloatTree> acc(*tree);
    for (int k = k0; k < k1; ++k)
      for (int j = 0; j < g.dims[1]; ++j) {
        const float* row = &image.data[g.linearIndex(0, j, k)];
        for (int i = 0; i < g.dims[0]; ++i)
          if (row[i] != background) acc.setValue(openvdb::Coord(i, j, k), row[i]);
      }
    trees[s] = tree;
  });
  auto grid = mergedGrid<openvdb::FloatGrid>(trees, background, gridName, g);
  report.activeVoxels = std::size_t(grid->activeVoxelCount());
  finishAndWrite(openvdb::GridPtrVec{grid}, t0, path, report);
  return report;
}

}  // namespace repose
