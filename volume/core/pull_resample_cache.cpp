#include "pull_resample_cache.h"

#include <utility>

#include "rigid_bone_overlay.h"

namespace repose {

void PullResampleCache::setTets(Tets tets) {
  tets_ = std::move(tets);
  boundary_.reset();
  coverage_.reset();
  distance_.reset();
}

void PullResampleCache::setRestNodes(Points nodes) {
  restNodes_ = std::move(nodes);
  coverage_.reset();
  distance_.reset();
}

void PullResampleCache::setRestGrid(const ImageGrid& grid) {
  if (!labels_.grid.sameGridAs(grid)) {
    coverage_.reset();
    distance_.reset();
  }
  if (labels_.grid.dims != grid.dims) labelBoxes_.reset();
  labels_.grid = grid;
  values_.grid = grid;
}

void PullResampleCache::setLabels(std::vector<std::int32_t> labels) {
  labels_.data = std::move(labels);
  values_.data.clear();
  labelBoxes_.reset();
}

void PullResampleCache::setIntensities(std::vector<float> values) {
  values_.data = std::move(values);
  labels_.data.clear();
  labelBoxes_.reset();
}

void PullResampleCache::setFixedBone(std::vector<int> fixedBone) { fixedBone_ = std::move(fixedBone); }

void PullResampleCache::extrapolationInputs(PullResampleOptions& options) {
  if (options.extrapolationDistance == 0) return;
  if (!boundary_) boundary_.reset(new TetBoundary(tetBoundary(tets_)));
  if (!coverage_) {
    coverage_.reset(new MaskVolume(restMeshCoverage(labels_.grid, restNodes_, tets_)));
    distance_.reset(new MaskVolume(restMeshDistance(*coverage_)));
  }
  options.boundary = boundary_.get();
  options.restCoverage = coverage_.get();
  options.restDistance = distance_.get();
}

void PullResampleCache::displacementInto(const Points& posedNodes, const ImageGrid& outGrid,
                                         PullResampleOptions options, float* out, PullResampleReport* report) {
  extrapolationInputs(options);
  displacementPullInto(labels_.grid, restNodes_, posedNodes, tets_, outGrid, options, out, report);
}

void PullResampleCache::intensitiesInto(const Points& posedNodes, const ImageGrid& outGrid,
                                        PullResampleOptions options, float* out, float background,
                                        PullResampleReport* report) {
  extrapolationInputs(options);
  resampleIntensityPullInto(values_, restNodes_, posedNodes, tets_, outGrid, options, out, background, report);
}

RigidBoneCounts PullResampleCache::labelsInto(const Points& posedNodes, const ImageGrid& outGrid,
                                              PullResampleOptions options, std::int32_t* out,
                                              std::int32_t background, bool rigid, PullResampleReport* report) {
  extrapolationInputs(options);
  resampleLabelsPullInto(labels_, restNodes_, posedNodes, tets_, outGrid, options, out, background, report);
  RigidBoneCounts counts;
  if (!rigid) return counts;
  if (!labelBoxes_) labelBoxes_.reset(new std::vector<Eigen::AlignedBox3i>(restLabelBoxes(labels_)));
  const ImageGrid voiGrid = options.outputExtent ? extentGrid(outGrid, *options.outputExtent) : outGrid;
  const auto bones = rigidBonesFromMesh(labels_, restNodes_, posedNodes, fixedBone_);
  counts.changedVoxels = overlayRigidBones(out, voiGrid, labels_, bones, labelBoxes_.get(), &counts.contestedVoxels);
  return counts;
}

}  // namespace repose
