#include "pose_quality.h"

#include <cmath>
#include <cstdio>

namespace repose {

namespace {

std::string format(const char* fmt, double a, double b = 0, double c = 0) {
  char text[256];
  std::snprintf(text, sizeof(text), fmt, a, b, c);
  return text;
}

std::string labelName(const LabelTable& table, int value) {
  const LabelInfo* l = table.find(value);
  return l ? l->name + " (label " + std::to_string(value) + ")" : "label " + std::to_string(value);
}

}  // namespace

PoseQuality poseQuality(const DeformationStats& s, const LabelTable& table, const PoseQualityLimits& limits,
                        const PosedLabelStats& labels) {
  PoseQuality q;
  const double webMl = s.stretchedVolumeMm3 / 1000.0;
  q.summary = format("body volume %.4f of rest, ", s.volumeRatio) + std::to_string(s.invertedTets) +
              format(" inverted tets, largest stretch %.1fx, %.1f ml stretched past %.0fx", s.maxStretch, webMl,
                     kWebStretch);
  // The label whose tets changed volume most.
  int worstLabel = 0;
  double worstDeviation = 0;
  for (const auto& [label, ratio] : s.labelVolumeRatio)
    if (label != 0 && std::abs(ratio - 1) > worstDeviation) worstDeviation = std::abs(ratio - 1), worstLabel = label;
  if (worstLabel != 0)
    q.summary += ", " + labelName(table, worstLabel) + format(" at %.3f of its volume", s.labelVolumeRatio.at(worstLabel));
  const double contestedMl = double(labels.contestedBoneVoxels) * labels.voxelMm3 / 1000.0;
  if (labels.voxelMm3 > 0)
    q.summary += ", " + std::to_string(labels.contestedBoneVoxels) + format(" voxels claimed by two bones (%.1f ml)", contestedMl);

  if (s.invertedTets > 0 && double(s.invertedTets) > limits.invertedFraction * double(s.tets))
    q.warnings.push_back(std::to_string(s.invertedTets) +
                         " tets turned inside out: parts collide or a joint bends past its range; the posed volume "
                         "is wrong there (--relax untangles them, or pose less far)");
  if (webMl > limits.webMl)
    q.warnings.push_back(format("%.0f ml of tissue stretched past %.0fx (largest %.0fx): parts that touched at rest "
                                "are pulled into a web; prepare the case with --contact-separation on",
                                webMl, kWebStretch, s.maxStretch));
  if (std::abs(s.volumeRatio - 1) > limits.bodyVolumeTolerance)
    q.warnings.push_back(format("the body's volume is %.3f of rest (more than %.0f %% off): the skinning squashes or "
                                "inflates tissue at the joints (--relax keeps volume)",
                                s.volumeRatio, 100 * limits.bodyVolumeTolerance));
  if (worstDeviation > limits.labelVolumeTolerance)
    q.warnings.push_back(labelName(table, worstLabel) +
                         format(" has %.3f of its rest volume (more than %.0f %% off)", s.labelVolumeRatio.at(worstLabel),
                                100 * limits.labelVolumeTolerance));
  if (contestedMl > limits.contestedBoneMl)
    q.warnings.push_back(format("two bones overlap in %.0f voxels (%.1f ml): a joint bends past its range or parts "
                                "collide; where they overlap the posed volume keeps one bone's label",
                                double(labels.contestedBoneVoxels), contestedMl));
  return q;
}

}  // namespace repose
