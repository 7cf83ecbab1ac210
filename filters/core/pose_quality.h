#pragma once
// What a user should know about a posed mesh before trusting its volume: a one-line summary and the
// warnings to act on (tets turned inside out, tissue pulled into a web, volume lost or gained).
#include <string>
#include <vector>

#include "deformation_stats.h"
#include "label_table.h"

namespace repose {

/// Thresholds above which a pose is warned about.
struct PoseQualityLimits {
  double bodyVolumeTolerance = 0.03;  ///< |posed / rest - 1| of the body's tet volume
  double labelVolumeTolerance = 0.2;  ///< |posed / rest - 1| of one label's tets
  double webMl = 25;                  ///< ml of tissue stretched past kWebStretch
  /// Inverted tets, as a fraction of the mesh: a few in the skin's creases are harmless (0.06 % on
  /// the phantom walking); tens of thousands are parts colliding.
  double invertedFraction = 0.001;
  /// ml of posed voxels two bones' rigid motions both claim: a few voxels where cartilage-thin gaps
  /// round away are harmless; more is one bone driven into another.
  double contestedBoneMl = 5;
};

/// Figures of the posed label volume (zero when none was made).
struct PosedLabelStats {
  std::size_t contestedBoneVoxels = 0;  ///< voxels two bones' rigid motions both claim (one bone overwrote another)
  double voxelMm3 = 0;                  ///< volume of one voxel (mm^3); 0 = no posed label volume
};

struct PoseQuality {
  std::string summary;                ///< "body volume 1.004 of rest, 0 inverted tets, largest stretch 2.1x, ..."
  std::vector<std::string> warnings;  ///< each a sentence saying what is wrong and what to try
};

/// The quality of one pose from its deformation statistics; labels are named from `table` when it
/// knows them (else "label N").
PoseQuality poseQuality(const DeformationStats& stats, const LabelTable& table, const PoseQualityLimits& limits = {},
                        const PosedLabelStats& labels = {});

}  // namespace repose
