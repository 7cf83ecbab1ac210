#pragma once
// The fidelity report's picture: body volume ratio against frame, one line per posing method (the
// comparison of the paper's figure 9), drawn with VTK's charts offscreen.
#include <map>
#include <string>
#include <vector>

namespace repose {

/// series: method -> (frame, volume ratio) points. Needs an X display (or Xvfb).
void plotVolumeRatios(const std::map<std::string, std::vector<std::pair<double, double>>>& series,
                      const std::string& pngPath, int width = 900, int height = 500);

}  // namespace repose
