#pragma once
// `repose rig`: the joints found from the bone labels, written as an editable skeleton.json.
#include <string>

#include <vtkSmartPointer.h>

class vtkImageData;

namespace repose {

class Options;

/// Prints the usage with --help; returns the exit code. Throws UsageError on bad options and
/// std::exception ("FILE: problem") on bad input; nothing is written then.
int runRigCommand(int argc, char** argv, int first);

/// The automatic skeleton of a label volume (also `repose prepare --skeleton auto`).
struct RigResult {
  vtkSmartPointer<vtkImageData> labels;  // relabelled when a label held several bones or fragments moved
  std::string skeletonJson, report, tableTsv;
  bool relabelled = false;
};

/// Rigs `labels` with the label table chosen by --label-table (see chooseLabelTable) and --max-gap.
/// Throws std::runtime_error naming labelsName when the table does not fit or fewer than 2 joints are found.
RigResult rigLabels(vtkImageData* labels, const std::string& labelsName, const Options& o);

}  // namespace repose
