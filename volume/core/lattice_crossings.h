#pragma once
// Where a triangle soup crosses the lines of a voxel lattice: the rows of voxel centres along one
// axis, met by each triangle at most once. The test is exact and consistent on shared edges and
// vertices (a symbolic perturbation of the row), so a row through a closed surface's edge or vertex
// crosses it exactly once: counting crossings along a row gives the winding number of a closed
// surface (winding_inside.h), and a lattice segment no crossing falls on joins two voxels on the
// same side of every triangle (enclosed_hollows.h).
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

namespace repose {

/// A box of voxel indices of a grid, i fastest.
struct IndexBox {
  std::array<int, 3> min{0, 0, 0};   ///< first voxel index of the box
  std::array<int, 3> dims{0, 0, 0};  ///< voxels along i, j, k
  std::size_t count() const { return std::size_t(dims[0]) * std::size_t(dims[1]) * std::size_t(dims[2]); }
  /// Box-local linear index of box-local (i, j, k).
  std::size_t index(int i, int j, int k) const {
    return (std::size_t(k) * std::size_t(dims[1]) + std::size_t(j)) * std::size_t(dims[0]) + std::size_t(i);
  }
};

/// One crossing of a lattice row with a triangle.
struct RowCrossing {
  std::uint32_t row;  ///< row over the two other axes, taken cyclically: axis + 1 fastest
  int last;           ///< last box-local voxel before the crossing along the row (the row's last voxel
                      ///< when the crossing lies beyond it)
  int sign;           ///< +1 when the triangle's normal (b-a)x(c-a) points along +axis, else -1
};

/// Appends the crossings of triangle (a, b, c), in continuous grid indices, with the rows of `box`
/// along `axis` (0, 1, 2: i, j, k) that it meets at or after their first voxel.
void crossRows(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c, int axis,
               const IndexBox& box, std::vector<RowCrossing>& out);

}  // namespace repose
