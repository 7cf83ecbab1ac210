#pragma once
// `repose animate`: a prepared case driven by a BVH motion clip, written as a ParaView time series.

namespace repose {

/// Prints the usage with --help; returns the exit code. Throws UsageError on bad options and
/// std::exception ("FILE: problem") on bad input; nothing is written then. With --compare it needs
/// an X display and may run itself again under xvfb-run (see requireDisplay).
int runAnimateCommand(int argc, char** argv, int first);

}  // namespace repose
