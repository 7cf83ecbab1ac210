// skeleton.json (prepare --skeleton, every case): parsed; an accepted skeleton written back and
// read again gives the same joints.
#include "fuzz_input.h"
#include "skeleton.h"

#include <stdexcept>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  repose::Skeleton skeleton;
  try {
    skeleton = repose::parseSkeletonJson(fuzzText(data, size));
  } catch (const std::invalid_argument&) {
    return 0;
  }
  const repose::Skeleton again = repose::parseSkeletonJson(repose::skeletonToJson(skeleton));
  if (again.joints.size() != skeleton.joints.size()) fuzzInvariantBroken("the skeleton does not read back");
  for (std::size_t j = 0; j < skeleton.joints.size(); ++j)
    if (again.joints[j].name != skeleton.joints[j].name || again.joints[j].labels != skeleton.joints[j].labels)
      fuzzInvariantBroken("a joint does not read back");
  return 0;
}
