#pragma once
// Types shared by the automatic rig's stages (bone_components, bone_fragments, bone_contacts,
// rig_tree, joint_centers; auto_rig runs them in that order): the options, the bones found in a
// label volume, and the fragments given to them.
#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "anatomy_names.h"
#include "image_grid.h"
#include "label_table.h"
#include "point_grid.h"

namespace repose {

struct AutoRigOptions {
  /// Two bones are adjacent when their surfaces are at most this far apart (mm) ...
  double maxGapMm = 6.0;
  /// ... or at most this many voxels (of the largest spacing), whichever is larger: a coarse image
  /// cannot show a joint space narrower than a couple of voxels, and a hinge whose bones taper
  /// toward the joint (as the phantom's knees and elbows do) shows a wider one (30 mm at the tiny
  /// phantom's elbows, 3 of its 10 mm voxels).
  double maxGapVoxels = 3.5;
  /// A bone anatomy expects (a scapula for a humerus, a femur for a tibia, a cervical vertebra for
  /// the skull) is still taken as the parent when it lies beyond the adjacency gap but within
  /// this distance (mm), before any other bone anatomy allows.
  double maxAnatomicGapMm = 25.0;
  /// A label's largest 6-connected component is a bone when it has at least minComponentVoxels
  /// voxels. Another component of the same label is a bone of its own only when the label may
  /// hold several bones (a paired bone named without a side: one per side; a name the rig does
  /// not recognise: any number) and it has at least minBoneFraction of the largest component's
  /// voxels, minBoneVolumeMm3 and minComponentVoxels. Every other component is a fragment.
  int minComponentVoxels = 8;
  double minBoneFraction = 0.25;
  double minBoneVolumeMm3 = 500.0;
  /// A fragment goes to a bone of its own kind it touches or that lies within this distance (mm,
  /// voxel centres) or this many voxels of the largest spacing, whichever is larger; else to a bone
  /// it touches, else to the nearest on its side within that distance; else it is left as soft
  /// tissue (see assignFragments).
  double maxFragmentDistanceMm = 20.0;
  double maxFragmentDistanceVoxels = 3.0;
  /// Fragments within this distance (mm) of the mid-sagittal plane belong to neither side.
  double midlineBandMm = 10.0;
  /// Reject a table whose names contradict where its bones lie (see checkLabelTableFits).
  bool checkTable = true;
  /// Plausible radii (mm) of a ball joint's head (femoral, humeral); fits outside are rejected.
  double minBallRadiusMm = 5.0;
  double maxBallRadiusMm = 40.0;
};

/// One 6-connected component of one bone label.
struct BoneComponent {
  int label = 0;
  std::size_t count = 0;
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();  ///< physical (mm)
  std::array<int, 3> lo{0, 0, 0}, hi{-1, -1, -1};       ///< index bounding box
  bool cut = false;                                     ///< touches the image boundary
  bool halved = false;  ///< one side of a component that crossed the mid-sagittal plane
};

/// A bone: the main component of a label (or of one side of it), and the fragments given to it.
struct RigBone {
  std::string name;      ///< label name, with _left/_right or _N when its label was split
  int sourceLabel = 0;   ///< label value in the input
  int value = 0;         ///< label value in the output volume
  int comp = -1;         ///< its main component (the geometry joints are fitted to)
  BoneName anatomy;      ///< recognised from the label name; side resolved from the position
                         ///< when the name has none (None for midline bones)
  std::size_t voxels = 0;  ///< main component plus the fragments given to it
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();  ///< of the main component
  std::array<int, 3> lo{0, 0, 0}, hi{-1, -1, -1};       ///< index bounding box, fragments included
  bool cut = false;
  std::vector<std::size_t> boundary;  ///< linear indices of its surface voxels (see findBoneBoundaries)
  std::shared_ptr<const PointGrid> surface;  ///< their physical positions, for distance queries
};

/// A component that is not a bone of its own, and where it went.
struct BoneFragment {
  int comp = -1;
  int label = 0;
  std::size_t voxels = 0;
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  int bone = -1;             ///< index into RigBones::bones; -1: left as soft tissue
  std::string why;           ///< "touches it", "nearest femur on its side, 4.0 mm", ...
  double distanceMm = 0;     ///< to the bone it went to (0 when touching), or the search limit
};

struct RigBones {
  std::vector<std::int32_t> componentOf;  ///< per voxel: component id, -1 outside bone labels
  std::vector<BoneComponent> components;
  std::vector<RigBone> bones;
  std::vector<int> boneOfComponent;  ///< bone of each component (main or fragment), -1: soft tissue
  std::vector<BoneFragment> fragments;
  double midX = 0;   ///< x (mm) of the mid-sagittal plane; LPS +x is the patient's left
  LabelTable table;  ///< the input table with the split bones' names (and unassignedValue)
  int unassignedValue = 0;  ///< label of fragments left as soft tissue (0 when there are none)
};

}  // namespace repose
