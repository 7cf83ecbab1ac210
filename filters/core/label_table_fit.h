#pragma once
// Does a label table describe this volume? A table read with the wrong volume (the built-in
// TotalSegmentator names on the phantom's labels, say) still names every value, so the test is
// anatomical: bones the table puts on the midline (vertebrae, sacrum, skull, sternum) must lie near
// it, and bones it names by side must lie on that side.
#include <string>
#include <vector>

#include "image_grid.h"
#include "label_table.h"

namespace repose {

struct LabelTableFit {
  int boneLabels = 0;     ///< bone labels of the table present in the volume
  int checked = 0;        ///< of those, the ones whose name says where they lie (midline or a side)
  int misplaced = 0;      ///< ... that lie where their name says they cannot
  std::vector<std::string> examples;  ///< "sacrum (25) lies 87 mm right of the midline", ...
  /// The table fits unless at least 3 bones were checked and more than half are misplaced.
  bool fits() const { return checked < 3 || 2 * misplaced <= checked; }
  /// One line for an error message: "11 of 11 bone labels lie where their names cannot be: ...".
  std::string problem() const;
};

/// The midline is the mean x of every labelled voxel (the body; LPS +x = left). A midline bone is
/// misplaced when its centroid lies more than max(40 mm, 15 % of the body's half width) off it; a
/// bone named by side when its centroid lies more than 20 mm on the other side.
LabelTableFit checkLabelTableFit(const LabelVolume& labels, const LabelTable& table);

}  // namespace repose
