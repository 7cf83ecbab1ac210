#pragma once
// Surface meshes -> voxels. A voxel is inside a surface when the surface's generalized winding
// number at its centre is at least 1/2 (winding_number.h, winding_inside.h), which takes surfaces
// as they come: holes are spanned, overlapping closed pieces make their union, inward pieces inside
// others are cavities. Surfaces of skin, bones and other tissues are then combined into one label
// volume, with a report of what was repaired.
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "image_grid.h"
#include "label_table.h"
#include "enclosed_hollows.h"
#include "mesh_topology.h"
#include "winding_inside.h"

namespace repose {

struct MeshVoxelizeOptions {
  /// Near each hole the winding number is evaluated within this many times the hole's radius of
  /// its middle (WindingInsideOptions::holeReach, at least 2); larger only costs time.
  double holeReach = 2.0;
  /// Also find the hollows the surface encloses, filling the thin ones as `hollows` says
  /// (enclosed_hollows.h); voxelizeLabels does for bones.
  bool findHollows = false;
  HollowOptions hollows;
};

/// What putting the orientation right changed (see voxelizeMesh).
struct OrientationRepairs {
  std::size_t trianglesTurned = 0;  ///< turned to agree with their neighbours (mixed windings)
  bool turnedOutward = false;       ///< the whole surface faced inward and was turned
  std::size_t cavities = 0;         ///< pieces facing inward inside other pieces: carved out
  std::size_t invertedPieces = 0;   ///< pieces facing inward but not inside others: turned outward
};

/// Voxels of `grid` whose centres lie inside one surface, stored over the index box of the surface
/// clipped to the grid (nothing outside that box is inside), with the counts of WindingInside.
struct MeshVoxelization : WindingInside {
  OrientationRepairs repairs;
  MeshTopology topology;
  /// With MeshVoxelizeOptions::findHollows: the hollows, whose thin ones `inside` then holds when
  /// filled (insideVoxels counts the surface's own inside only).
  EnclosedHollows hollows;
  /// Grid voxel (i,j,k) inside?
  bool at(int i, int j, int k) const {
    i -= boxMin[0], j -= boxMin[1], k -= boxMin[2];
    if (i < 0 || j < 0 || k < 0 || i >= boxDims[0] || j >= boxDims[1] || k >= boxDims[2]) return false;
    return inside[(std::size_t(k) * boxDims[1] + j) * boxDims[0] + i] != 0;
  }
};

/// Voxelizes one triangle soup (V #V by 3 physical LPS mm, F #F by 3) on `grid` (any origin,
/// spacing, direction): a voxel is inside when the soup's winding number at its centre is at least
/// 1/2. Orientation is put right first: triangles are turned to agree with their neighbours
/// (consistentlyOriented); then, piece by piece (meshPieces), a soup whose largest piece faces
/// inward is turned, and a piece facing against the largest one is a cavity when it lies inside
/// the others (a skull's inner table, a hollow bone's inner wall: carved out) and is turned outward
/// otherwise.
/// Holes are spanned (WindingInside::meanInsideWinding says how well). With options.findHollows,
/// the hollows it encloses are found and the thin ones filled (fillEnclosedHollows). Does not
/// judge: see voxelizeLabels.
/// Threaded; the result does not depend on the number of threads.
/// Throws std::invalid_argument on an empty mesh, a bad index, a non-finite vertex or an empty grid.
MeshVoxelization voxelizeMesh(const MeshVertices& V, const MeshTriangles& F, const ImageGrid& grid,
                              const MeshVoxelizeOptions& options = {});

/// Axis-aligned grid (identity direction, LPS) with cubic voxels of voxelMm fitting the points' bounds
/// plus padVoxels voxels each side. Throws std::invalid_argument when it would exceed maxVoxels
/// (the message gives the count and a voxel size that fits) or the input is empty or not finite.
ImageGrid gridFittingPoints(const MeshVertices& V, double voxelMm, double padVoxels, std::size_t maxVoxels);

enum class VoxelizeRole { Skin, Bone, Tissue };

struct VoxelizePart {
  std::string name;    ///< label name (label table), e.g. femur_left
  std::string source;  ///< file it came from, for messages ("" -> name)
  VoxelizeRole role = VoxelizeRole::Bone;
  MeshVertices V;      ///< #V by 3, physical LPS mm
  MeshTriangles F;     ///< #F by 3
};

struct LabelVoxelizeOptions {
  double voxelMm = 1.0;        ///< voxel size of the grid fitted to the skin (when no grid is given)
  double padVoxels = 2.0;      ///< background voxels around the skin's bounds
  std::size_t maxVoxels = std::size_t(512) << 20;
  MeshVoxelizeOptions mesh;
  /// Bones are solid: the hollows a bone's surface encloses (a cortical shell's marrow) are bone up
  /// to this radius (enclosed_hollows.h); wider ones (a cranial cavity) stay cavities.
  double maxMarrowRadiusMm = kMaxMarrowRadiusMm;
  /// Keep bones as their surfaces enclose them (shells stay shells); their hollows are still reported.
  bool hollowBones = false;
};

struct VoxelizedPart {
  std::string name, source;
  VoxelizeRole role = VoxelizeRole::Bone;
  int label = 0;
  std::size_t voxels = 0;          ///< voxels inside the surface (w >= 1/2): a hollow bone's shell
  std::size_t solidVoxels = 0;     ///< bones: voxels plus those of its thin hollows; else voxels
  std::size_t labelledVoxels = 0;  ///< voxels carrying its label in the result (after priorities)
  double voxelVolume = 0;          ///< voxels x voxel volume (mm^3): the shell's volume
  double solidVolume = 0;          ///< solidVoxels x voxel volume (mm^3)
  EnclosedHollows hollows;         ///< bones: the hollows it encloses, filled unless hollowBones
  MeshTopology topology;
  double outsideSkinFraction = 0;  ///< bones and tissues: fraction of their voxels outside the skin
  double overlapVolume = 0;        ///< mm^3 inside two of its pieces or more
  double meanInsideWinding = 0;    ///< see WindingInside
  bool cutByGrid = false;
  OrientationRepairs repairs;
  double seconds = 0;              ///< voxelizing it (wall time)
};

struct LabelVoxelization {
  LabelVolume labels;  ///< 0 background, 1 skin interior, bones and tissues numbered in input order
  LabelTable table;    ///< 0 background, skin (soft), bones (bone), tissues (soft)
  std::vector<VoxelizedPart> parts;
  std::vector<std::string> warnings;  ///< one line each, naming the file
  double seconds = 0;
  /// Summary, one line a part, then the warnings.
  std::string text() const;
};

/// Below this mean winding number inside (1 for a closed surface, 0.5 for an open sheet) a surface
/// is too open to have an inside.
constexpr double kMinInsideWinding = 0.75;

/// One label volume from one skin and any number of bones and tissues: the skin's interior gets the
/// skin's label (soft tissue), each bone (solid, its thin hollows filled unless options.hollowBones)
/// and tissue its own; where they overlap bones win over
/// tissues over skin (between two bones, or two tissues, the first given). The grid is `grid` when
/// its dims are non-zero, else gridFittingPoints(skin, options). Holes, overlapping pieces, cavities
/// and inward pieces are repaired and reported in text(). A surface too open to have an inside (its
/// inside voxels' mean winding number below kMinInsideWinding: an open sheet, a bowl) or that
/// encloses no voxel centre is an error; a bone or tissue partly outside the skin (kept in the body
/// anyway), overlapping bones and a surface cut by the grid are warnings.
/// Throws std::invalid_argument "SOURCE: problem" on bad input, no or several skins, duplicate
/// names, or a grid above options.maxVoxels.
LabelVoxelization voxelizeLabels(const std::vector<VoxelizePart>& parts, const ImageGrid& grid,
                                 const LabelVoxelizeOptions& options = {});

}  // namespace repose
