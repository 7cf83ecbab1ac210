#include "resample_pull.h"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace repose {

ImageGrid posedOutputGrid(const ImageGrid& rest, const Points& posedNodes, int paddingVoxels) {
  if (rest.voxelCount() == 0) throw std::invalid_argument("posed output grid: empty rest grid");
  Eigen::Vector3d lo(0, 0, 0);
  Eigen::Vector3d hi(rest.dims[0] - 1, rest.dims[1] - 1, rest.dims[2] - 1);
  for (Eigen::Index i = 0; i < posedNodes.rows(); ++i) {
    const Eigen::Vector3d x = posedNodes.row(i).transpose();
    if (!x.allFinite()) throw std::invalid_argument("posed output grid: non-finite posed node");
    const Eigen::Vector3d ijk = rest.physicalToIndex(x);
    lo = lo.cwiseMin(ijk);
    hi = hi.cwiseMax(ijk);
  }
  ImageGrid out = rest;
  Eigen::Vector3d first;
  for (int a = 0; a < 3; ++a) {
    const double f = std::floor(lo[a]) - paddingVoxels;
    const double l = std::ceil(hi[a]) + paddingVoxels;
    if (l - f + 1 > double(std::numeric_limits<int>::max() / 4))
      throw std::invalid_argument("posed output grid: posed body is implausibly large");
    first[a] = f;
    out.dims[a] = int(l - f) + 1;
  }
  out.origin = rest.indexToPhysical(first);
  return out;
}

}  // namespace repose
