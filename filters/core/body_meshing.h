#pragma once
// The body's tet mesh from a label volume, as `repose prepare` makes it: the body mask on a meshing
// grid chosen for a tet budget (meshing_mask.h), its surface, bone seeds, TetGen (tet_mesher.h; meshed
// again with the body's own tets per surface point when the budget's fit overshoots by a tenth, and
// from the undecimated surface when TetGen refuses a decimated one), then spatial order, tags, freed
// bone contacts and bone-less pieces dropped (mesh_tagging.h).
//
// Contouring the mask is the caller's: the VTK layer extracts, smooths and decimates the surface
// (vtkReposeSurfaceExtractor::ContourMask) and passes that in as a function, so this file holds the
// order and the heuristics and no VTK.
#include <functional>
#include <string>
#include <vector>

#include "image_grid.h"
#include "meshing_mask.h"
#include "skeleton.h"
#include "tet_mesh.h"
#include "tet_mesher.h"

namespace repose {

struct BodyMeshingOptions {
  MeshingMaskOptions mask;
  TetMeshingOptions tets;
  double surfaceReduction = 0;  ///< decimation target handed to the surface extraction (0 = none)
  int seedSurfaceStep = 0;      ///< bone seed steps in voxels; 0 = from the meshing spacing (seedSteps)
  int seedInteriorStep = 0;
};

/// The body (a mask on the meshing grid) and a decimation target -> a triangle surface in mm (V #V
/// by 3, F #F by 3). Returns false when no surface comes out; throws std::invalid_argument when it
/// is not made of triangles.
using BodySurfaceExtraction = std::function<bool(const MaskVolume& body, double reduction, Points& V, Triangles& F)>;
/// Told before each TetGen run what it is about to do (TetGen says nothing while it runs).
using BodyMeshingProgress = std::function<void(const std::string& text)>;

struct BodyMeshing {
  TetMesh mesh;                      ///< nodes in mm, tets, fixedBone per node, tetLabel per tet
  std::string report;                ///< one line per stage (filled as they run: kept on a throw)
  std::vector<std::string> warnings; ///< bones that touch everywhere, pieces dropped, bones without a node
  double meshingSpacingMm = 0;
  std::size_t contactVoxelsCut = 0;
  std::string contactReport;         ///< the separated contacts, one line each
  std::size_t seedPoints = 0, surfaceTriangles = 0, fixedNodes = 0, freedContactNodes = 0;
  double tetgenSeconds = 0;          ///< all TetGen runs
};

/// labels: the scan's label volume; intensity: its CT on the same grid, or null. Fills `out` (its
/// report as the stages run). Throws std::invalid_argument on bad input, nothing to mesh, or TetGen
/// failing on the undecimated surface.
void meshBody(const LabelVolume& labels, const IntensityVolume* intensity, const Skeleton& skeleton,
              const BodyMeshingOptions& options, const BodySurfaceExtraction& extractSurface,
              const BodyMeshingProgress& progress, BodyMeshing& out);

}  // namespace repose
