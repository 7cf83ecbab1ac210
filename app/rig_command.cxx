#include "rig_command.h"

#include <filesystem>
#include <iostream>
#include <stdexcept>

#include <vtkDataArray.h>
#include <vtkImageData.h>
#include <vtkPointData.h>

#include "atomic_outputs.h"
#include "cli_options.h"
#include "scan_preparation.h"
#include "output_guard.h"
#include "repose_pipeline.h"
#include "vtkReposeAutoRig.h"

namespace repose {
namespace {

const char* kRigUsage =
    "usage: repose rig --labels FILE [--label-table FILE] --out skeleton.json [--max-gap MM]\n"
    "  Finds the joints from the bone labels and writes an editable skeleton.json, rooted at the pelvis.\n"
    "  Ball joints by sphere fits to the femoral and humeral heads, others where adjacent bones come closest.\n"
    "  A label holding both sides (femur) is split (femur_left, femur_right). Smaller pieces of a label\n"
    "  (under 25 % of its largest piece or 0.5 ml, or more than one per side) are never joints: each goes to\n"
    "  its own bone when that touches it or lies within 20 mm on its side of the midline, else to a bone it\n"
    "  touches, else to the nearest bone on its side within 20 mm, else it is left as soft tissue (label\n"
    "  unassigned_bone_fragments); the report says where each went. Parents follow anatomy: skull on the\n"
    "  cervical spine, patella with its femur, ribs and sternum with the spine, clavicle - scapula - humerus\n"
    "  on each side. Joint names come from a fixed vocabulary whatever the table calls the bones: pelvis,\n"
    "  spine, chest, neck, head, jaw, vertebra_L4, left_/right_ clavicle, scapula, shoulder, elbow, wrist,\n"
    "  hip, knee, ankle. When labels were split or pieces moved, the relabelled volume and its table are\n"
    "  written beside the skeleton (labels_rigged.nii.gz, labels_rigged.tsv).\n"
    "  --label-table FILE  value<TAB>name[<TAB>bone|soft|background] lines, or a 3D Slicer colour table\n"
    "                      (.ctbl/.txt: value name R G B A). Default: the table beside the labels (NAME.tsv,\n"
    "                      NAME.ctbl, NAME_ColorTable.ctbl, NAME.txt unless it holds no table, labels.tsv for\n"
    "                      NAME.nii.gz), else TotalSegmentator's class names. A table whose bone names\n"
    "                      contradict where the bones lie (the wrong table) is an error\n"
    "  --max-gap MM        largest gap between bones that still makes a joint (default 6)\n";

}  // namespace

int runRigCommand(int argc, char** argv, int first) {
  const Options o(argc, argv, first, {"labels", "label-table", "out", "max-gap"}, {});
  if (o.help) return std::cout << kRigUsage, 0;
  const std::string labelsPath = o.require("labels");
  const std::string outPath = o.require("out");
  const std::filesystem::path out(outPath);
  const std::string dir = out.has_parent_path() ? out.parent_path().string() : ".";
  refuseOutputsOverInputs(dir, {out.filename().string(), "labels_rigged.nii.gz", "labels_rigged.tsv"},
                          {{labelsPath, o.get("label-table")}, {}});
  auto labels = readLabelVolume(labelsPath);
  const RigResult r = rigLabels(labels, labelsPath, o.get("label-table"), o.number("max-gap", 6));
  AtomicOutputs files(dir);
  writeTextFile(files.stage(out.filename().string()), r.skeletonJson);
  if (r.relabelled) {
    writeLabelImage(r.labels, files.stage("labels_rigged.nii.gz"));
    writeTextFile(files.stage("labels_rigged.tsv"), r.tableTsv);
  }
  files.commit();
  std::cout << r.report;
  std::cout << "skeleton written to " << outPath
            << (r.relabelled ? " (it refers to the relabelled " + dir + "/labels_rigged.nii.gz, table labels_rigged.tsv)"
                             : std::string())
            << "\n";
  return 0;
}

}  // namespace repose
