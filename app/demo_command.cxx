#include "demo_command.h"

#include <iostream>
#include <string>
#include <vector>

#include <vtkImageData.h>
#include <vtkPolyData.h>
#include <vtkUnstructuredGrid.h>

#include "atomic_outputs.h"
#include "cli_options.h"
#include "display_requirement.h"
#include "phantom_command.h"
#include "pipeline_report.h"
#include "posed_writes.h"
#include "prepare_command.h"
#include "render_snapshot.h"
#include "repose_pipeline.h"
#include "skeleton.h"
#include "vtkReposePhantomSource.h"

namespace repose {
namespace {

const char* kDemoUsage =
    "usage: repose demo [--out DIR] [--size tiny|small|medium|large] [--skinning dqs|lbs] [--no-render]\n"
    "  Builds the phantom, prepares it and poses it (left hip flexed 60 deg, left knee 45 deg,\n"
    "  right shoulder abducted 80 deg, right elbow 90 deg). Writes into DIR (default ./repose-demo):\n"
    "  rest_labels.nii.gz, skeleton.json, pose.json, case/, posed_labels.nii.gz, posed_mesh.vtu,\n"
    "  posed_surfaces.vtp, rest_surfaces.vtp and render.png, and prints the time of each stage.\n"
    "  --size       phantom size (default small)\n"
    "  --no-render  skip render.png (it needs an X display; without one, repose runs itself under xvfb-run)\n";

/// The demo's pose: a hip flexed 60 deg, a knee 45 deg, a shoulder abducted 80 deg, an elbow 90 deg.
/// LPS frame: +x patient left, +y posterior, +z superior.
const char* kDemoPose = R"({
  "rotations": {
    "left_hip":       {"axis": [1, 0, 0], "degrees": -60},
    "left_knee":      {"axis": [1, 0, 0], "degrees": 45},
    "right_shoulder": {"axis": [0, 1, 0], "degrees": 80},
    "right_elbow":    {"axis": [1, 0, 0], "degrees": -90}
  },
  "translation": [0, 0, 0]
}
)";

std::vector<int> boneLabels(const std::string& skeletonJson) {
  std::vector<int> labels;
  for (const auto& j : parseSkeletonJson(skeletonJson).joints)
    labels.insert(labels.end(), j.labels.begin(), j.labels.end());
  return labels;
}

}  // namespace

int runDemoCommand(int argc, char** argv, int first) {
  const Options o(argc, argv, first, {"out", "size", "skinning"}, {"no-render"});
  if (o.help) return std::cout << kDemoUsage, 0;
  const bool render = !o.has("no-render");
  if (render) requireDisplay(argc, argv, "render.png (or pass --no-render)");
  const std::string outDir = o.get("out", "repose-demo");
  const std::string size = o.get("size", "small");
  Pipeline pipeline;
  pipeline.setProgress([](const std::string& s) { std::cout << "demo: " << s << "..." << std::endl; });

  std::cout << "demo: building the " << size << " phantom..." << std::endl;
  auto phantom = phantomSource(size);
  vtkImageData* labels = phantom->GetOutput();
  const std::string skeletonJson = phantom->GetSkeletonJSON();

  AtomicOutputs out(outDir);
  writeLabelImage(labels, out.stage("rest_labels.nii.gz"));
  writeTextFile(out.stage("skeleton.json"), skeletonJson);
  writeTextFile(out.stage("pose.json"), kDemoPose);
  writeTextFile(out.stage("labels.tsv"), phantom->GetLabelTableTSV());
  pipeline.setLabelTableTsv(phantom->GetLabelTableTSV());
  prepareCase(pipeline, labels, "phantom", skeletonJson, "phantom skeleton", nullptr, "", o, out.stage("case"),
              ".nii.gz");

  pipeline.setPose(kDemoPose, "demo pose");
  pipeline.setSkinningMethod(o.get("skinning", "dqs"));
  std::cout << "demo: posing..." << std::endl;
  writePosed(pipeline, out, ".nii.gz", ".nii.gz");
  writeSurfaces(pipeline.restSurfaces(), out.stage("rest_surfaces.vtp"));
  if (render) {
    std::cout << "demo: rendering..." << std::endl;
    renderSideBySide(pipeline.restSurfaces(), pipeline.posedSurfaces(), boneLabels(skeletonJson),
                             out.stage("render.png"));
  }
  out.commit();
  int d[3];
  labels->GetDimensions(d);
  std::cout << "demo: " << d[0] << "x" << d[1] << "x" << d[2] << " voxels, "
            << pipeline.restMesh()->GetNumberOfPoints() << " nodes, " << pipeline.restMesh()->GetNumberOfCells()
            << " tets; outputs in " << outDir << "\nstage times:\n";
  printTimings(pipeline);
  return 0;
}

}  // namespace repose
