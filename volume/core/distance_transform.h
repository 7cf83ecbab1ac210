#pragma once
// Exact Euclidean distance transform of a voxel mask on a lattice of any spacing (Felzenszwalb and
// Huttenlocher 2012, "Distance Transforms of Sampled Functions"): one pass per axis of the lower
// envelope of parabolas, linear in the voxels. Used to measure how wide a region is: the distance
// from its deepest voxel to the nearest voxel outside it.
#include <array>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

namespace repose {

/// For each voxel set in `mask` (dims[0] * dims[1] * dims[2] voxels, i fastest), the squared
/// distance (mm^2, spacing in mm along i, j, k) between its centre and the nearest centre of a
/// voxel not set; voxels beyond the box count as not set. 0 for voxels not set. Threaded; the
/// result does not depend on the number of threads. Throws std::invalid_argument when the mask's
/// size does not match dims or a spacing is not positive.
std::vector<double> squaredDistanceToUnset(const std::vector<std::uint8_t>& mask, const std::array<int, 3>& dims,
                                           const Eigen::Vector3d& spacing);

}  // namespace repose
