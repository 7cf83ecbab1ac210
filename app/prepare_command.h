#pragma once
// `repose prepare`: a label volume meshed, weighted and bound once per scan into a case directory.
#include <string>

class vtkImageData;

namespace repose {

class Options;
class Pipeline;

/// Prints the usage with --help; returns the exit code. Throws UsageError on bad options and
/// std::exception ("FILE: problem") on bad input; nothing is written then.
int runPrepareCommand(int argc, char** argv, int first);

/// Prepares `pipeline` with the meshing and weighting options of `o` (--max-tets, --mesh-spacing,
/// --quality, --influences, ...; UsageError when out of range), saves the case into caseDir with the
/// labels as labelsExt and prints the pipeline's report (also `repose demo`).
void prepareCase(Pipeline& pipeline, vtkImageData* labels, const std::string& labelsName,
                 const std::string& skeletonJson, const std::string& skeletonName, vtkImageData* image,
                 const std::string& imageName, const Options& o, const std::string& caseDir,
                 const std::string& labelsExt);

}  // namespace repose
