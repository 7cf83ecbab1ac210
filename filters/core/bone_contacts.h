#pragma once
// Where bones come close: each bone's surface voxels, and for every pair of bones the surface
// voxels of one within a distance of the other (the articular patches joints are fitted to).
#include <limits>
#include <utility>
#include <vector>

#include "rig_bones.h"

namespace repose {

/// Surface voxels of every bone (a 6-neighbour outside it; the bone: its main component and the
/// fragments RigBones::boneOfComponent gives it): RigBone::boundary and RigBone::surface.
void findBoneBoundaries(const ImageGrid& grid, RigBones& bones);

/// Surface voxels of bone `other` whose centres lie within the threshold of bone `self`'s surface.
struct BoneContact {
  int other = -1;
  float dmin = std::numeric_limits<float>::max();  ///< closest voxel-centre distance (mm)
  std::vector<std::pair<std::size_t, float>> near;  ///< (linear index of other's voxel, distance)
};

/// contacts[a]: the bones whose surface voxels lie within `threshold` mm (voxel centres) of bone
/// a's surface, with those voxels. Each bone's distance field is stamped into its padded bounding
/// box only, so the cost is the surface voxels times the voxels of a ball of that radius.
std::vector<std::vector<BoneContact>> findBoneContacts(const ImageGrid& grid, const RigBones& bones, double threshold);

/// The contact of bone `self` with `other` (other's voxels near self), or nullptr.
const BoneContact* findContact(const std::vector<std::vector<BoneContact>>& contacts, int self, int other);

}  // namespace repose
