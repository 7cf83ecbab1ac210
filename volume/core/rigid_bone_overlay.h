#pragma once
// Bones are rigid: after the pull through the tets, each bone's voxels are placed exactly where its
// rigid motion takes them. The tet field is smooth, so at a joint whose bones touch (a femoral head
// in its socket) the tets between the two bones shear and would smear one bone into the other.
#include <Eigen/Geometry>
#include <vector>

#include "image_grid.h"
#include "label_boxes.h"
#include "tet_mesh.h"

namespace repose {

struct RigidBone {
  Eigen::Isometry3d transform = Eigen::Isometry3d::Identity();  ///< rest -> posed
  std::vector<std::int32_t> labels;                              ///< rest label values of the bone
};

/// Each bone's rigid transform, fitted (Kabsch) to its fixed nodes' rest and posed positions (exact
/// for skinned fixed nodes), and its labels: the rest labels at those nodes. Bones with fewer than 3
/// non-collinear fixed nodes are left out. restNodes/posedNodes #V by 3, fixedBone #V (-1 free).
std::vector<RigidBone> rigidBonesFromMesh(const LabelVolume& rest, const Points& restNodes,
                                          const Points& posedNodes, const std::vector<int>& fixedBone);

/// For every bone and every voxel of `posed` near the bone's moved position, reads the rest label at
/// the rigidly back-mapped centre: a label of that bone is written; a voxel the pull had given that
/// bone's label but which lies outside the rigid bone gets the rest tissue there (when it is not
/// another bone). Threaded over slices. Returns the number of voxels changed.
std::size_t overlayRigidBones(LabelVolume& posed, const LabelVolume& rest, const std::vector<RigidBone>& bones);
/// Same on caller memory: posedData holds posedGrid.voxelCount() labels, i fastest. posedGrid may be a
/// block of the full posed grid (extentGrid), since each voxel is decided on its own.
std::size_t overlayRigidBones(std::int32_t* posedData, const ImageGrid& posedGrid, const LabelVolume& rest,
                              const std::vector<RigidBone>& bones);

/// labelBoxes(rest) (label_boxes.h): it depends on the rest labels only, so compute it once and pass
/// it to overlayRigidBones for every pose.
std::vector<Eigen::AlignedBox3i> restLabelBoxes(const LabelVolume& rest);
/// Same as above with the rest bounding boxes from restLabelBoxes(rest) (null or empty: scanned here).
/// contestedVoxels (optional) receives the number of posed voxels that two bones' rigid motions both
/// claim (bones colliding: a joint bent past its range, or parts welded at rest); the bone later in
/// `bones` keeps such a voxel.
std::size_t overlayRigidBones(std::int32_t* posedData, const ImageGrid& posedGrid, const LabelVolume& rest,
                              const std::vector<RigidBone>& bones,
                              const std::vector<Eigen::AlignedBox3i>* labelBoxes,
                              std::size_t* contestedVoxels = nullptr);

}  // namespace repose
