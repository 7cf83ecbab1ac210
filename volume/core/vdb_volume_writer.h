#pragma once
// Posed volumes as sparse OpenVDB grids (.vdb), which film and game tools (Houdini, Blender) read
// directly. Only voxels that differ from the background are stored. OpenVDB stays behind this header.
#include <cstddef>
#include <cstdint>
#include <string>

#include "image_grid.h"

namespace repose {

struct VdbWriteOptions {
  /// Also one float fog-volume grid "label_<value>" per non-zero label (1 inside, background 0).
  bool labelFogGrids = true;
};

struct VdbWriteReport {
  std::size_t grids = 0;          ///< grids written
  std::size_t activeVoxels = 0;   ///< active voxels of the main grid ("labels" or the intensity grid)
  std::size_t memoryBytes = 0;    ///< in-memory size of all grids (OpenVDB's memUsage)
  double buildSeconds = 0;        ///< dense -> sparse conversion
  double writeSeconds = 0;        ///< file output
};

/// Writes `labels` to `path` as an Int32 grid "labels": background 0, every voxel with a non-zero
/// label active and holding it. Voxel (i,j,k) of the volume is voxel (i,j,k) of the grid, and the
/// grid's transform is the volume's index-to-physical map (origin, spacing and direction as one
/// affine map), so the grid lies in the same physical millimetres (LPS) as the NIfTI output. The file
/// is written under a temporary name and renamed. Throws std::invalid_argument when the data does not
/// match the grid, std::runtime_error when the file cannot be written.
VdbWriteReport writeLabelsVdb(const LabelVolume& labels, const std::string& path, const VdbWriteOptions& options = {});

/// Writes `image` to `path` as a float grid named `gridName` (e.g. "ct"): background `background`,
/// voxels whose value differs from it active. Same transform and error handling as writeLabelsVdb.
VdbWriteReport writeIntensityVdb(const IntensityVolume& image, float background, const std::string& path,
                                 const std::string& gridName = "ct");

}  // namespace repose
