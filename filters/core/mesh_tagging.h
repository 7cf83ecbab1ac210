#pragma once
// Links the tet mesh to the label volume: bone seeds for meshing, node-to-bone and tet labels.
#include <vector>

#include "image_grid.h"
#include "tet_mesh.h"

namespace repose {

/// Points to insert into the mesh so every bone is resolved: centres of bone voxels on each bone's
/// boundary, subsampled on a lattice of `surfaceStep` voxels, each with seeds 0.45 voxel towards its
/// non-bone faces (fixed to the bone: they put the bone boundary into the mesh), and of interior bone
/// voxels every `interiorStep` voxels. Only voxels inside `mask` are used. boneOfLabel maps label -> bone or -1.
Points boneSeedPoints(const LabelVolume& labels, const std::vector<int>& boneOfLabel, const MaskVolume& mask,
                      int surfaceStep = 2, int interiorStep = 4);

/// Fills mesh.fixedBone (bone of the nearest voxel's label at each node, -1 when not bone) and
/// mesh.tetLabel (label of the nearest voxel at each tet's centroid).
void tagMesh(TetMesh& mesh, const LabelVolume& labels, const std::vector<int>& boneOfLabel);

struct ContactReport {
  int edgesBetweenBones = 0;  ///< edges that joined nodes fixed to two different bones
  int nodesFreed = 0;         ///< fixed nodes made free so that no such edge is left
  int bonesKept = 0;          ///< bones whose nodes all touched another bone: left fixed (edges remain)
};

/// Frees every fixed node that shares a tet edge with a node fixed to another bone. Such an edge
/// spans a joint: with both ends rigid, bending the joint shears or inverts the tets around it and
/// nothing (skinning weights, FEM) can repair them. After this no edge joins two bones' fixed nodes,
/// so every tet between two bones has a free node. A bone that would lose all its fixed nodes keeps
/// them (reported in bonesKept). Call after tagMesh.
ContactReport freeBoneContacts(TetMesh& mesh);

struct ComponentReport {
  int componentsKept = 0, componentsDropped = 0;
  int nodesDropped = 0, tetsDropped = 0;
};

/// Keeps the connected components of the tagged mesh (tets connected through shared nodes) that hold
/// at least one fixed (bone) node: a free-floating piece cannot be posed. Renumbers the nodes and
/// keeps fixedBone / tetLabel in step. Throws std::invalid_argument when no component holds a bone node.
ComponentReport keepBoneComponents(TetMesh& mesh);

}  // namespace repose
