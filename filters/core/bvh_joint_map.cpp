#include "bvh_joint_map.h"

#include "json_text.h"

#include "anatomy_names.h"

#include <json/json.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <memory>
#include <sstream>
#include <stdexcept>

namespace repose {
namespace {

// The CMU joints in the two conversions of the database: role, "3dsMax" name, "MotionBuilder" name.
struct CmuJoint {
  const char* role;
  const char* max3ds;
  const char* motionBuilder;
};
const CmuJoint kCmuJoints[] = {
    {"hips", "Hips", "Hips"},
    {"lowerback", "lowerback", "LowerBack"},
    {"upperback", "Chest", "Spine"},
    {"thorax", "Chest2", "Spine1"},
    {"lowerneck", "lowerneck", "Neck"},
    {"upperneck", "Neck", "Neck1"},
    {"head", "Head", "Head"},
    {"left_femur", "LeftHip", "LeftUpLeg"},
    {"left_tibia", "LeftKnee", "LeftLeg"},
    {"left_foot", "LeftAnkle", "LeftFoot"},
    {"left_collar", "LeftCollar", "LeftShoulder"},
    {"left_humerus", "LeftShoulder", "LeftArm"},
    {"left_radius", "LeftElbow", "LeftForeArm"},
    {"left_wrist", "LeftWrist", "LeftHand"},
    {"right_femur", "RightHip", "RightUpLeg"},
    {"right_tibia", "RightKnee", "RightLeg"},
    {"right_foot", "RightAnkle", "RightFoot"},
    {"right_collar", "RightCollar", "RightShoulder"},
    {"right_humerus", "RightShoulder", "RightArm"},
    {"right_radius", "RightElbow", "RightForeArm"},
    {"right_wrist", "RightWrist", "RightHand"},
};

// The CMU role (without its side) that drives a limb or girdle joint of the vocabulary (without its
// side); "" for none.
std::string cmuLimbRole(const std::string& limb) {
  static const std::map<std::string, std::string> roles = {
      {"hip", "femur"},    {"knee", "tibia"},  {"ankle", "foot"},      {"shoulder", "humerus"},
      {"elbow", "radius"}, {"wrist", "wrist"}, {"clavicle", "collar"}, {"scapula", "collar"}};
  const auto it = roles.find(limb);
  return it == roles.end() ? "" : it->second;
}

// Spinal levels as one axis: L5 = 0 ... L1 = 4, T12 = 5 ... T1 = 16, C7 = 17 ... C1 = 23, skull = 24.
// A joint at level l moves the bones from l up, relative to the bone below.
struct Band {
  const char* role;
  double from, to;
};
const Band kCmuTrunkBands[] = {{"lowerback", 0, 5},  {"upperback", 5, 11}, {"thorax", 11, 17},
                               {"lowerneck", 17, 21}, {"upperneck", 21, 24}, {"head", 24, 25}};

struct TrunkJoint {
  int index;
  double level, topEnd;  // topEnd: where its bone ends when no trunk joint lies above it
};

// A cervical joint below the skull: a head joint above it, or vertebrae of the neck beside it.
bool neckIsCervical(const Skeleton& skeleton) {
  if (skeleton.find("head") >= 0) return true;
  for (const Joint& j : skeleton.joints)
    if (j.name.compare(0, 10, "vertebra_C") == 0) return true;
  return false;
}

bool trunkLevel(const std::string& name, bool cervicalNeck, TrunkJoint& t) {
  if (name == "spine") return t.level = 0, t.topEnd = 5, true;
  if (name == "chest") return t.level = 5, t.topEnd = 17, true;
  if (name == "neck") return cervicalNeck ? (t.level = 17, t.topEnd = 24) : (t.level = 24, t.topEnd = 25), true;
  if (name == "head") return t.level = 24, t.topEnd = 25, true;
  // vertebra_<level> of the vocabulary; sacral levels belong to the pelvis.
  const std::string prefix = "vertebra_";
  if (name.compare(0, prefix.size(), prefix) != 0 || !isStandardJointName(name)) return false;
  const char region = name[prefix.size()];
  const int n = std::stoi(name.substr(prefix.size() + 1));
  if (region == 'L') t.level = 5 - n;
  else if (region == 'T') t.level = 17 - n;
  else if (region == 'C') t.level = 24 - n;
  else return false;
  t.topEnd = t.level + 1;
  return true;
}

// The clip's name for each CMU role, in the conversion whose names it has most of.
std::map<std::string, std::string> cmuNames(const BvhMotion& motion) {
  int max3ds = 0, motionBuilder = 0;
  for (const CmuJoint& j : kCmuJoints) {
    if (std::string(j.max3ds) == j.motionBuilder) continue;
    max3ds += motion.find(j.max3ds) >= 0;
    motionBuilder += motion.find(j.motionBuilder) >= 0;
  }
  std::map<std::string, std::string> names;
  for (const CmuJoint& j : kCmuJoints) {
    const char* name = motionBuilder > max3ds ? j.motionBuilder : j.max3ds;
    if (motion.find(name) >= 0) names[j.role] = name;
  }
  return names;
}

// Trunk joints of the skeleton, lowest level first, with the CMU trunk joints' shares.
void mapTrunk(const Skeleton& skeleton, const std::map<std::string, std::string>& cmu, BvhJointMap& map) {
  const bool cervicalNeck = neckIsCervical(skeleton);
  std::vector<TrunkJoint> trunk;
  for (int j = 0; j < int(skeleton.size()); ++j) {
    TrunkJoint t{j, 0, 0};
    if (trunkLevel(skeleton.joints[j].name, cervicalNeck, t)) trunk.push_back(t);
  }
  std::stable_sort(trunk.begin(), trunk.end(), [](const TrunkJoint& a, const TrunkJoint& b) { return a.level < b.level; });
  for (std::size_t i = 0; i < trunk.size(); ++i) {
    const double from = i == 0 ? -std::numeric_limits<double>::infinity() : trunk[i].level;
    const double to = i + 1 < trunk.size() ? trunk[i + 1].level : trunk[i].topEnd;
    std::vector<BvhShare> shares;
    for (const Band& band : kCmuTrunkBands) {
      const auto name = cmu.find(band.role);
      const double overlap = std::min(to, band.to) - std::max(from, band.from);
      if (name == cmu.end() || overlap <= 1e-9) continue;
      shares.push_back({name->second, std::min(1.0, overlap / (band.to - band.from))});
    }
    if (!shares.empty()) map.shares[skeleton.joints[trunk[i].index].name] = shares;
  }
}

std::string sidePrefix(const std::string& name) {
  const BoneSide side = jointSide(name);
  return side == BoneSide::Left ? "left_" : side == BoneSide::Right ? "right_" : "";
}

}  // namespace

BvhJointMap defaultCmuJointMap(const BvhMotion& motion, const Skeleton& skeleton) {
  const std::map<std::string, std::string> cmu = cmuNames(motion);
  BvhJointMap map;
  auto follow = [&](const std::string& joint, const std::string& role) {
    const auto name = cmu.find(role);
    if (name != cmu.end() && skeleton.find(joint) >= 0 && !map.joints.count(name->second))
      map.joints[name->second] = joint;
  };
  follow("pelvis", "hips");
  for (const StandardJoint& joint : standardJoints()) {
    if (joint.region == JointRegion::Trunk) continue;
    const std::string pre = sidePrefix(joint.name), limb = std::string(joint.name).substr(pre.size());
    if (limb == "scapula" && skeleton.find(pre + "clavicle") >= 0) continue;  // the collar drives the clavicle
    follow(joint.name, pre + cmuLimbRole(limb));
  }
  mapTrunk(skeleton, cmu, map);
  if (map.empty())
    throw std::invalid_argument(
        cmu.empty() ? "the clip has none of the CMU joint names the built-in map knows (Hips, LeftUpLeg or "
                      "LeftHip, ...): give a joint map (JSON {\"BVH joint\": \"skeleton joint\", ...})"
                    : "the built-in CMU joint map matches no joint of this skeleton (it knows pelvis, spine, "
                      "chest, vertebra_*, neck, head, left_/right_ hip, knee, ankle, shoulder, elbow, wrist, clavicle, "
                      "scapula): give a joint map (JSON {\"BVH joint\": \"skeleton joint\", ...})");
  return map;
}

BvhJointMap parseJointMapJson(const std::string& text) {
  Json::Value root;
  try {
    root = parseJsonText(text, false);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("joint map: ") + e.what());
  }
  if (root.isObject() && root.isMember("map")) root = root["map"];
  if (!root.isObject())
    throw std::invalid_argument("joint map: expected an object {\"BVH joint\": \"skeleton joint\", ...}");
  BvhJointMap map;
  for (const std::string& key : root.getMemberNames()) {
    if (!root[key].isString())
      throw std::invalid_argument("joint map: the value for BVH joint '" + key + "' must be a skeleton joint name");
    map.joints[key] = root[key].asString();
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

JointMapCoverage jointMapCoverage(const Skeleton& skeleton, const BvhJointMap& map) {
  std::map<std::string, std::string> source;
  for (const auto& [bvh, joint] : map.joints) {
    if (skeleton.find(joint) < 0) throw std::invalid_argument("the joint map names skeleton joint '" + joint +
                                                              "', which the skeleton does not have");
    source[joint] = bvh;
  }
  for (const auto& [joint, shares] : map.shares) {
    if (skeleton.find(joint) < 0) throw std::invalid_argument("the joint map names skeleton joint '" + joint +
                                                              "', which the skeleton does not have");
    std::string text;
    for (const BvhShare& share : shares) {
      text += (text.empty() ? "" : " + ") + share.bvhJoint;
      if (share.fraction < 0.995) text += " " + std::to_string(int(std::lround(100 * share.fraction))) + "%";
    }
    source[joint] = text;
  }
  JointMapCoverage coverage;
  auto driven = [&](const std::string& name) { return source.count(name) != 0; };
  for (const Joint& joint : skeleton.joints) {
    if (driven(joint.name)) {
      coverage.driven.emplace_back(joint.name, source[joint.name]);
      continue;
    }
    const std::string side = sidePrefix(joint.name);
    // One shoulder girdle joint per side in the clips: the other girdle bone follows the driven one.
    const bool girdleFollows = isGirdleJoint(joint.name) && (driven(side + "clavicle") || driven(side + "scapula"));
    if ((isLimbJoint(joint.name) || isGirdleJoint(joint.name)) && !girdleFollows) {
      coverage.undrivenLimbs.push_back(joint.name);
    } else if (isStandardJointName(joint.name)) {
      coverage.following.push_back(joint.name);
    } else {
      coverage.unknownNames.push_back(joint.name);
    }
  }
  return coverage;
}

}  // namespace repose
