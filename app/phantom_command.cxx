#include "phantom_command.h"

#include <iostream>
#include <stdexcept>

#include <vtkImageData.h>
#include <vtkPointData.h>

#include "atomic_outputs.h"
#include "cli_options.h"
#include "repose_pipeline.h"
#include "vtkReposePhantomSource.h"

namespace repose {
namespace {

const char* kPhantomUsage =
    "usage: repose phantom --out DIR [--size tiny|small|medium|large] [--rest-pose apart|contact]\n"
    "  Writes DIR/labels.nii.gz, DIR/skeleton.json and DIR/labels.tsv (label table).\n"
    "  --rest-pose apart    arms and thighs clear of each other (default)\n"
    "  --rest-pose contact  as real scans are taken: arms against the torso, hands against the thighs,\n"
    "                       thighs touching, with no background between them\n";

}  // namespace

vtkSmartPointer<vtkReposePhantomSource> phantomSource(const std::string& size, const std::string& rest) {
  auto phantom = vtkSmartPointer<vtkReposePhantomSource>::New();
  if (size != "tiny" && size != "small" && size != "medium" && size != "large")
    throw UsageError("unknown --size '" + size + "' (use tiny, small, medium or large)");
  if (rest != "apart" && rest != "contact")
    throw UsageError("unknown --rest-pose '" + rest + "' (use apart or contact)");
  phantom->SetSizeName(size.c_str());
  phantom->SetRestPoseName(rest.c_str());
  phantom->Update();
  if (!phantom->GetOutput() || !phantom->GetOutput()->GetPointData())
    throw std::runtime_error("phantom: cannot build the phantom");
  return phantom;
}

int runPhantomCommand(int argc, char** argv, int first) {
  const Options o(argc, argv, first, {"out", "size", "rest-pose"}, {});
  if (o.help) return std::cout << kPhantomUsage, 0;
  const std::string outDir = o.require("out");
  auto phantom = phantomSource(o.get("size", "small"), o.get("rest-pose", "apart"));
  AtomicOutputs out(outDir);
  writeLabelImage(phantom->GetOutput(), out.stage("labels.nii.gz"));
  writeTextFile(out.stage("skeleton.json"), phantom->GetSkeletonJSON());
  writeTextFile(out.stage("labels.tsv"), phantom->GetLabelTableTSV());
  out.commit();
  int d[3];
  phantom->GetOutput()->GetDimensions(d);
  std::cout << "phantom: " << d[0] << "x" << d[1] << "x" << d[2] << " voxels written to " << outDir << "\n";
  return 0;
}

}  // namespace repose
