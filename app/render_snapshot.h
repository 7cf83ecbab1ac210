#pragma once
// Offscreen picture of rest and posed surfaces side by side (skin translucent, bones opaque).
#include <string>
#include <vector>

class vtkPolyData;

namespace repose {

/// Renders `left` (rest) and `right` (posed) side by side from the front, plus `right` from the
/// side, into a PNG of width x height (surfaces with cell data "Label"),
/// bones (labels in boneLabels) opaque ivory, other surfaces translucent skin colour. Needs an X
/// display (or Xvfb). Throws std::runtime_error on failure.
void renderSideBySide(vtkPolyData* left, vtkPolyData* right, const std::vector<int>& boneLabels,
                      const std::string& pngPath, int width = 1500, int height = 800);

}  // namespace repose
