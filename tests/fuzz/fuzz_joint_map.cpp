// BVH joint maps (repose animate --map): parsed without crashing.
#include "bvh_joint_map.h"
#include "fuzz_input.h"

#include <stdexcept>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    repose::parseJointMapJson(fuzzText(data, size));
  } catch (const std::invalid_argument&) {
  }
  return 0;
}
