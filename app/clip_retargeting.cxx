#include "clip_retargeting.h"

#include <cstdio>
#include <iostream>
#include <stdexcept>
#include <vector>

#include "cli_options.h"

namespace repose {
namespace {

std::string joinNames(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

}  // namespace

std::unique_ptr<BvhRetargeter> retargetClip(const Options& o, const Skeleton& skeleton, const BvhMotion& motion,
                                            const std::string& bvhPath) {
  BvhJointMap map;
  JointMapCoverage coverage;
  try {
    map = o.has("map") ? readJointMapFile(o.get("map")) : defaultCmuJointMap(motion, skeleton);
    coverage = jointMapCoverage(skeleton, map);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error((o.has("map") ? o.get("map") + ": " : bvhPath + ": ") + e.what());
  }
  RetargetOptions options;
  options.mode = parseRetargetMode(o.get("mode", "direction"));
  options.referenceFrame = static_cast<int>(o.number("reference-frame", 0));
  options.translateRoot = !o.has("no-root-motion");
  options.unitScaleMm = o.number("unit-mm", 0);
  std::unique_ptr<BvhRetargeter> retargeter;
  try {
    retargeter = std::make_unique<BvhRetargeter>(motion, skeleton, map, options);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(bvhPath + ": " + e.what());
  }
  const BvhUnits& units = retargeter->units();
  char line[256];
  if (o.has("unit-mm"))
    std::snprintf(line, sizeof(line), "%g mm per unit (--unit-mm)", units.mmPerUnit);
  else
    std::snprintf(line, sizeof(line), "%s (%s %.1f units), %.*f mm per unit; --unit-mm overrides", units.name.c_str(),
                  units.measure.c_str(), units.measuredUnits, units.mmPerUnit < 100 ? 2 : 0, units.mmPerUnit);
  std::cout << "animate: BVH units: " << line << "\n";
  std::string driven;
  for (const auto& [joint, source] : coverage.driven) driven += (driven.empty() ? "" : ", ") + joint + " <- " + source;
  std::cout << "animate: the clip drives " << coverage.driven.size() << " of " << skeleton.size()
            << " joints: " << driven << "\n";
  if (!coverage.following.empty())
    std::cout << "animate: not driven, following their parents: " << joinNames(coverage.following) << "\n";
  std::vector<std::string> problems;
  if (!coverage.undrivenLimbs.empty())
    problems.push_back("the clip drives none of the limb joints " + joinNames(coverage.undrivenLimbs));
  if (!coverage.unknownNames.empty() && !o.has("map"))
    problems.push_back("the built-in map does not know the joint names " + joinNames(coverage.unknownNames) +
                       " (standard names: see --help)");
  for (const std::string& problem : problems) {
    if (o.has("strict"))
      throw std::runtime_error(bvhPath + ": " + problem + " (--strict): map them with --map FILE, JSON " +
                               "{\"BVH joint\": \"skeleton joint\"}");
    std::cout << "animate: warning: " << problem << ": they only follow their parents; map them with --map FILE "
              << "(JSON {\"BVH joint\": \"skeleton joint\"}), or --strict to stop here\n";
  }
  return retargeter;
}

}  // namespace repose
