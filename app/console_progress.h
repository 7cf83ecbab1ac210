#pragma once
// Progress of long CLI stages on the console, a line at most every few seconds: the FEM reports
// every Newton and continuation step (several a second on a small mesh, one every few seconds on a
// whole body), and a user waiting a minute wants to see where it is, not a scroll of steps.
#include <functional>
#include <string>

namespace repose {

/// A progress callback (Pipeline::setProgress) that prints "<prefix><text>" to stdout, the first text at once and then at
/// most one every `interval` seconds (the latest text when due).
std::function<void(const std::string&)> throttledConsoleProgress(const std::string& prefix, double interval = 5.0);

}  // namespace repose
