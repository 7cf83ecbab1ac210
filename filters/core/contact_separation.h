#pragma once
// Parts of the body that touch in the scan (an arm against the torso, a hand against a thigh,
// the thighs) are cut apart before meshing, so that posing them apart leaves no tissue web.
#include <cstddef>
#include <string>
#include <vector>

#include "meshing_grid.h"
#include "skeleton.h"

namespace repose {

struct ContactSeparationOptions {
  /// A background voxel beside the body is in a crease (the slit left where two skins meet) when a
  /// line through it meets the body on both sides within this many voxel steps. Outside a convex
  /// surface no line does (the segment between two body points would hold the voxel), so only
  /// concave places qualify: slits and folds, and the apex of a corner.
  int creaseReach = 2;
  /// ... and it lies at least this deep in such voxels (mm from the nearest background voxel that
  /// is not): the slit between two touching parts runs deep, while a corner (a wrist, the chin,
  /// a groin) is concave along one line of voxels only. 0 = 1.5 x the grid's mean spacing.
  double creaseDepthMm = 0;
  /// Pairs with fewer crease voxels between them are not contacts (noise of the surface).
  std::size_t minCreaseVoxels = 4;
};

struct ContactSeparationReport {
  struct Contact {
    int boneA = -1, boneB = -1;     ///< skeleton joint indices, boneA < boneB
    std::size_t creaseVoxels = 0;   ///< background voxels of the slit between them
    double offsetMm = 0;            ///< shift of their boundary to pass through the crease
    std::size_t voxelsCut = 0;      ///< body voxels removed to part them
    double areaMm2 = 0;             ///< area of the cut (voxels cut x a voxel's mean face area)
  };
  std::vector<Contact> contacts;
  std::size_t voxelsCut = 0;
  /// One line per contact, naming the joints.
  std::string text(const Skeleton& skeleton) const;
};

/// Finds where two body segments (each body voxel belongs to its geodesically nearest bone) meet
/// in a crease and cuts a one-voxel gap between them there:
/// - segments: the two nearest bones of every voxel (nearestBones); where bones A and B compete,
///   the boundary is shifted by the median of dA - dB over the crease between them, so that it
///   passes through the slit where their skins meet rather than halfway between the bones (a
///   thin hand against a thick thigh keeps its own tissue, and the thigh its own);
/// - which part of their boundary is a contact: each boundary voxel takes the kind of the nearest
///   place (along the boundary) where the boundary reaches the outside: a crease between A and B
///   (contact: cut) or any other skin (a joint's own tissue, e.g. over the shoulder: kept). A
///   boundary between a bone and its parent is also kept within the child joint's depth of its
///   centre (the distance from the centre to the outside);
/// - the cut removes, on the larger segment's side, the boundary voxels touching the other side
///   (26-neighbourhood), so the two parts' surfaces separate. Bone voxels are never removed.
/// body and bone are on one grid (binToMeshingGrid); body is changed in place. Deterministic.
ContactSeparationReport separateContacts(MaskVolume& body, const Volume<std::int16_t>& bone,
                                         const Skeleton& skeleton, const ContactSeparationOptions& options = {});

}  // namespace repose
