#include "prepare_command.h"

#include <iostream>

#include <vtkImageData.h>
#include <vtkSmartPointer.h>

#include "atomic_outputs.h"
#include "cli_options.h"
#include "scan_preparation.h"
#include "output_guard.h"
#include "pipeline_report.h"
#include "repose_pipeline.h"
#include "rig_command.h"

namespace repose {
namespace {

const char* kPrepareUsage =
    "usage: repose prepare --labels FILE --skeleton FILE|auto [--image CT_FILE] --out CASE_DIR [options]\n"
    "  Meshes the body with TetGen, solves Laplace's equation for the bone weights and binds the skin\n"
    "  and bone surfaces to the mesh. CASE_DIR then holds mesh.vtu, surfaces.vtp, skeleton.json,\n"
    "  labels.<ext>, labels.tsv (the label table) and manifest.json (ParaView opens the .vtu/.vtp as they are).\n"
    "  --skeleton auto         find the skeleton from the bone labels (see 'repose rig')\n"
    "  --label-table FILE      label names and kinds (TSV or 3D Slicer colour table); default: the table beside\n"
    "                          the labels, else TotalSegmentator's names (see 'repose rig --help')\n"
    "  --image FILE            CT on the label grid: the body is the labels united with CT above the threshold;\n"
    "                          a folder is read as a DICOM CT series (--series-uid UID when it holds several)\n"
    "  --body-threshold HU     default -500\n"
    "  --max-tets N            tet budget (default 3000000, the paper's scale): the body is meshed on the finest\n"
    "                          voxel size, not finer than the labels', whose mesh fits it; 0 = the label spacing\n"
    "  --mesh-spacing MM       mesh the body on this voxel size instead (overrides --max-tets); coarser = fewer tets\n"
    "  --quality RATIO         TetGen radius-edge bound (default 2.0)\n"
    "  --influences K          bone weights kept per node (default 4)\n"
    "  --surface-reduction F   fraction of surface triangles removed by decimation (default 0)\n"
    "  --contact-separation on|off  cut apart body parts that touch in the scan (an arm against the torso,\n"
    "                          a hand against a thigh, the thighs) where their skins meet in a crease, so that\n"
    "                          posing them apart leaves no tissue web (default on)\n";

}  // namespace

void prepareCase(Pipeline& pipeline, vtkImageData* labels, const std::string& labelsName,
                 const std::string& skeletonJson, const std::string& skeletonName, vtkImageData* image,
                 const std::string& imageName, const Options& o, const std::string& caseDir,
                 const std::string& labelsExt) {
  PrepareSettings s;
  s.bodyThreshold = o.number("body-threshold", s.bodyThreshold);
  s.meshSpacing = o.number("mesh-spacing", s.meshSpacing);
  s.maxTets = o.number("max-tets", s.maxTets);
  if (s.maxTets != 0 && s.maxTets < 1000) throw UsageError("--max-tets must be 0 (no budget) or at least 1000");
  s.radiusEdgeRatio = o.number("quality", s.radiusEdgeRatio);
  s.maxInfluences = static_cast<int>(o.number("influences", s.maxInfluences));
  s.surfaceReduction = o.number("surface-reduction", s.surfaceReduction);
  if (s.maxInfluences < 1 || s.maxInfluences > 16) throw UsageError("--influences must be between 1 and 16");
  if (s.meshSpacing < 0) throw UsageError("--mesh-spacing must not be negative");
  if (s.radiusEdgeRatio < 1.1) throw UsageError("--quality must be at least 1.1 (TetGen does not terminate below)");
  if (s.surfaceReduction < 0 || s.surfaceReduction >= 1) throw UsageError("--surface-reduction must be in [0, 1)");
  const std::string separation = o.get("contact-separation", "on");
  if (separation != "on" && separation != "off")
    throw UsageError("--contact-separation takes on or off, not '" + separation + "'");
  s.separateContacts = separation == "on";
  pipeline.prepare(labels, labelsName, skeletonJson, skeletonName, image, imageName, s);
  pipeline.saveCase(caseDir, labelsExt);
  for (const auto& line : pipeline.reportLines()) std::cout << "  " << line << "\n";
}

int runPrepareCommand(int argc, char** argv, int first) {
  const Options o(argc, argv, first,
                  {"labels", "skeleton", "image", "series-uid", "out", "body-threshold", "mesh-spacing", "quality", "influences",
                   "surface-reduction", "label-table", "max-gap", "contact-separation", "max-tets"},
                  {});
  if (o.help) return std::cout << kPrepareUsage, 0;
  const std::string labelsPath = o.require("labels");
  const std::string skeletonPath = o.require("skeleton");
  const std::string caseDir = o.require("out");
  std::string ext = imageExtension(labelsPath);
  if (ext != ".nii.gz" && ext != ".nii" && ext != ".nrrd" && ext != ".mha") ext = ".nii.gz";
  refuseOutputsOverInputs(caseDir, Pipeline::caseFileNames(ext),
                          {{labelsPath, skeletonPath, o.get("image"), o.get("label-table")}, {}});
  Pipeline pipeline;
  pipeline.setProgress([](const std::string& s) { std::cout << "prepare: " << s << "..." << std::endl; });
  ScanSource source;
  source.labelsPath = labelsPath;
  source.skeletonPath = skeletonPath;
  source.labelTablePath = o.get("label-table");
  source.imagePath = o.get("image");
  source.seriesUid = o.get("series-uid");
  source.maxGapMm = o.number("max-gap", 6);
  const ScanForPreparation scan =
      readScanForPreparation(source, [](const std::string& s) { std::cout << "prepare: " << s << "..." << std::endl; });
  std::cout << scan.rigReport;
  pipeline.setLabelTableTsv(scan.tableTsv);
  prepareCase(pipeline, scan.labels, labelsPath, scan.skeletonJson, scan.skeletonName, scan.image, source.imagePath, o,
              caseDir, ext);
  std::cout << "prepared case written to " << caseDir << " (label table: " << caseDir << "/labels.tsv)\n";
  printTimings(pipeline);
  return 0;
}

}  // namespace repose
