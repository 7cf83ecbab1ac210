#include "skeleton.h"

#include "json_text.h"

#include <json/json.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <stdexcept>

namespace repose {
namespace {

[[noreturn]] void fail(const std::string& message) {
  throw std::invalid_argument("skeleton.json: " + message);
}

Json::Value parseSkeletonText(const std::string& text) {
  try {
    return parseJsonText(text, true);  // NaN/Infinity parse, so the error can say which value
  } catch (const std::invalid_argument& e) {
    fail(e.what());
  }
}

// Valid UTF-8 without control characters: a name that is not would not survive being written back
// (the JSON writer replaces invalid bytes), so a case's joints would no longer match its poses.
bool isPrintableUtf8(const std::string& text) {
  for (std::size_t i = 0; i < text.size();) {
    const unsigned char c = static_cast<unsigned char>(text[i]);
    if (c < 0x20 || c == 0x7f) return false;
    const int extra = c < 0x80 ? 0 : (c >> 5) == 0x6 ? 1 : (c >> 4) == 0xe ? 2 : (c >> 3) == 0x1e ? 3 : -1;
    if (extra < 0 || i + std::size_t(extra) >= text.size() + (extra == 0)) return false;  // lead byte, length
    std::uint32_t code = extra == 0 ? c : c & (0x3f >> extra);
    for (int k = 1; k <= extra; ++k) {
      const unsigned char d = static_cast<unsigned char>(text[i + std::size_t(k)]);
      if ((d >> 6) != 0x2) return false;
      code = (code << 6) | (d & 0x3f);
    }
    // Overlong forms, surrogates and code points beyond Unicode are not UTF-8.
    static const std::uint32_t least[4] = {0, 0x80, 0x800, 0x10000};
    if (code < least[extra] || (code >= 0xd800 && code <= 0xdfff) || code > 0x10ffff) return false;
    i += std::size_t(extra) + 1;
  }
  return true;
}

// A joint as read, before parent names are resolved.
struct RawJoint {
  Joint joint;
  std::string parentName;  // empty for the root
};

RawJoint readJoint(const Json::Value& value, Json::ArrayIndex index) {
  RawJoint raw;
  if (!value.isObject()) fail("joint #" + std::to_string(index) + " is not an object");
  if (!value.isMember("name") || !value["name"].isString() || value["name"].asString().empty())
    fail("joint #" + std::to_string(index) + " has no \"name\" string");
  raw.joint.name = value["name"].asString();
  const std::string& name = raw.joint.name;
  if (!isPrintableUtf8(name))
    fail("joint #" + std::to_string(index) + "'s name is not text (invalid UTF-8 or a control character)");

  const Json::Value& parent = value["parent"];  // null when absent
  if (!parent.isNull()) {
    if (!parent.isString()) fail("joint '" + name + "': \"parent\" must be a joint name or null");
    raw.parentName = parent.asString();
    if (raw.parentName.empty()) fail("joint '" + name + "': \"parent\" is an empty name");
  }

  const Json::Value& center = value["center"];
  if (!center.isArray() || center.size() != 3)
    fail("joint '" + name + "': \"center\" must be an array of 3 numbers [x, y, z]");
  for (Json::ArrayIndex i = 0; i < 3; ++i) {
    if (!center[i].isNumeric())
      fail("joint '" + name + "': \"center\" must be an array of 3 numbers [x, y, z]");
    const double c = center[i].asDouble();
    if (!std::isfinite(c)) fail("joint '" + name + "': \"center\" has a non-finite value");
    raw.joint.center[i] = c;
  }

  const Json::Value& labels = value["labels"];
  if (!labels.isNull()) {
    if (!labels.isArray()) fail("joint '" + name + "': \"labels\" must be an array of integers");
    for (const Json::Value& l : labels) {
      if (!l.isIntegral() || !l.isInt())
        fail("joint '" + name + "': \"labels\" must be an array of integers");
      // Label 0 is the background around the body (TetGen would refine its open surface forever).
      if (l.asInt() <= 0)
        fail("joint '" + name + "': label " + std::to_string(l.asInt()) +
             " is not a bone label (labels are positive; 0 is the background)");
      raw.joint.labels.push_back(l.asInt());
    }
  }
  return raw;
}

}  // namespace

int Skeleton::find(const std::string& name) const {
  for (std::size_t j = 0; j < joints.size(); ++j)
    if (joints[j].name == name) return int(j);
  return -1;
}

Skeleton parseSkeletonJson(const std::string& text) {
  const Json::Value root = parseSkeletonText(text);
  if (!root.isObject() || !root.isMember("joints") || !root["joints"].isArray())
    fail("missing \"joints\" array");
  const Json::Value& joints = root["joints"];
  if (joints.empty()) fail("\"joints\" is empty");

  std::vector<RawJoint> raw;
  std::map<std::string, int> indexOf;
  for (Json::ArrayIndex i = 0; i < joints.size(); ++i) {
    raw.push_back(readJoint(joints[i], i));
    if (!indexOf.emplace(raw.back().joint.name, int(i)).second)
      fail("duplicate joint name '" + raw.back().joint.name + "'");
  }

  // Resolve parents against the input order.
  std::vector<int> parent(raw.size(), -1);
  std::vector<std::string> roots;
  for (std::size_t i = 0; i < raw.size(); ++i) {
    if (raw[i].parentName.empty()) {
      roots.push_back(raw[i].joint.name);
      continue;
    }
    auto it = indexOf.find(raw[i].parentName);
    if (it == indexOf.end())
      fail("joint '" + raw[i].joint.name + "' names unknown parent '" + raw[i].parentName + "'");
    parent[i] = it->second;
  }

  // Cycles: walk up from every joint; more than #joints steps means a loop.
  for (std::size_t i = 0; i < raw.size(); ++i) {
    int j = int(i);
    for (std::size_t steps = 0; j >= 0; ++steps) {
      if (steps > raw.size())
        fail("joint '" + raw[i].joint.name + "' is part of a parent cycle");
      j = parent[j];
    }
  }
  if (roots.empty()) fail("no root joint (one joint must have \"parent\": null)");
  if (roots.size() > 1) {
    std::string list;
    for (const auto& r : roots) list += (list.empty() ? "'" : ", '") + r + "'";
    fail("several root joints (" + list + "); exactly one joint may have \"parent\": null");
  }

  // Labels used by two joints.
  std::map<int, std::string> ownerOfLabel;
  for (const RawJoint& r : raw)
    for (int l : r.joint.labels) {
      auto [it, inserted] = ownerOfLabel.emplace(l, r.joint.name);
      if (!inserted && it->second != r.joint.name)
        fail("label " + std::to_string(l) + " is listed by joints '" + it->second + "' and '" +
             r.joint.name + "'");
    }

  // Parents first: breadth-first from the root, children in input order.
  std::vector<std::vector<int>> children(raw.size());
  int rootIndex = -1;
  for (std::size_t i = 0; i < raw.size(); ++i) {
    if (parent[i] < 0)
      rootIndex = int(i);
    else
      children[parent[i]].push_back(int(i));
  }
  std::vector<int> order{rootIndex};
  for (std::size_t q = 0; q < order.size(); ++q)
    for (int c : children[order[q]]) order.push_back(c);

  std::vector<int> newIndex(raw.size(), -1);
  for (std::size_t n = 0; n < order.size(); ++n) newIndex[order[n]] = int(n);
  Skeleton skeleton;
  skeleton.joints.reserve(raw.size());
  for (int old : order) {
    Joint j = raw[old].joint;
    j.parent = parent[old] < 0 ? -1 : newIndex[parent[old]];
    skeleton.joints.push_back(std::move(j));
  }
  return skeleton;
}

std::string skeletonToJson(const Skeleton& skeleton) {
  Json::Value root(Json::objectValue);
  Json::Value joints(Json::arrayValue);
  for (const Joint& j : skeleton.joints) {
    Json::Value v(Json::objectValue);
    v["name"] = j.name;
    if (j.parent >= 0 && std::size_t(j.parent) < skeleton.joints.size())
      v["parent"] = skeleton.joints[j.parent].name;
    else
      v["parent"] = Json::Value(Json::nullValue);
    Json::Value c(Json::arrayValue);
    for (int i = 0; i < 3; ++i) c.append(j.center[i]);
    v["center"] = c;
    Json::Value labels(Json::arrayValue);
    for (int l : j.labels) labels.append(l);
    v["labels"] = labels;
    joints.append(v);
  }
  root["joints"] = joints;
  Json::StreamWriterBuilder writer;
  writer["indentation"] = "  ";
  writer["precision"] = 17;
  return Json::writeString(writer, root) + "\n";
}

Skeleton readSkeletonFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::invalid_argument(path + ": cannot read");
  std::ostringstream text;
  text << in.rdbuf();
  try {
    return parseSkeletonJson(text.str());
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(path + ": " + e.what());
  }
}

std::vector<int> boneOfLabel(const Skeleton& skeleton, int maxLabel) {
  if (maxLabel < 0) throw std::invalid_argument("boneOfLabel: maxLabel must be >= 0");
  std::vector<int> bone(std::size_t(maxLabel) + 1, -1);
  for (std::size_t j = 0; j < skeleton.joints.size(); ++j)
    for (int l : skeleton.joints[j].labels)
      if (l >= 0 && l <= maxLabel) bone[l] = int(j);
  return bone;
}

}  // namespace repose
