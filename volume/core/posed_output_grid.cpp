#include "resample_pull.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>

namespace repose {
namespace {

// Inclusive index box on the rest lattice.
struct IndexBox {
  Eigen::Vector3d lo, hi;
  double voxels() const { return (hi - lo + Eigen::Vector3d::Ones()).prod(); }
};

std::string voxelCount(double voxels) {
  char text[32];
  if (voxels >= 1e5)
    std::snprintf(text, sizeof(text), voxels >= 1e7 ? "%.0f M" : "%.1f M", voxels / 1e6);
  else
    std::snprintf(text, sizeof(text), "%.0f", voxels);
  return text;
}

[[noreturn]] void tooLarge(const ImageGrid& rest, const IndexBox& box, const IndexBox& nodes, double maxVoxels) {
  const Eigen::Vector3d dims = box.hi - box.lo + Eigen::Vector3d::Ones();
  const Eigen::Vector3d span = (nodes.hi - nodes.lo).cwiseProduct(rest.spacing);
  char text[400];
  std::snprintf(text, sizeof(text),
                "the posed volume would have %s voxels (%.0f x %.0f x %.0f of %.3g mm), more than the limit of "
                "%s voxels: the posed body spans %.0f x %.0f x %.0f mm",
                voxelCount(box.voxels()).c_str(), dims[0], dims[1], dims[2], rest.spacing.minCoeff(),
                voxelCount(maxVoxels).c_str(), span[0], span[1], span[2]);
  throw std::invalid_argument(text);
}

}  // namespace

ImageGrid posedOutputGrid(const ImageGrid& rest, const Points& posedNodes, const PosedGridOptions& options) {
  if (rest.voxelCount() == 0) throw std::invalid_argument("posed output grid: empty rest grid");
  const Eigen::Vector3d restLo(0, 0, 0);
  const Eigen::Vector3d restHi(rest.dims[0] - 1, rest.dims[1] - 1, rest.dims[2] - 1);
  // The posed nodes' index box (the rest box when there are none).
  IndexBox nodes{Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()),
                 Eigen::Vector3d::Constant(-std::numeric_limits<double>::infinity())};
  for (Eigen::Index i = 0; i < posedNodes.rows(); ++i) {
    const Eigen::Vector3d x = posedNodes.row(i).transpose();
    if (!x.allFinite()) throw std::invalid_argument("posed output grid: non-finite posed node");
    const Eigen::Vector3d ijk = rest.physicalToIndex(x);
    nodes.lo = nodes.lo.cwiseMin(ijk);
    nodes.hi = nodes.hi.cwiseMax(ijk);
  }
  if (posedNodes.rows() == 0) nodes = {restLo, restHi};
  auto padded = [&](const IndexBox& b, int padding) {
    IndexBox out;
    for (int a = 0; a < 3; ++a) {
      out.lo[a] = std::floor(b.lo[a]) - padding;
      out.hi[a] = std::ceil(b.hi[a]) + padding;
    }
    return out;
  };
  const int bodyPadding = options.bodyPaddingVoxels < 0 ? options.paddingVoxels : options.bodyPaddingVoxels;
  const IndexBox body = padded(nodes, bodyPadding);
  IndexBox box = padded({nodes.lo.cwiseMin(restLo), nodes.hi.cwiseMax(restHi)}, options.paddingVoxels);
  const double inPlace = std::max(padded({restLo, restHi}, options.paddingVoxels).voxels(), body.voxels());
  if (!(box.voxels() <= options.restExtentFactor * inPlace)) box = body;
  if (options.maxVoxels > 0 && box.voxels() > options.maxVoxels) tooLarge(rest, box, nodes, options.maxVoxels);
  ImageGrid out = rest;
  for (int a = 0; a < 3; ++a) {
    if (box.hi[a] - box.lo[a] + 1 > double(std::numeric_limits<int>::max() / 4))
      throw std::invalid_argument("posed output grid: posed body is implausibly large");
    out.dims[a] = int(box.hi[a] - box.lo[a]) + 1;
  }
  out.origin = rest.indexToPhysical(box.lo);
  return out;
}

ImageGrid posedOutputGrid(const ImageGrid& rest, const Points& posedNodes, int paddingVoxels) {
  PosedGridOptions options;
  options.paddingVoxels = paddingVoxels;
  return posedOutputGrid(rest, posedNodes, options);
}

int extrapolationReachVoxels(const ImageGrid& rest, double extrapolationDistance) {
  // resampleLabelsPull's layers: ceil(distance / finest spacing) + 2 (at most 64 + 2).
  const double distance = extrapolationDistance < 0 ? 2.0 * rest.spacing.maxCoeff() : extrapolationDistance;
  return distance > 0 ? int(std::min(64.0, std::ceil(distance / rest.spacing.minCoeff()))) + 2 : 0;
}

}  // namespace repose
