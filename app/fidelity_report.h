#pragma once
// --compare: the fidelity of several skinning and relaxation methods at the same poses
// (fidelity.csv and fidelity.png).
#include <cstdint>
#include <map>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace repose {

class AtomicOutputs;
class Options;
class Pipeline;

/// The methods of --compare: "lbs", "dqs", "lbs+fem", "dqs+fem" (none without --compare).
/// Throws UsageError for any other word or an empty list.
std::vector<std::string> parseCompare(const Options& o);

/// Fidelity of every compared method at the current pose: one CSV row each, and the volume ratios
/// for the plot. The pipeline's own method and relaxation are restored afterwards.
struct FidelityReport {
  std::vector<std::string> methods;
  std::ostringstream rows;
  std::vector<std::int32_t> labels;  // columns, fixed by the first row
  std::map<std::string, std::vector<std::pair<double, double>>> series;

  void addFrame(Pipeline& pipeline, int frame, const std::string& userMethod, bool userRelax, double nu,
                int iterations);
  /// fidelity.csv and fidelity.png (needs an X display).
  void write(AtomicOutputs& out) const;
};

}  // namespace repose
