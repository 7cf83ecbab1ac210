#pragma once
// Hollows a surface encloses, and the filling of the thin ones. A bone's surface may be its cortex
// alone: an outer surface and an inward-facing inner one around the marrow and cancellous bone, which
// the winding number counts as outside (w = 0). The Visible Human's hip bones are such shells: 1.2 mm
// of cortex around about 391 ml. For posing, marrow moves with its bone, so such a hollow is bone; a
// cavity wide enough to hold an organ (a skull's cranial cavity) is not.
//
// A hollow is a connected region of voxels outside the surface (w < 1/2) that the outside cannot
// reach without crossing the surface: the outside is flooded from beyond the surface's box along the
// lattice segments between voxel centres that no triangle crosses (lattice_crossings.h), holes
// counting as closed by the cones that span them in the winding number (winding_inside.h). So a
// shell thinner than a voxel, which leaves few voxel centres or none inside it, still walls its
// hollow in, at any voxel size: the hip bones' shells, which fall apart into hundreds of pieces of
// voxels at 2 mm, enclose their 391 ml at 0.5 to 4 mm alike. An opening modelled in the surface
// (a cup's mouth, a canal through the wall) lets the outside in once a lattice segment passes
// through it: what lies behind it is then no hollow.
// A hollow's width is its radius: the distance from its deepest voxel centre to the nearest voxel
// centre not in it (distance_transform.h), the radius of the largest ball it holds within about a
// voxel.
#include <cstddef>
#include <vector>

#include "image_grid.h"
#include "mesh_topology.h"
#include "winding_inside.h"

namespace repose {

/// Largest radius of a hollow filled as bone by default (mm): cancellous bone and marrow fit in
/// balls of up to about 25 mm (a femoral or humeral head; the Visible Human's hip bones 16-17 mm),
/// an adult's cranial cavity holds one of 50 mm or more.
constexpr double kMaxMarrowRadiusMm = 30.0;

struct HollowOptions {
  bool fill = true;                             ///< fill the thin hollows (else only find them)
  double maxFillRadiusMm = kMaxMarrowRadiusMm;  ///< a hollow of this radius or less is thin
};

struct EnclosedHollow {
  std::size_t voxels = 0;
  double radiusMm = 0;  ///< see the file's comment
  bool thin = false;    ///< radius at most HollowOptions::maxFillRadiusMm
};

struct EnclosedHollows {
  std::vector<EnclosedHollow> hollows;  ///< largest first
  std::size_t thinVoxels = 0;           ///< voxels of the thin hollows
  std::size_t wideVoxels = 0;           ///< voxels of the others (cavities)
  bool filled = false;                  ///< the thin hollows were added to the inside
  double largestThinRadiusMm = 0, smallestWideRadiusMm = 0;  ///< 0 when there is none
};

/// Finds the hollows that the soup V (#V by 3, physical mm) F (#F by 3, oriented as for the
/// winding number) encloses on `grid`, given `inside`, its voxels by insideByWindingNumber on the
/// same soup and grid, and with options.fill adds the thin ones to inside.inside (not to
/// insideVoxels). Deterministic.
/// Throws std::invalid_argument on a bad index or a radius that is negative or not a number.
EnclosedHollows fillEnclosedHollows(const MeshVertices& V, const MeshTriangles& F, const ImageGrid& grid,
                                    WindingInside& inside, const HollowOptions& options = {});

}  // namespace repose
