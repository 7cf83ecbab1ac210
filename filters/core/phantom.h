#pragma once
// A procedural human-like label volume with its skeleton: the built-in test and demo subject.
#include <string>
#include <utility>
#include <vector>

#include "image_grid.h"
#include "skeleton.h"

namespace repose {

enum class PhantomSize { Tiny, Small, Medium, Large };
/// "tiny" | "small" | "medium" | "large"; throws std::invalid_argument otherwise.
PhantomSize parsePhantomSize(const std::string& name);

/// How the phantom lies in its scan. Apart: arms and thighs clear of each other by a background
/// gap. Contact: as real scans are taken, the arms rest against the torso, the hands against the
/// thighs and the thighs touch from the crotch to the knees, with no background between them (the
/// tissues are welded in the voxels, as in a CT).
enum class PhantomRestPose { Apart, Contact };
/// "apart" | "contact"; throws std::invalid_argument otherwise.
PhantomRestPose parsePhantomRestPose(const std::string& name);

/// Label values of the phantom.
namespace phantom_label {
enum : int {
  Background = 0, Skin = 1, Fat = 2, Muscle = 3, Brain = 4, Lungs = 5, Heart = 6, Liver = 7, Kidneys = 8, Bowel = 9,
  Skull = 20, Spine = 21, Ribcage = 22, Pelvis = 23,
  FemurLeft = 24, FemurRight = 25, TibiaLeft = 26, TibiaRight = 27, FootLeft = 28, FootRight = 29,
  HumerusLeft = 30, HumerusRight = 31, ForearmLeft = 32, ForearmRight = 33, HandLeft = 34, HandRight = 35,
};
}

struct Phantom {
  LabelVolume labels;
  Skeleton skeleton;   ///< the true joint centres the phantom was built from
  std::vector<std::pair<int, std::string>> labelNames;  ///< value, name (bones and tissues)
};

/// Builds the phantom. Non-zero origin, anisotropic spacing, LPS direction diag(-1,-1,1).
Phantom makePhantom(PhantomSize size, PhantomRestPose rest = PhantomRestPose::Apart);

/// Same grid, skeleton and label names as makePhantom(size, rest) without voxelizing: labels.data is
/// empty (cheap; for pipeline information passes).
Phantom describePhantom(PhantomSize size, PhantomRestPose rest = PhantomRestPose::Apart);

}  // namespace repose
