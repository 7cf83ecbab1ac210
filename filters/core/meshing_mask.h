#pragma once
// What the mesh is made from: the body of a label volume (and CT) on the meshing grid, its outer
// skin layer taken off and touching parts cut apart.
#include <cstddef>
#include <string>
#include <vector>

#include "body_mask.h"
#include "contact_separation.h"
#include "mesh_budget.h"
#include "meshing_grid.h"
#include "skeleton.h"

namespace repose {

struct MeshingMaskOptions {
  BodyMaskOptions body;
  double meshSpacingMm = 0;   ///< meshing grid spacing; 0 = chosen from maxTets (or the scan's grid)
  double maxTets = 0;         ///< tet budget when meshSpacingMm is 0; 0 = the scan's grid, no budget
  double tetsPerPoint = kTetsPerPoint;  ///< the budget's prediction (see predictTets)
  /// Labels of the skin (e.g. a "skin" entry of the label table): removed before meshing, as the
  /// paper does, so that skins touching in the scan part. Empty: the outer voxel layer is peeled.
  std::vector<int> skinLabels;
  bool peelOuterLayer = true;  ///< without skin labels: take off the outer voxel layer
  bool separateContacts = true;
  ContactSeparationOptions contact;
};

struct MeshingMask {
  MaskVolume body;     ///< the scan's grid: labels (and CT) with holes filled, before peeling
  MaskVolume peeled;   ///< the scan's grid: skin or outer layer removed, bones kept whole
  MeshingVolumes mesh; ///< the meshing grid: what the surface is extracted from
  MeshSpacingChoice spacing;  ///< the meshing spacing (chosen from the budget, or as given)
  std::size_t bodyVoxels = 0, peeledVoxels = 0, meshVoxels = 0, skinVoxelsRemoved = 0;
  double closedMm = 0;                  ///< closing radius of a body the labels alone make (0: none)
  PosableComponentsReport components;   ///< pieces of the body kept, bridged, dropped
  ContactSeparationReport contacts;
};

/// body mask (closed where the labels alone leave gaps: no CT, no skin label, no label holding half
/// the body; every piece with bone kept, labelled pieces without bone bridged to them) -> skin
/// removed (or outer layer peeled), bone voxels kept -> meshing spacing (given, or
/// chosen from the tet budget) -> binned to the meshing grid -> contacts separated. boneOfLabel
/// maps label -> skeleton joint or -1.
/// Throws std::invalid_argument on inconsistent input or when nothing is left to mesh.
MeshingMask meshingMask(const LabelVolume& labels, const IntensityVolume* image, const std::vector<int>& boneOfLabel,
                        const Skeleton& skeleton, const MeshingMaskOptions& options);

}  // namespace repose
