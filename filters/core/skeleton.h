#pragma once
// The articulated skeleton: joints, each rotating the rigid bone made of its labels (skeleton.json).
#include <Eigen/Core>
#include <string>
#include <vector>

namespace repose {

struct Joint {
  std::string name;
  int parent = -1;                 ///< index into Skeleton::joints, -1 for the root
  Eigen::Vector3d center = Eigen::Vector3d::Zero();  ///< rest-pose centre of rotation (mm, LPS)
  std::vector<int> labels;         ///< label values forming this joint's rigid bone
};

/// Joints are stored parents-first (every parent index is smaller than its child's index).
/// The bone index used by weights and skinning is the joint index.
struct Skeleton {
  std::vector<Joint> joints;
  int find(const std::string& name) const;  ///< -1 when absent
  std::size_t size() const { return joints.size(); }
};

/// Parses skeleton.json text: {"joints": [{"name", "parent", "center", "labels"}]}.
/// Sorts joints parents-first. Throws std::invalid_argument on malformed JSON, missing fields,
/// duplicate names, an unknown parent, a cycle, several roots, or a label used by two joints.
Skeleton parseSkeletonJson(const std::string& text);
/// Serializes to skeleton.json text (pretty-printed).
std::string skeletonToJson(const Skeleton& skeleton);
/// Reads and parses a file; errors name the file.
Skeleton readSkeletonFile(const std::string& path);

/// label value -> bone (joint) index, -1 for labels that are not bone. Size maxLabel+1.
std::vector<int> boneOfLabel(const Skeleton& skeleton, int maxLabel);

}  // namespace repose
