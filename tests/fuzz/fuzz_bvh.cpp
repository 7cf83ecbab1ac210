// BVH motion files (repose animate --bvh): parsed, and an accepted clip used as animate first uses
// it: its units inferred, its rest pose and first and last frames posed.
#include "bvh.h"
#include "fuzz_input.h"

#include <stdexcept>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  repose::BvhMotion motion;
  try {
    motion = repose::parseBvh(fuzzText(data, size), "fuzz.bvh");
  } catch (const std::invalid_argument&) {
    return 0;  // rejected with its one-line message
  }
  if (motion.joints.empty()) fuzzInvariantBroken("a clip without joints was accepted");
  if (motion.frameCount != int(motion.frames.rows())) fuzzInvariantBroken("frame count differs from the rows");
  if (!motion.frames.allFinite()) fuzzInvariantBroken("a non-finite channel value was accepted");
  try {
    repose::inferBvhUnits(motion);
  } catch (const std::invalid_argument&) {
  }
  repose::bvhRestPose(motion);
  if (motion.frameCount > 0) {
    repose::bvhGlobalPose(motion, 0);
    repose::bvhGlobalPose(motion, motion.frameCount - 1);
  }
  return 0;
}
