#pragma once
// `repose phantom`: the built-in phantom's label volume, skeleton and label table.
#include <string>

#include <vtkSmartPointer.h>

class vtkReposePhantomSource;

namespace repose {

/// Prints the usage with --help; returns the exit code. Throws UsageError on bad options.
int runPhantomCommand(int argc, char** argv, int first);

/// The phantom built at `size` (tiny, small, medium, large) in `rest` pose (apart, contact);
/// throws UsageError naming --size or --rest-pose for any other word.
vtkSmartPointer<vtkReposePhantomSource> phantomSource(const std::string& size, const std::string& rest = "apart");

}  // namespace repose
