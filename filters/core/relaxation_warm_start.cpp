#include "relaxation_warm_start.h"

namespace repose {

void RelaxationWarmStart::offer(bool wanted, std::uint64_t restKey, Eigen::Index nodeCount,
                                CorotationalOptions& options) const {
  if (wanted && options.model == CorotationalOptions::FixedCorotated && restKey_ == restKey &&
      correction_.size() > 0 && correction_.rows() == nodeCount)
    options.startCorrection = correction_;
}

void RelaxationWarmStart::forget() { correction_.resize(0, 3); }

void RelaxationWarmStart::remember(std::uint64_t restKey, const Points& input, const Points& output) {
  correction_ = output - input;
  restKey_ = restKey;
}

}  // namespace repose
