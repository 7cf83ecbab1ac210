#pragma once
// The names of the data arrays the stages pass on, in one place: the filters write them, the next
// stages, the case files and the apps read them by these names (ParaView shows them as they are).

namespace repose::arrays {

// Tet mesh point data (vtkReposeBodyMesher, vtkReposeBoneWeights; mesh.vtu of a case).
inline constexpr char kFixedBone[] = "FixedBone";  ///< int: bone (joint index) a node is fixed to, -1 free
inline constexpr char kWeights[] = "Weights";      ///< float, K per node: bone weights, largest first
inline constexpr char kBoneIds[] = "BoneIds";      ///< K per node: the bones of those weights

// Cell data of tet meshes and surfaces.
inline constexpr char kLabel[] = "Label";  ///< int: label value of a tet or a surface triangle (-1: skin)

// Surface point data (vtkReposeSurfaceBinding; surfaces.vtp of a case).
inline constexpr char kBoundTet[] = "BoundTet";          ///< int: the rest tet a vertex is bound to
inline constexpr char kBoundWeights[] = "BoundWeights";  ///< float, 4: its barycentric coordinates

// Image scalars.
inline constexpr char kLabels[] = "Labels";              ///< int label volumes (phantom, voxelizer, rig)
inline constexpr char kImageScalars[] = "ImageScalars";  ///< images read from files, posed images
inline constexpr char kDisplacement[] = "Displacement";  ///< float, 3: posed voxel -> rest point, in mm

}  // namespace repose::arrays
