#pragma once
// Display colours of labels: bones ivory shades, other tissues from a fixed palette, skin beige.
#include <vtkSmartPointer.h>

#include "label_table.h"

class vtkLookupTable;

namespace repose {

/// Colour (0..1) of a label value; `isBone` picks the ivory family. Skin (-1 in surfaces.vtp, or a
/// table entry named "skin") is beige.
void labelColor(int value, const LabelTable& table, bool isBone, double rgb[3]);
/// Lookup table mapping values 0..maxLabel to their colours with `alpha` (0 stays transparent).
vtkSmartPointer<vtkLookupTable> labelLookupTable(int maxLabel, const LabelTable& table,
                                                 const std::vector<int>& boneLabels, double alpha);

}  // namespace repose
