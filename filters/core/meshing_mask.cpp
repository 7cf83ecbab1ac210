#include "meshing_mask.h"

#include <algorithm>
#include <stdexcept>

namespace repose {

namespace {

std::size_t countSet(const MaskVolume& m) { return std::size_t(std::count(m.data.begin(), m.data.end(), 1)); }

}  // namespace

MeshingMask meshingMask(const LabelVolume& labels, const IntensityVolume* image, const std::vector<int>& boneOfLabel,
                        const Skeleton& skeleton, const MeshingMaskOptions& options) {
  MeshingMask out;
  BodyMaskOptions bodyOptions = options.body;
  bodyOptions.keepLargestComponent = false;  // every piece that can be posed is kept, below
  if (!image && options.skinLabels.empty() && bodyOptions.closingMm == 0 && labelsLeaveGaps(labels))
    bodyOptions.closingMm = 2 * labels.grid.spacing.maxCoeff();
  out.closedMm = bodyOptions.closingMm;
  out.body = bodyMask(labels, image, bodyOptions);
  out.components = keepPosableComponents(out.body, labels, boneOfLabel);
  if (out.components.kept == 0)
    throw std::invalid_argument("no piece of the body holds a bone of the skeleton: check the skeleton's labels");
  out.bodyVoxels = countSet(out.body);

  if (!options.skinLabels.empty()) {
    out.peeled = out.body;
    for (std::size_t v = 0; v < labels.data.size(); ++v)
      if (out.peeled.data[v] &&
          std::find(options.skinLabels.begin(), options.skinLabels.end(), labels.data[v]) != options.skinLabels.end()) {
        out.peeled.data[v] = 0;
        ++out.skinVoxelsRemoved;
      }
  } else {
    out.peeled = options.peelOuterLayer ? peelOuterLayer(out.body) : out.body;
  }
  keepBoneVoxels(out.peeled, labels, boneOfLabel);
  out.peeledVoxels = countSet(out.peeled);
  if (out.peeledVoxels == 0)
    throw std::invalid_argument("the body is at most two voxels thick: nothing is left after taking off its skin");

  if (options.meshSpacingMm > 0 || !(options.maxTets > 0)) {
    out.spacing.spacingMm = std::max(options.meshSpacingMm, labels.grid.spacing.minCoeff());
  } else {
    out.spacing = chooseMeshSpacing(out.peeled, labels, boneOfLabel, options.maxTets, options.tetsPerPoint);
  }
  out.mesh = binToMeshingGrid(out.peeled, labels, boneOfLabel, meshingGrid(labels.grid, out.spacing.spacingMm));
  if (options.separateContacts) out.contacts = separateContacts(out.mesh.body, out.mesh.bone, skeleton, options.contact);
  out.meshVoxels = countSet(out.mesh.body);
  return out;
}

}  // namespace repose
