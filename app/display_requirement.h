#pragma once
// Rendering (render.png, fidelity.png) needs an X display.

namespace repose {

/// Returns when an X display is there. Without one, runs this command again under `xvfb-run -a`
/// (replacing the process) when xvfb-run is installed, else throws std::runtime_error
/// "WHY needs an X display: install xvfb (xvfb-run)".
void requireDisplay(int argc, char** argv, const char* why);

}  // namespace repose
