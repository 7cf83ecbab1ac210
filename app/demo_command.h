#pragma once
// `repose demo`: the built-in phantom prepared and posed, every output written and rendered.

namespace repose {

/// Prints the usage with --help; returns the exit code. Throws UsageError on bad options. Rendering
/// needs an X display: without one it runs itself again under xvfb-run (see requireDisplay).
int runDemoCommand(int argc, char** argv, int first);

}  // namespace repose
