#pragma once
// Closed surface meshes -> voxels: each surface becomes a narrow-band signed distance field with
// OpenVDB (meshToVolume), whose sign says which voxel centres are inside; surfaces of skin, bones and
// other tissues are then combined into one label volume.
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "image_grid.h"
#include "label_table.h"
#include "mesh_topology.h"

namespace repose {

struct MeshVoxelizeOptions {
  /// Narrow band each side of the surface (voxels). OpenVDB decides inside/outside by flood-filling
  /// the outside sign through this band, so holes narrower than about the band are bridged and
  /// self-intersections and inconsistent orientation do not matter; wider holes let the outside in.
  double bandVoxels = 3.0;
};

/// Voxels of `grid` whose centres lie inside one surface, stored over the index box of the surface
/// clipped to the grid (nothing outside that box is inside).
struct MeshVoxelization {
  std::array<int, 3> boxMin{0, 0, 0};   ///< first voxel index of the box
  std::array<int, 3> boxDims{0, 0, 0};  ///< voxels along i, j, k (0 when the surface misses the grid)
  std::vector<std::uint8_t> inside;     ///< boxDims product, i fastest; 1 = inside
  std::size_t insideVoxels = 0;
  bool cutByGrid = false;               ///< the surface reaches beyond the grid
  std::size_t cavities = 0;             ///< pieces facing inward inside other pieces: carved out
  std::size_t invertedPieces = 0;       ///< pieces facing inward but not inside others: kept as solids
  MeshTopology topology;
  /// Grid voxel (i,j,k) inside?
  bool at(int i, int j, int k) const {
    i -= boxMin[0], j -= boxMin[1], k -= boxMin[2];
    if (i < 0 || j < 0 || k < 0 || i >= boxDims[0] || j >= boxDims[1] || k >= boxDims[2]) return false;
    return inside[(std::size_t(k) * boxDims[1] + j) * boxDims[0] + i] != 0;
  }
};

/// Voxelizes one triangle soup (V #V by 3 physical LPS mm, F #F by 3) on `grid` (any origin,
/// spacing, direction): the surface is taken into the grid's continuous index space, converted to a
/// level set there (distances in voxel units), and a voxel is inside when the level set is negative
/// at its centre. Threaded over slices. Does not judge closedness: see voxelizeLabels.
/// A soup of several pieces (connected components) is a union of the pieces, except that a piece
/// oriented against the largest one and lying inside the others is a cavity (the inner surface of a
/// skull or a hollow bone) and is carved out: orientation matters only between pieces.
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
};

struct VoxelizedPart {
  std::string name, source;
  VoxelizeRole role = VoxelizeRole::Bone;
  int label = 0;
  std::size_t voxels = 0;          ///< voxels inside the surface
  std::size_t labelledVoxels = 0;  ///< voxels carrying its label in the result (after priorities)
  double voxelVolume = 0;          ///< voxels x voxel volume (mm^3)
  MeshTopology topology;
  double outsideSkinFraction = 0;  ///< bones and tissues: fraction of their voxels outside the skin
  bool cutByGrid = false;
  std::size_t cavities = 0, invertedPieces = 0;  ///< see MeshVoxelization
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

/// One label volume from one skin and any number of bones and tissues: the skin's interior gets the
/// skin's label (soft tissue), each bone and tissue its own; where they overlap bones win over
/// tissues over skin (between two bones, or two tissues, the first given). The grid is `grid` when
/// its dims are non-zero, else gridFittingPoints(skin, options). A surface that encloses no voxel is
/// an error (open with holes wider than the band, or smaller than a voxel); a surface with holes or
/// non-manifold edges that still encloses voxels, a bone or tissue partly outside the skin (kept in
/// the body anyway) and overlapping bones are warnings.
/// Throws std::invalid_argument "SOURCE: problem" on bad input, no or several skins, duplicate
/// names, or a grid above options.maxVoxels.
LabelVoxelization voxelizeLabels(const std::vector<VoxelizePart>& parts, const ImageGrid& grid,
                                 const LabelVoxelizeOptions& options = {});

}  // namespace repose
