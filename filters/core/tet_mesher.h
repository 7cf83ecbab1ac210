#pragma once
// Constrained quality tetrahedralization of a closed surface (TetGen; the only file that uses it is
// tet_mesher.cpp, so the mesher can be swapped).
#include <string>

#include "tet_mesh.h"

namespace repose {

struct TetMeshingOptions {
  double radiusEdgeRatio = 2.0;   ///< TetGen -q quality bound
  double minDihedralDegrees = 0;  ///< TetGen -q second value, 0 = TetGen default
  double maxTetVolume = 0;        ///< mm^3, 0 = unbounded (grading comes from the surface and seeds)
  /// TetGen -Y: the surface triangles become the mesh's boundary faces unsplit. Refinement then
  /// inserts interior points only; splitting every encroached surface edge (each triangle is its own
  /// facet) doubled the surface's points and took most of TetGen's time on whole-body scans. When
  /// TetGen cannot recover the surface this way the region is meshed again with splitting allowed.
  /// Ignored with a volume bound: tets on a large surface triangle only shrink when it is split.
  bool preserveSurface = true;
  bool verbose = false;
};

struct TetMeshingReport {
  int inputPoints = 0, inputFacets = 0, seedPoints = 0;
  int nodes = 0, tets = 0;
  bool surfacePreserved = false;  ///< the boundary is the input surface (see preserveSurface)
  std::string preserveFailure;    ///< why preserving it failed, when it was asked for and failed
  double seconds = 0;
};

/// Tetrahedralizes the region enclosed by the closed, non-self-intersecting triangle surface
/// (V #V by 3, F #F by 3; several disjoint shells allowed). `seeds` (#S by 3, may be empty) are
/// extra interior points inserted into the mesh (points outside the region are ignored): they make
/// the mesh fine where the anatomy needs it (near bones). Returns nodes and positively oriented tets;
/// fixedBone and tetLabel are left empty. Throws std::invalid_argument (with TetGen's reason) on failure.
TetMesh tetrahedralizeSurface(const Points& V, const Triangles& F, const Points& seeds,
                              const TetMeshingOptions& options, TetMeshingReport* report = nullptr);

}  // namespace repose
