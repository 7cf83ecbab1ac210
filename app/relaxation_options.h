#pragma once
// --relax and its --relax-* options: the one place their words are spelled, checked and turned into
// the settings of vtkReposeCorotationalRelax (through the pipeline).
#include <string>

namespace repose {

class Options;
class Pipeline;

/// What the fidelity report needs to switch relaxation on and off again.
struct RelaxationChoice {
  bool enabled = false;   ///< --relax
  double poisson = 0.49;  ///< --poisson (the core's default)
  int iterations = 1;     ///< --relax-iterations (the core's default)
};

/// Sets the pipeline's relaxation from --relax, --relax-model, --relax-iterations, --relax-volume,
/// --relax-continuation, --relax-strained-region and --poisson. Regions, continuation and strained
/// region also serve --compare's +fem methods without --relax. Throws UsageError for a word not among
/// a setting's choices, a number out of range, or a --relax-* option without --relax.
RelaxationChoice applyRelaxation(Pipeline& pipeline, const Options& o);

/// --relax-start: previous (each frame's solve starts from the frame before's correction: true) or
/// skinned (false). Throws UsageError for another word, or when given without --relax or --compare.
bool relaxationWarmStart(const Options& o);

}  // namespace repose
