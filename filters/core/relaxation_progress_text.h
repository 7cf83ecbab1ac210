#pragma once
// Where a relaxation is, in words for a progress bar: "Newton step 3", "fold-free continuation,
// step 12, path 42 %, 25 s so far, about 35 s left at this pace", ...
#include <chrono>
#include <string>

#include "corotational_fem.h"

namespace repose {

/// One per solve: it times the continuation's path from its first step, for its pace.
class RelaxationProgressText {
 public:
  /// "FEM set-up", "Newton step N", "untangling inverted tets", "relaxing untangled neighbourhoods",
  /// "relaxing the strained region", "fold-free continuation, step N, path P %, ..." or
  /// "linear solve N" (steps counted from 1).
  std::string operator()(const RelaxationProgress& p);

 private:
  bool onPath_ = false;
  std::chrono::steady_clock::time_point pathStart_;
};

}  // namespace repose
