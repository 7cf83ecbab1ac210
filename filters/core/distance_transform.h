#pragma once
// Exact Euclidean distance transform on a voxel grid with anisotropic spacing.
#include <cstdint>
#include <vector>

#include "image_grid.h"

namespace repose {

/// Distance (mm, between voxel centres, spacing per axis; the direction matrix is a rotation and
/// does not change distances) from every voxel of `features.grid` to the nearest voxel whose
/// feature value is non-zero. Voxels with no feature in the image get +infinity.
/// Exact (Felzenszwalb & Huttenlocher's separable lower envelope of parabolas, one pass per axis),
/// O(#voxels), threaded over image lines; the result does not depend on the thread count.
/// Returns #voxels floats, i fastest. Throws std::invalid_argument if data and grid disagree.
std::vector<float> distanceToFeatures(const MaskVolume& features);

}  // namespace repose
