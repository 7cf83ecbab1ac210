// pose.json (repose pose --pose, the GUI's saved poses): parsed; an accepted pose's rotations are
// unit quaternions and its translation finite.
#include "fuzz_input.h"
#include "pose.h"

#include <cmath>
#include <stdexcept>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  repose::Pose pose;
  try {
    pose = repose::parsePoseJson(fuzzText(data, size));
  } catch (const std::invalid_argument&) {
    return 0;
  }
  for (const auto& [joint, q] : pose.rotations)
    if (!(std::abs(q.norm() - 1.0) < 1e-6)) fuzzInvariantBroken("an accepted rotation is not a unit quaternion");
  if (!pose.translation.allFinite()) fuzzInvariantBroken("an accepted translation is not finite");
  return 0;
}
