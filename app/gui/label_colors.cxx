#include "label_colors.h"

#include <algorithm>

#include <vtkLookupTable.h>

namespace repose {

void labelColor(int value, const LabelTable& table, bool isBone, double rgb[3]) {
  const LabelInfo* info = table.find(value);
  if (value == -1 || (info && info->name == "skin")) {
    rgb[0] = 0.93, rgb[1] = 0.75, rgb[2] = 0.63;
    return;
  }
  if (isBone || (info && info->kind == LabelKind::Bone)) {
    // Ivory with a small per-bone variation so neighbouring bones can be told apart.
    const double v = ((value * 37) % 7) / 7.0;
    rgb[0] = 0.95 - 0.08 * v, rgb[1] = 0.92 - 0.10 * v, rgb[2] = 0.80 - 0.14 * v;
    return;
  }
  static const double palette[][3] = {{0.85, 0.35, 0.30}, {0.95, 0.85, 0.45}, {0.65, 0.25, 0.25},
                                      {0.90, 0.70, 0.80}, {0.55, 0.75, 0.90}, {0.80, 0.20, 0.25},
                                      {0.60, 0.40, 0.25}, {0.75, 0.55, 0.30}, {0.85, 0.60, 0.50},
                                      {0.45, 0.70, 0.45}, {0.60, 0.55, 0.85}, {0.30, 0.60, 0.70}};
  const double* c = palette[static_cast<unsigned>(value) % 12];
  std::copy(c, c + 3, rgb);
}

vtkSmartPointer<vtkLookupTable> labelLookupTable(int maxLabel, const LabelTable& table,
                                                 const std::vector<int>& boneLabels, double alpha) {
  maxLabel = std::max(maxLabel, 1);
  auto lut = vtkSmartPointer<vtkLookupTable>::New();
  lut->SetNumberOfTableValues(maxLabel + 1);
  lut->SetTableRange(0, maxLabel);
  for (int v = 0; v <= maxLabel; ++v) {
    double rgb[3];
    labelColor(v, table, std::find(boneLabels.begin(), boneLabels.end(), v) != boneLabels.end(), rgb);
    lut->SetTableValue(v, rgb[0], rgb[1], rgb[2], v == 0 ? 0.0 : alpha);
  }
  lut->Build();
  return lut;
}

}  // namespace repose
