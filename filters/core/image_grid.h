#pragma once
// A regular 3-D image lattice in physical (LPS, millimetre) space, and volumes on it.
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

namespace repose {

/// Geometry of a regular image: x = origin + direction * diag(spacing) * index.
struct ImageGrid {
  std::array<int, 3> dims{0, 0, 0};          ///< voxels along i, j, k
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  ///< physical position of voxel (0,0,0)
  Eigen::Vector3d spacing = Eigen::Vector3d::Ones(); ///< mm between voxel centres
  Eigen::Matrix3d direction = Eigen::Matrix3d::Identity(); ///< columns: physical axes of i, j, k

  std::size_t voxelCount() const { return std::size_t(dims[0]) * dims[1] * dims[2]; }
  std::size_t linearIndex(int i, int j, int k) const {
    return (std::size_t(k) * dims[1] + j) * dims[0] + i;
  }
  bool contains(int i, int j, int k) const {
    return i >= 0 && j >= 0 && k >= 0 && i < dims[0] && j < dims[1] && k < dims[2];
  }
  /// index (possibly fractional) -> physical point
  Eigen::Vector3d indexToPhysical(const Eigen::Vector3d& ijk) const {
    return origin + direction * spacing.cwiseProduct(ijk);
  }
  /// physical point -> continuous index
  Eigen::Vector3d physicalToIndex(const Eigen::Vector3d& x) const {
    return (direction.transpose() * (x - origin)).cwiseQuotient(spacing);
  }
  /// Same lattice (dims, origin, spacing, direction) within a relative tolerance.
  bool sameGridAs(const ImageGrid& o, double tol = 1e-6) const;
};

/// A scalar volume, voxel (i,j,k) at data[grid.linearIndex(i,j,k)] (i fastest, as in VTK and ITK).
template <class T>
struct Volume {
  ImageGrid grid;
  std::vector<T> data;
  T& at(int i, int j, int k) { return data[grid.linearIndex(i, j, k)]; }
  const T& at(int i, int j, int k) const { return data[grid.linearIndex(i, j, k)]; }
};
using LabelVolume = Volume<std::int32_t>;
using IntensityVolume = Volume<float>;
using MaskVolume = Volume<std::uint8_t>;

}  // namespace repose
