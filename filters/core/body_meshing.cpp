#include "body_meshing.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "freed_heap.h"
#include "mesh_budget.h"
#include "mesh_ordering.h"
#include "mesh_tagging.h"

namespace repose {

namespace {

using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

/// The mask's lines of the report: the body, its pieces, what was peeled, the meshing grid, contacts.
void reportMask(const MeshingMask& meshing, const MeshingMaskOptions& options, const Skeleton& skeleton,
                double seconds, std::ostream& report) {
  const auto& mg = meshing.mesh.body.grid;
  report << "body mask: " << meshing.bodyVoxels << " voxels";
  if (meshing.closedMm > 0) report << " (the labels alone make the body: closed by " << meshing.closedMm << " mm)";
  report << ", " << meshing.components.kept << " piece(s) with bone";
  if (meshing.components.bridged > 0)
    report << ", " << meshing.components.bridged << " without bone bridged to them (" << meshing.components.bridgeVoxels
           << " bridge voxels)";
  if (meshing.components.dropped > 0)
    report << ", " << meshing.components.dropped << " dropped (" << meshing.components.droppedVoxels
           << " voxels: no bone and too small or too far to bridge)";
  report << "; " << meshing.peeledVoxels << " after "
         << (options.skinLabels.empty() ? "peeling the outer layer"
                                        : "removing " + std::to_string(meshing.skinVoxelsRemoved) + " skin voxels")
         << "\nmeshing grid: " << mg.dims[0] << "x" << mg.dims[1] << "x" << mg.dims[2] << " at "
         << meshing.spacing.spacingMm << " mm";
  if (meshing.spacing.trials > 0)
    report << " (chosen for at most " << static_cast<long long>(options.maxTets) << " tets: "
           << meshing.spacing.surfaceFaces << " surface faces, " << meshing.spacing.seeds << " bone seeds, about "
           << std::lround(meshing.spacing.predictedTets) << " tets; " << meshing.spacing.trials << " trials)";
  report << ", " << meshing.meshVoxels << " voxels, " << meshing.contacts.contacts.size() << " contact(s) separated, "
         << meshing.contacts.voxelsCut << " voxels cut (" << seconds << " s)\n"
         << meshing.contacts.text(skeleton);
}

/// One pass: mask -> seeds -> surface -> TetGen, with the mask options given.
TetMesh meshOnce(const LabelVolume& labels, const IntensityVolume* intensity, const Skeleton& skeleton,
                 const std::vector<int>& boneOfLabel, const MeshingMaskOptions& maskOptions,
                 const BodyMeshingOptions& options, const BodySurfaceExtraction& extractSurface,
                 const BodyMeshingProgress& progress, MeshingMask& meshing, TetMeshingReport& tetReport,
                 std::ostream& report, BodyMeshing& out) {
  auto t = Clock::now();
  meshing = meshingMask(labels, intensity, boneOfLabel, skeleton, maskOptions);
  out.meshingSpacingMm = meshing.spacing.spacingMm;
  out.contactVoxelsCut = meshing.contacts.voxelsCut;
  out.contactReport = meshing.contacts.text(skeleton);
  reportMask(meshing, maskOptions, skeleton, secondsSince(t), report);

  t = Clock::now();
  SeedSteps steps = seedSteps(labels.grid, meshing.spacing.spacingMm);
  if (options.seedSurfaceStep > 0) {
    steps.surface = options.seedSurfaceStep;
    steps.interior = 2 * steps.surface;
  }
  if (options.seedInteriorStep > 0) steps.interior = options.seedInteriorStep;
  const Points seeds = boneSeedPoints(labels, boneOfLabel, meshing.peeled, steps.surface, steps.interior);
  out.seedPoints = std::size_t(seeds.rows());
  report << "bone seeds: " << seeds.rows() << " (steps " << steps.surface << "/" << steps.interior << " voxels, "
         << secondsSince(t) << " s)\n";
  // The scan-grid masks are done with (the surface comes from the meshing grid's): not beside TetGen.
  meshing.body = MaskVolume();
  meshing.peeled = MaskVolume();

  auto meshSurface = [&](double reduction) {
    const auto ts = Clock::now();
    Points V;
    Triangles F;
    if (!extractSurface(meshing.mesh.body, reduction, V, F))
      throw std::invalid_argument("no body surface could be extracted (MeshingSpacing too coarse for the body?)");
    out.surfaceTriangles = std::size_t(F.rows());
    report << "surface: " << V.rows() << " points, " << F.rows() << " triangles (reduction " << reduction << ", "
           << secondsSince(ts) << " s)\n";
    std::ostringstream text;
    text << "TetGen: " << F.rows() << " surface triangles and " << seeds.rows() << " bone seeds";
    if (meshing.spacing.predictedTets > 0)
      text << " into about " << std::lround(meshing.spacing.predictedTets / 1e3) << " k tets";
    if (progress) progress(text.str());
    TetMesh mesh = tetrahedralizeSurface(V, F, seeds, options.tets, &tetReport);
    releaseFreedHeap();  // TetGen's pools, before the next stage allocates
    return mesh;
  };
  // A decimated surface may self-intersect in a narrow gap: TetGen refuses it, the full one is used.
  try {
    return meshSurface(options.surfaceReduction);
  } catch (const std::invalid_argument& e) {
    if (options.surfaceReduction <= 0) throw;
    report << "decimated surface rejected (" << e.what() << "); meshing the full surface\n";
    return meshSurface(0.0);
  }
}

void reportTetGen(const TetMeshingReport& r, std::ostream& report) {
  report << "tetgen: " << r.nodes << " nodes, " << r.tets << " tets, "
         << (r.surfacePreserved ? "surface kept" : "surface split")
         << (r.preserveFailure.empty() ? "" : " (keeping it failed: " + r.preserveFailure + ")") << " (" << r.seconds
         << " s)\n";
}

/// Spatial order, tags, freed bone contacts, bone-less pieces dropped; the tagging lines and warnings.
void tagAndClean(TetMesh& mesh, const LabelVolume& labels, const Skeleton& skeleton,
                 const std::vector<int>& boneOfLabel, std::ostream& report, BodyMeshing& out) {
  const auto t = Clock::now();
  reorderMeshSpatially(mesh);
  tagMesh(mesh, labels, boneOfLabel);
  const ContactReport contacts = freeBoneContacts(mesh);
  out.freedContactNodes = contacts.nodesFreed;
  if (contacts.bonesKept > 0)
    out.warnings.push_back(std::to_string(contacts.bonesKept) + " bone(s) touch another bone everywhere in the mesh: " +
                           "their joints cannot bend without inverting tets");
  const ComponentReport components = keepBoneComponents(mesh);
  if (components.componentsDropped > 0)
    out.warnings.push_back("dropped " + std::to_string(components.componentsDropped) + " mesh component(s) without bone (" +
                           std::to_string(components.nodesDropped) + " nodes, " + std::to_string(components.tetsDropped) +
                           " tets); kept " + std::to_string(components.componentsKept));
  std::vector<std::size_t> fixedPerBone(skeleton.size(), 0);
  out.fixedNodes = 0;
  for (int b : mesh.fixedBone)
    if (b >= 0 && b < int(fixedPerBone.size())) {
      ++fixedPerBone[std::size_t(b)];
      ++out.fixedNodes;
    }
  report << "tagging: " << out.fixedNodes << " fixed nodes (" << contacts.nodesFreed << " freed where "
         << contacts.edgesBetweenBones << " edges joined two bones), " << components.componentsKept
         << " component(s) kept, " << components.componentsDropped << " dropped (" << components.nodesDropped
         << " nodes, " << components.tetsDropped << " tets) (" << secondsSince(t) << " s)\n";
  for (std::size_t b = 0; b < fixedPerBone.size(); ++b) {
    report << "  " << skeleton.joints[b].name << ": " << fixedPerBone[b] << " fixed nodes\n";
    if (fixedPerBone[b] == 0 && !skeleton.joints[b].labels.empty())
      out.warnings.push_back("bone '" + skeleton.joints[b].name +
                             "' has no mesh node inside it: its labels are missing from the meshed body or it is "
                             "thinner than the mesh resolution");
  }
}

}  // namespace

void meshBody(const LabelVolume& labels, const IntensityVolume* intensity, const Skeleton& skeleton,
              const BodyMeshingOptions& options, const BodySurfaceExtraction& extractSurface,
              const BodyMeshingProgress& progress, BodyMeshing& out) {
  out = BodyMeshing();
  std::ostringstream report;
  try {
    const int maxLabel = labels.data.empty() ? 0 : *std::max_element(labels.data.begin(), labels.data.end());
    const std::vector<int> boneOfLabelMap = boneOfLabel(skeleton, std::max(0, maxLabel));
    MeshingMaskOptions maskOptions = options.mask;
    MeshingMask meshing;
    TetMeshingReport tetReport;
    out.mesh = meshOnce(labels, intensity, skeleton, boneOfLabelMap, maskOptions, options, extractSurface, progress,
                        meshing, tetReport, report, out);
    reportTetGen(tetReport, report);
    out.tetgenSeconds = tetReport.seconds;
    // The budget's prediction is a fit: where TetGen exceeds the budget by a tenth, choose again with
    // the tets per surface point this body has shown, and mesh once more.
    if (meshing.spacing.trials > 0 && tetReport.tets > 1.1 * maskOptions.maxTets) {
      maskOptions.tetsPerPoint =
          1.02 * tetReport.tets / static_cast<double>(meshing.spacing.surfaceFaces + meshing.spacing.seeds);
      report << "over the budget of " << static_cast<long long>(maskOptions.maxTets) << " tets ("
             << maskOptions.tetsPerPoint << " tets per surface point): meshing again\n";
      out.mesh = meshOnce(labels, intensity, skeleton, boneOfLabelMap, maskOptions, options, extractSurface,
                          progress, meshing, tetReport, report, out);
      reportTetGen(tetReport, report);
      out.tetgenSeconds += tetReport.seconds;
    }
    tagAndClean(out.mesh, labels, skeleton, boneOfLabelMap, report, out);
  } catch (...) {
    out.report = report.str();
    throw;
  }
  out.report = report.str();
}

}  // namespace repose
