#include "relaxation_options.h"

#include <cmath>
#include <stdexcept>

#include "cli_options.h"
#include "corotational_fem.h"
#include "repose_pipeline.h"

namespace repose {

RelaxationChoice applyRelaxation(Pipeline& pipeline, const Options& o) {
  // Regions and continuation also serve the +fem methods of --compare.
  pipeline.setRelaxationVolume(o.get("relax-volume", "segments"));
  const std::string continuation = o.get("relax-continuation", "if-inverted");
  if (continuation != "if-inverted" && continuation != "never" && continuation != "always")
    throw UsageError("--relax-continuation must be if-inverted, never or always");
  pipeline.setRelaxationContinuation(continuation);
  const std::string strainedRegion = o.get("relax-strained-region", "first");
  if (strainedRegion != "first" && strainedRegion != "off")
    throw UsageError("--relax-strained-region must be first or off");
  pipeline.setRelaxationStrainedRegion(strainedRegion);
  const CorotationalOptions defaults;
  RelaxationChoice choice;
  choice.poisson = defaults.poisson;
  choice.iterations = defaults.outerIterations;
  if (!o.has("relax")) {
    if (o.has("relax-iterations") || o.has("poisson") || o.has("relax-model") ||
        ((o.has("relax-volume") || o.has("relax-continuation") || o.has("relax-strained-region")) && !o.has("compare")))
      throw UsageError("--relax-model, --relax-iterations, --relax-volume, --relax-continuation, "
                       "--relax-strained-region and --poisson need --relax");
    return choice;
  }
  const std::string model = o.get("relax-model", "fixed-corotated");
  if (model != "fixed-corotated" && model != "linear")
    throw UsageError("--relax-model must be fixed-corotated or linear");
  pipeline.setRelaxationModel(model);
  const double nu = o.number("poisson", defaults.poisson);
  const double iterations = o.number("relax-iterations", defaults.outerIterations);
  if (!(nu > -1 && nu < 0.5)) throw UsageError("--poisson must be in (-1, 0.5)");
  if (iterations < 1 || iterations != std::floor(iterations)) throw UsageError("--relax-iterations must be a whole number >= 1");
  choice.enabled = true;
  choice.poisson = nu;
  choice.iterations = static_cast<int>(iterations);
  pipeline.setRelaxation(true, choice.poisson, choice.iterations);
  return choice;
}

bool relaxationWarmStart(const Options& o) {
  const std::string relaxStart = o.get("relax-start", "previous");
  if (relaxStart != "previous" && relaxStart != "skinned") throw UsageError("--relax-start must be previous or skinned");
  if (o.has("relax-start") && !o.has("relax") && !o.has("compare"))
    throw UsageError("--relax-start needs --relax (or --compare with a +fem method)");
  return relaxStart == "previous";
}

}  // namespace repose
