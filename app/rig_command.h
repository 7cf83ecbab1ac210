#pragma once
// `repose rig`: the joints found from the bone labels, written as an editable skeleton.json.
#include <string>

namespace repose {

/// Prints the usage with --help; returns the exit code. Throws UsageError on bad options and
/// std::exception ("FILE: problem") on bad input; nothing is written then.
int runRigCommand(int argc, char** argv, int first);

}  // namespace repose
