#include "relaxation_progress_text.h"

#include "progress_line.h"

namespace repose {

std::string RelaxationProgressText::operator()(const RelaxationProgress& p) {
  switch (p.phase) {
    case RelaxationProgress::Setup:
      return "FEM set-up";
    case RelaxationProgress::Newton:
      return "Newton step " + std::to_string(p.newtonIterations + 1);
    case RelaxationProgress::Untangling:
      return "untangling inverted tets";
    case RelaxationProgress::Neighbourhood:
      return "relaxing untangled neighbourhoods";
    case RelaxationProgress::StrainedRegion:
      return "relaxing the strained region";
    case RelaxationProgress::Continuation: {
      if (!onPath_) {
        onPath_ = true;
        pathStart_ = std::chrono::steady_clock::now();
      }
      const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - pathStart_).count();
      return "fold-free continuation, step " + std::to_string(p.continuationSteps + 1) + ", " +
             fractionProgressLine("path", p.pathFraction, seconds);
    }
    case RelaxationProgress::Linear:
      return "linear solve " + std::to_string(p.outerIteration + 1);
  }
  return std::string();
}

}  // namespace repose
