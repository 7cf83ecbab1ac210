#include "relaxation_options.h"

#include <cmath>
#include <stdexcept>
#include <utility>
#include <vector>

#include "cli_options.h"
#include "corotational_fem.h"
#include "repose_pipeline.h"
#include "vtkReposeCorotationalRelax.h"

namespace repose {
namespace {

using Relax = vtkReposeCorotationalRelax;

/// A --relax-* option, its word when absent and the value each word stands for (in the order
/// messages list them).
struct Setting {
  const char* option;
  const char* fallback;
  std::vector<std::pair<const char*, int>> words;
};

/// A setting whose words are the relaxation filter's (the one table the batch reads too).
Setting filterSetting(const char* option, const char* setting, const char* fallback) {
  Setting s{option, fallback, {}};
  for (int i = 0; i < Relax::GetNumberOfWords(setting); ++i)
    s.words.emplace_back(Relax::GetWord(setting, i), Relax::GetWordValue(setting, Relax::GetWord(setting, i)));
  return s;
}

const Setting kModel = filterSetting("relax-model", "model", "fixed-corotated");
const Setting kVolume = filterSetting("relax-volume", "volume", "segments");
const Setting kContinuation = filterSetting("relax-continuation", "continuation", "if-inverted");
const Setting kStrainedRegion{"relax-strained-region", "first", {{"first", 1}, {"off", 0}}};
const Setting kStart{"relax-start", "previous", {{"previous", 1}, {"skinned", 0}}};

/// "a, b or c"
std::string listed(const Setting& s, const char* lastSeparator) {
  std::string text;
  for (std::size_t i = 0; i < s.words.size(); ++i)
    text += (i == 0 ? "" : i + 1 == s.words.size() ? lastSeparator : ", ") + std::string(s.words[i].first);
  return text;
}

/// The value the setting's option stands for.
int valueOf(const Setting& s, const Options& o) {
  const std::string word = o.get(s.option, s.fallback);
  for (const auto& [name, value] : s.words)
    if (word == name) return value;
  throw UsageError("--" + std::string(s.option) + " must be " + listed(s, " or "));
}

}  // namespace

RelaxationChoice applyRelaxation(Pipeline& pipeline, const Options& o) {
  // Regions and continuation also serve the +fem methods of --compare.
  pipeline.setRelaxationVolume(static_cast<Relax::VolumeRegionsType>(valueOf(kVolume, o)));
  pipeline.setRelaxationContinuation(static_cast<Relax::ContinuationType>(valueOf(kContinuation, o)));
  pipeline.setRelaxationStrainedRegion(valueOf(kStrainedRegion, o) != 0);
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
  pipeline.setRelaxationModel(static_cast<Relax::ModelType>(valueOf(kModel, o)));
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
  const bool previous = valueOf(kStart, o) != 0;
  if (o.has("relax-start") && !o.has("relax") && !o.has("compare"))
    throw UsageError("--relax-start needs --relax (or --compare with a +fem method)");
  return previous;
}

}  // namespace repose
