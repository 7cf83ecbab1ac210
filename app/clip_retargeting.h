#pragma once
// A BVH clip retargeted onto a case's skeleton, as `repose animate` reports it.
#include <memory>
#include <string>

#include "bvh.h"
#include "retarget.h"
#include "skeleton.h"

namespace repose {

class Options;

/// The clip retargeted onto the skeleton by --map (default: the CMU names), --mode, --reference-frame,
/// --no-root-motion and --unit-mm. Prints the clip's units and which joints it drives, and warns
/// (or with --strict throws std::runtime_error naming bvhPath) when recognised limb joints are left
/// undriven or joint names are unknown. A bad map or clip throws std::runtime_error naming its file.
std::unique_ptr<BvhRetargeter> retargetClip(const Options& o, const Skeleton& skeleton, const BvhMotion& motion,
                                            const std::string& bvhPath);

}  // namespace repose
