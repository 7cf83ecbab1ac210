#include "retarget.h"

#include <json/json.h>

#include <cmath>
#include <fstream>
#include <memory>
#include <sstream>
#include <stdexcept>

namespace repose {
namespace {

[[noreturn]] void fail(const std::string& message) { throw std::invalid_argument("retarget: " + message); }

// Orthonormal frame whose first column is `primary` and whose third is `up` made orthogonal to it.
bool frameFrom(const Eigen::Vector3d& primary, const Eigen::Vector3d& up, Eigen::Matrix3d& frame) {
  const Eigen::Vector3d e1 = primary.normalized();
  Eigen::Vector3d e3 = up - up.dot(e1) * e1;
  if (e3.norm() < 1e-6 * up.norm()) return false;
  e3.normalize();
  frame.col(0) = e1;
  frame.col(1) = e3.cross(e1);
  frame.col(2) = e3;
  return true;
}

// Minimal rotation taking direction a onto direction b (any perpendicular axis when opposite).
Eigen::Matrix3d minimalRotation(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return Eigen::Quaterniond::FromTwoVectors(a, b).toRotationMatrix();
}

constexpr double kTiny = 1e-9;

}  // namespace

RetargetMode parseRetargetMode(const std::string& name) {
  if (name == "direction") return RetargetMode::Direction;
  if (name == "relative") return RetargetMode::Relative;
  throw std::invalid_argument("unknown retarget mode '" + name + "' (expected direction or relative)");
}

Eigen::Matrix3d bvhToLps() {
  Eigen::Matrix3d m;
  m << 1, 0, 0,  //
      0, 0, -1,  //
      0, 1, 0;
  return m;
}

const std::vector<std::pair<std::string, std::vector<std::string>>>& cmuJointCandidates() {
  // 3dsMax conversion: LeftHip/LeftKnee/LeftAnkle, lowerback, LeftShoulder (upper arm)/LeftElbow/LeftWrist.
  // MotionBuilder conversion: LeftUpLeg/LeftLeg/LeftFoot, LowerBack, LeftArm/LeftForeArm/LeftHand.
  // The scan's neck joint (skull base) rotates the skull: the BVH Head joint.
  static const std::vector<std::pair<std::string, std::vector<std::string>>> table = {
      {"pelvis", {"Hips"}},
      {"spine", {"LowerBack", "lowerback", "Spine"}},
      {"neck", {"Head", "Neck1", "Neck"}},
      {"left_hip", {"LeftUpLeg", "LeftHip"}},
      {"left_knee", {"LeftLeg", "LeftKnee"}},
      {"left_ankle", {"LeftFoot", "LeftAnkle"}},
      {"right_hip", {"RightUpLeg", "RightHip"}},
      {"right_knee", {"RightLeg", "RightKnee"}},
      {"right_ankle", {"RightFoot", "RightAnkle"}},
      {"left_shoulder", {"LeftArm", "LeftShoulder"}},
      {"left_elbow", {"LeftForeArm", "LeftElbow"}},
      {"left_wrist", {"LeftHand", "LeftWrist"}},
      {"right_shoulder", {"RightArm", "RightShoulder"}},
      {"right_elbow", {"RightForeArm", "RightElbow"}},
      {"right_wrist", {"RightHand", "RightWrist"}},
  };
  return table;
}

BvhJointMap defaultCmuJointMap(const BvhMotion& motion, const Skeleton& skeleton) {
  BvhJointMap map;
  for (const auto& entry : cmuJointCandidates()) {
    if (skeleton.find(entry.first) < 0) continue;
    for (const std::string& candidate : entry.second)
      if (motion.find(candidate) >= 0) {
        map[candidate] = entry.first;
        break;
      }
  }
  if (map.empty())
    fail("the built-in CMU joint map matches no joint of this clip and skeleton: give a joint map "
         "(JSON {\"BVH joint\": \"skeleton joint\", ...})");
  return map;
}

BvhJointMap parseJointMapJson(const std::string& text) {
  Json::CharReaderBuilder builder;
  builder["collectComments"] = false;
  std::unique_ptr<Json::CharReader> reader(builder.newCharReader());
  Json::Value root;
  std::string errors;
  if (!reader->parse(text.data(), text.data() + text.size(), &root, &errors))
    throw std::invalid_argument("joint map: malformed JSON: " + errors);
  if (root.isObject() && root.isMember("map")) root = root["map"];
  if (!root.isObject())
    throw std::invalid_argument("joint map: expected an object {\"BVH joint\": \"skeleton joint\", ...}");
  BvhJointMap map;
  for (const std::string& key : root.getMemberNames()) {
    if (!root[key].isString())
      throw std::invalid_argument("joint map: the value for BVH joint '" + key + "' must be a skeleton joint name");
    map[key] = root[key].asString();
  }
  return map;
}

BvhJointMap readJointMapFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::invalid_argument("cannot open joint map file '" + path + "'");
  std::ostringstream buffer;
  buffer << in.rdbuf();
  try {
    return parseJointMapJson(buffer.str());
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(path + ": " + e.what());
  }
}

BvhRetargeter::BvhRetargeter(const BvhMotion& motion, const Skeleton& skeleton, const BvhJointMap& map,
                             const RetargetOptions& options)
    : motion_(motion), skeleton_(skeleton), options_(options) {
  if (!(options.unitScaleMm > 0) || !std::isfinite(options.unitScaleMm))
    fail("unitScaleMm must be a positive number of millimetres per BVH unit");
  if (motion.joints.empty()) fail("the BVH clip has no joints");
  if (motion.frameCount <= 0) fail("the BVH clip has no frames");
  if (options.referenceFrame < 0 || options.referenceFrame >= motion.frameCount)
    fail("reference frame " + std::to_string(options.referenceFrame) + " is out of range (the clip has " +
         std::to_string(motion.frameCount) + " frames)");
  const int n = int(skeleton.size());
  for (int j = 0; j < n; ++j)
    if (skeleton.joints[j].parent >= j) fail("skeleton joints must be stored parents first");

  bvhOf_.assign(n, -1);
  for (const auto& entry : map) {
    const int b = motion.find(entry.first);
    if (b < 0) fail("the joint map names BVH joint '" + entry.first + "', which the clip does not have");
    const int s = skeleton.find(entry.second);
    if (s < 0) fail("the joint map names skeleton joint '" + entry.second + "', which the skeleton does not have");
    if (bvhOf_[s] >= 0)
      fail("the joint map maps both '" + motion.joints[bvhOf_[s]].name + "' and '" + entry.first +
           "' onto skeleton joint '" + entry.second + "'");
    bvhOf_[s] = b;
  }
  if (map.empty()) fail("the joint map is empty");

  std::vector<std::vector<int>> children(n);
  for (int j = 0; j < n; ++j)
    if (skeleton.joints[j].parent >= 0) children[skeleton.joints[j].parent].push_back(j);
  mappedAncestor_.assign(n, -1);
  for (int j = 0; j < n; ++j) {
    const int p = skeleton.joints[j].parent;
    if (p >= 0) mappedAncestor_[j] = bvhOf_[p] >= 0 ? p : mappedAncestor_[p];
  }

  const Eigen::Matrix3d M = bvhToLps();
  const std::vector<Eigen::Isometry3d> rest = bvhRestPose(motion);
  auto bvhPos = [&](int skeletonJoint) -> Eigen::Vector3d { return M * rest[bvhOf_[skeletonJoint]].translation(); };
  auto centre = [&](int j) -> const Eigen::Vector3d& { return skeleton.joints[j].center; };

  mainChild_.assign(n, -1);
  lateralLeft_.assign(n, -1);
  lateralRight_.assign(n, -1);
  restDirBvh_.assign(n, Eigen::Vector3d::Zero());
  restAlign_.assign(n, Eigen::Matrix3d::Identity());
  for (int j = 0; j < n; ++j) {
    if (bvhOf_[j] < 0) continue;
    // Nearest mapped descendants, reached through unmapped joints.
    std::vector<int> candidates, todo(children[j].rbegin(), children[j].rend());
    while (!todo.empty()) {
      const int k = todo.back();
      todo.pop_back();
      if (bvhOf_[k] >= 0) {
        candidates.push_back(k);
      } else {
        todo.insert(todo.end(), children[k].rbegin(), children[k].rend());
      }
    }
    if (candidates.empty()) continue;  // leaf

    if (mappedAncestor_[j] < 0 && candidates.size() >= 2) {
      // Topmost mapped joint (the pelvis): align the left-right axis between its outermost children.
      int left = candidates[0], right = candidates[0];
      for (int k : candidates) {
        if (centre(k).x() > centre(left).x()) left = k;
        if (centre(k).x() < centre(right).x()) right = k;
      }
      const Eigen::Vector3d u0 = centre(left) - centre(right);
      const Eigen::Vector3d a0 = bvhPos(left) - bvhPos(right);
      Eigen::Matrix3d frameScan, frameBvh;
      const Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
      if (u0.norm() > kTiny && a0.norm() > kTiny && frameFrom(u0, up, frameScan) && frameFrom(a0, up, frameBvh)) {
        lateralLeft_[j] = left;
        lateralRight_[j] = right;
        restDirBvh_[j] = a0.normalized();
        restAlign_[j] = frameBvh * frameScan.transpose();
        continue;
      }
    }
    // Main child: the one best continuing the incoming bone (the first one for a root).
    int best = candidates[0];
    const int p = skeleton.joints[j].parent;
    if (p >= 0 && (centre(j) - centre(p)).norm() > kTiny) {
      const Eigen::Vector3d incoming = (centre(j) - centre(p)).normalized();
      double bestScore = -2;
      for (int k : candidates) {
        const Eigen::Vector3d d = centre(k) - centre(j);
        if (d.norm() <= kTiny) continue;
        const double score = d.normalized().dot(incoming);
        if (score > bestScore) {
          bestScore = score;
          best = k;
        }
      }
    }
    const Eigen::Vector3d u0 = centre(best) - centre(j);
    const Eigen::Vector3d a0 = bvhPos(best) - bvhPos(j);
    if (u0.norm() <= kTiny || a0.norm() <= kTiny) continue;  // no bone to align: treated as a leaf
    mainChild_[j] = best;
    restDirBvh_[j] = a0.normalized();
    restAlign_[j] = minimalRotation(u0, a0);
  }

  const int root = 0;
  translationJoint_ = (n > 0 && bvhOf_[root] >= 0) ? bvhOf_[root] : 0;
  const std::vector<Eigen::Isometry3d> ref = bvhGlobalPose(motion, options.referenceFrame);
  refRootPosition_ = ref[translationJoint_].translation();
  refRotation_.assign(n, Eigen::Matrix3d::Identity());
  for (int j = 0; j < n; ++j)
    if (bvhOf_[j] >= 0) refRotation_[j] = M * ref[bvhOf_[j]].linear() * M.transpose();
}

Pose BvhRetargeter::poseFromGlobal(const std::vector<Eigen::Matrix3d>& global,
                                   const std::vector<Eigen::Isometry3d>& bvh) const {
  Pose pose;
  const int n = int(skeleton_.size());
  for (int j = 0; j < n; ++j) {
    if (bvhOf_[j] < 0) continue;  // identity local rotation: follows its parent
    const int p = skeleton_.joints[j].parent;
    const Eigen::Matrix3d local = p >= 0 ? Eigen::Matrix3d(global[p].transpose() * global[j]) : global[j];
    pose.rotations[skeleton_.joints[j].name] = Eigen::Quaterniond(local).normalized();
  }
  if (options_.translateRoot)
    pose.translation =
        options_.unitScaleMm * (bvhToLps() * (bvh[translationJoint_].translation() - refRootPosition_));
  return pose;
}

Pose BvhRetargeter::pose(int frame) const {
  if (frame < 0 || frame >= motion_.frameCount)
    fail("frame " + std::to_string(frame) + " is out of range (the clip has " + std::to_string(motion_.frameCount) +
         " frames)");
  const std::vector<Eigen::Isometry3d> bvh = bvhGlobalPose(motion_, frame);
  const Eigen::Matrix3d M = bvhToLps();
  const int n = int(skeleton_.size());
  std::vector<Eigen::Matrix3d> global(n, Eigen::Matrix3d::Identity());
  auto bvhRotation = [&](int j) -> Eigen::Matrix3d { return M * bvh[bvhOf_[j]].linear() * M.transpose(); };
  auto bvhPos = [&](int j) -> Eigen::Vector3d { return M * bvh[bvhOf_[j]].translation(); };

  for (int j = 0; j < n; ++j) {
    const int p = skeleton_.joints[j].parent;
    if (bvhOf_[j] < 0) {
      if (p >= 0) global[j] = global[p];
      continue;
    }
    const Eigen::Matrix3d Q = bvhRotation(j);
    if (options_.mode == RetargetMode::Relative) {
      global[j] = Q * refRotation_[j].transpose();
      continue;
    }
    Eigen::Vector3d a1 = Eigen::Vector3d::Zero();
    if (lateralLeft_[j] >= 0) {
      a1 = bvhPos(lateralLeft_[j]) - bvhPos(lateralRight_[j]);
    } else if (mainChild_[j] >= 0) {
      a1 = bvhPos(mainChild_[j]) - bvhPos(j);
    } else if (mappedAncestor_[j] >= 0) {
      // Leaf: the parent's orientation composed with the BVH rotation between the two joints,
      // expressed in the parent's BVH rest frame.
      const int a = mappedAncestor_[j];
      global[j] = global[a] * restAlign_[a].transpose() * bvhRotation(a).transpose() * Q * restAlign_[a];
      continue;
    }
    // Swing the BVH bone's rest direction, as carried by Q, onto the frame's actual bone direction
    // (they differ when unmapped BVH joints lie between), keeping Q's twist.
    const Eigen::Vector3d carried = Q * restDirBvh_[j];
    global[j] = a1.norm() > kTiny ? Eigen::Matrix3d(minimalRotation(carried, a1) * Q * restAlign_[j])
                                  : Eigen::Matrix3d(Q * restAlign_[j]);
  }
  return poseFromGlobal(global, bvh);
}

Pose retargetBvhFrame(const BvhMotion& motion, const Skeleton& skeleton, const BvhJointMap& map, int frame,
                      const RetargetOptions& options) {
  return BvhRetargeter(motion, skeleton, map, options).pose(frame);
}

}  // namespace repose
