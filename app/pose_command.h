#pragma once
// `repose pose`: a prepared case posed: posed label volume (and CT), mesh, surfaces and extra meshes.

namespace repose {

/// Prints the usage with --help; returns the exit code. Throws UsageError on bad options and
/// std::exception ("FILE: problem") on bad input; nothing is written then. With --compare it needs
/// an X display and may run itself again under xvfb-run (see requireDisplay).
int runPoseCommand(int argc, char** argv, int first);

}  // namespace repose
