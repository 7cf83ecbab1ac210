#pragma once
// Voxels inside a triangle soup by its generalized winding number, w >= 1/2 (winding_number.h),
// evaluated exactly at every voxel centre without summing over the triangles at each one:
//   w_S = w_{S+C} - w_C,
// where C closes the soup's boundary chain (boundaryChain: the rims of holes, orientation seams) by
// a cone from the mean point of each connected piece of it. S + C is a closed chain, whose winding
// number is the signed count of its crossings along a ray: one scanline pass over the grid rows
// gives it everywhere, exactly (the crossing test is made consistent on shared edges and vertices by
// a symbolic perturbation of the ray). w_C is evaluated (WindingNumberTree) only near the cones,
// within holeReach times each cone's radius of its apex; beyond, a single-layer cap subtends less
// than a 30 degree cone, |w_C| < 0.07, and cannot move w across 1/2 from an integer.
// A closed surface, overlapping closed pieces and nested shells cost a scanline pass only.
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "image_grid.h"
#include "mesh_topology.h"

namespace repose {

struct WindingInsideOptions {
  /// w_C is evaluated within this many times each cone's radius of its apex (at least 2).
  double holeReach = 2.0;
  /// Accuracy parameter of the hierarchical evaluation of w_C (WindingNumberOptions::beta).
  double beta = 2.0;
};

/// Inside voxels over the index box of the soup's vertices clipped to the grid, with how they were found.
struct WindingInside {
  std::array<int, 3> boxMin{0, 0, 0};   ///< first voxel index of the box
  std::array<int, 3> boxDims{0, 0, 0};  ///< voxels along i, j, k (0 when the soup misses the grid)
  std::vector<std::uint8_t> inside;     ///< boxDims product, i fastest; 1 = inside (w >= 1/2)
  std::size_t insideVoxels = 0;
  std::size_t overlapVoxels = 0;        ///< inside voxels with w >= 3/2: inside two pieces or more
  std::size_t cones = 0;                ///< connected pieces of the boundary chain, each closed by a cone
  std::size_t evaluatedVoxels = 0;      ///< voxels near a cone, where w_C was evaluated
  /// Mean of min(w, 1) over the inside voxels near the cones: how closed the surface looks where it
  /// is open, about 0.5 for an open sheet; 1 when there is no cone (closed), 0 when nothing is inside.
  double meanInsideWinding = 0;
  bool cutByGrid = false;               ///< the soup reaches beyond the grid
  bool outsideGrid = false;             ///< the soup's bounds miss the grid altogether
};

/// The cones closing a soup's boundary chain (boundaryChain: the rims of holes, orientation seams):
/// one per connected piece of the chain, its apex the mean of the piece's vertices.
struct ClosingCones {
  MeshVertices V;   ///< the soup's vertices followed by one apex per cone
  MeshTriangles F;  ///< cap triangles (apex, to, from) over the chain's edges (from, to)
  std::vector<Eigen::Vector3d> apex;
  std::vector<double> radius;  ///< farthest chain vertex from the apex (mm)
};

/// Cones closing the boundary chain of V (#V by 3), F (#F by 3): none for a closed soup. Throws
/// std::invalid_argument on a bad index.
ClosingCones closingCones(const MeshVertices& V, const MeshTriangles& F);

/// Voxel centres of `grid` (any origin, spacing, direction) inside the soup V (#V by 3, physical
/// mm, the grid's frame) F (#F by 3) by w >= 1/2, as the triangles are oriented (outward: w = 1
/// inside; an inward piece inside an outward one subtracts). Threaded over rows; the result does
/// not depend on the number of threads.
/// Throws std::invalid_argument on an empty soup, a bad index, a non-finite vertex, an empty grid or
/// a holeReach below 2.
WindingInside insideByWindingNumber(const MeshVertices& V, const MeshTriangles& F, const ImageGrid& grid,
                                    const WindingInsideOptions& options = {});

}  // namespace repose
