#pragma once
// Small volumes for the tests of the voxel-grid stages: a grid with a flipped direction and an offset
// origin (so that index and physical space differ), volumes filled with one value, voxel centres.
#include <Eigen/Core>

#include "image_grid.h"

namespace repose::testing {

inline ImageGrid makeGrid(int nx, int ny, int nz, Eigen::Vector3d spacing = {1, 1, 1}) {
  ImageGrid g;
  g.dims = {nx, ny, nz};
  g.origin = {10, -4, 7};
  g.spacing = spacing;
  g.direction << -1, 0, 0, 0, -1, 0, 0, 0, 1;
  return g;
}

template <class T>
Volume<T> filled(const ImageGrid& g, T value) {
  Volume<T> v;
  v.grid = g;
  v.data.assign(g.voxelCount(), value);
  return v;
}

inline Eigen::Vector3d centre(const ImageGrid& g, int i, int j, int k) {
  return g.indexToPhysical(Eigen::Vector3d(i, j, k));
}

}  // namespace repose::testing
