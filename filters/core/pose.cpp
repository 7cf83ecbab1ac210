#include "pose.h"

#include "json_text.h"

#include <json/json.h>

#include <cmath>
#include <fstream>
#include <memory>
#include <sstream>
#include <stdexcept>

namespace repose {
namespace {

[[noreturn]] void fail(const std::string& message) {
  throw std::invalid_argument("pose.json: " + message);
}

// Reads a JSON array of n finite numbers; `what` names it in errors.
template <int N>
Eigen::Matrix<double, N, 1> readVector(const Json::Value& v, const std::string& what) {
  if (!v.isArray() || v.size() != Json::ArrayIndex(N))
    fail(what + " must be an array of " + std::to_string(N) + " numbers");
  Eigen::Matrix<double, N, 1> out;
  for (int i = 0; i < N; ++i) {
    if (!v[Json::ArrayIndex(i)].isNumeric())
      fail(what + " must be an array of " + std::to_string(N) + " numbers");
    out[i] = v[Json::ArrayIndex(i)].asDouble();
    if (!std::isfinite(out[i])) fail(what + " has a non-finite value (NaN or inf)");
  }
  return out;
}

// q = [w,x,y,z] made unit. stableNorm: a plain norm overflows for components near 1e300 and the
// result is not unit.
Eigen::Quaterniond unitQuaternion(const Eigen::Vector4d& q, const std::string& where) {
  if (!q.allFinite()) fail(where + ": \"quaternion\" has a non-finite value (NaN or inf)");
  if (q.stableNorm() < 1e-12) fail(where + ": \"quaternion\" is zero");
  const Eigen::Vector4d u = q.stableNormalized();
  return Eigen::Quaterniond(u[0], u[1], u[2], u[3]);
}

Eigen::Quaterniond readRotation(const std::string& joint, const Json::Value& r) {
  const std::string where = "rotation of joint '" + joint + "'";
  if (!r.isObject()) fail(where + " must be an object with \"axis\"+\"degrees\" or \"quaternion\"");
  const bool hasAxis = r.isMember("axis") || r.isMember("degrees");
  const bool hasQuat = r.isMember("quaternion");
  if (hasAxis && hasQuat) fail(where + " has both \"axis\"/\"degrees\" and \"quaternion\"; give one");
  if (hasQuat) {
    return unitQuaternion(readVector<4>(r["quaternion"], where + ": \"quaternion\" [w,x,y,z]"), where);
  }
  if (!hasAxis) fail(where + " needs \"axis\" and \"degrees\", or \"quaternion\"");
  if (!r.isMember("axis")) fail(where + " has \"degrees\" but no \"axis\"");
  if (!r.isMember("degrees")) fail(where + " has \"axis\" but no \"degrees\"");
  const Eigen::Vector3d axis = readVector<3>(r["axis"], where + ": \"axis\"");
  const double n = axis.stableNorm();  // see "quaternion": no overflow for huge components
  if (n < 1e-12) fail(where + ": \"axis\" is zero");
  if (!r["degrees"].isNumeric()) fail(where + ": \"degrees\" must be a number");
  const double deg = r["degrees"].asDouble();
  if (!std::isfinite(deg)) fail(where + ": \"degrees\" is not finite");
  return Eigen::Quaterniond(Eigen::AngleAxisd(deg * M_PI / 180.0, axis.stableNormalized()));
}

}  // namespace

Pose parsePoseJson(const std::string& text) {
  Json::Value root;
  try {
    root = parseJsonText(text, true);  // NaN/Infinity parse, so the error can say which value
  } catch (const std::invalid_argument& e) {
    fail(e.what());
  }
  if (!root.isObject()) fail("top level must be an object {\"rotations\": {...}, \"translation\": [x,y,z]}");

  Pose pose;
  const Json::Value& rotations = root["rotations"];
  if (!rotations.isNull()) {
    if (!rotations.isObject()) fail("\"rotations\" must be an object {JOINT: rotation}");
    for (const std::string& name : rotations.getMemberNames())
      pose.rotations[name] = readRotation(name, rotations[name]);
  }
  if (root.isMember("translation"))
    pose.translation = readVector<3>(root["translation"], "\"translation\"");
  return pose;
}

// {"rotations": {JOINT: rotation(q)}, "translation": [...]} with `digits` significant digits.
template <class RotationToJson>
std::string writePose(const Pose& pose, int digits, RotationToJson rotation) {
  Json::Value root(Json::objectValue);
  Json::Value rotations(Json::objectValue);
  for (const auto& [name, q] : pose.rotations) rotations[name] = rotation(q);
  root["rotations"] = rotations;
  Json::Value t(Json::arrayValue);
  for (int i = 0; i < 3; ++i) t.append(pose.translation[i]);
  root["translation"] = t;
  Json::StreamWriterBuilder writer;
  writer["indentation"] = "  ";
  writer["precision"] = digits;
  return Json::writeString(writer, root) + "\n";
}

std::string poseToJson(const Pose& pose) {
  return writePose(pose, 17, [](const Eigen::Quaterniond& q) {
    Json::Value quat(Json::arrayValue);
    for (double c : {q.w(), q.x(), q.y(), q.z()}) quat.append(c);
    Json::Value r(Json::objectValue);
    r["quaternion"] = quat;
    return r;
  });
}

Pose canonicalPose(const Pose& pose) {
  Pose out;
  for (const auto& [joint, q] : pose.rotations)
    out.rotations[joint] =
      unitQuaternion(Eigen::Vector4d(q.w(), q.x(), q.y(), q.z()), "rotation of joint '" + joint + "'");
  if (!pose.translation.allFinite()) fail("\"translation\" has a non-finite value (NaN or inf)");
  out.translation = pose.translation;
  return out;
}

std::string poseToAxisAngleJson(const Pose& pose) {
  // Values below the printed precision are written as 0, so a turn about x reads [1, 0, 0].
  auto clean = [](double v) { return std::fabs(v) < 1e-12 ? 0.0 : v; };
  return writePose(pose, 12, [&](const Eigen::Quaterniond& q) {
    const Eigen::AngleAxisd aa(q.normalized());  // angle in [0, pi]
    const bool none = aa.angle() < 1e-15;
    Json::Value axis(Json::arrayValue);
    for (int i = 0; i < 3; ++i) axis.append(none ? double(i == 0) : clean(aa.axis()[i]));
    Json::Value r(Json::objectValue);
    r["axis"] = axis;
    r["degrees"] = none ? 0.0 : clean(aa.angle() * 180.0 / M_PI);
    return r;
  });
}

Pose readPoseFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::invalid_argument(path + ": cannot read");
  std::ostringstream text;
  text << in.rdbuf();
  try {
    return parsePoseJson(text.str());
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(path + ": " + e.what());
  }
}

void validatePose(const Pose& pose, const Skeleton& skeleton) {
  for (const auto& [name, q] : pose.rotations) {
    if (skeleton.find(name) < 0) {
      std::string known;
      for (const Joint& j : skeleton.joints) known += (known.empty() ? "" : ", ") + j.name;
      throw std::invalid_argument("pose names unknown joint '" + name + "' (skeleton joints: " +
                                  known + ")");
    }
    if (!std::isfinite(q.w()) || !std::isfinite(q.x()) || !std::isfinite(q.y()) ||
        !std::isfinite(q.z()) || q.norm() < 1e-12)
      throw std::invalid_argument("pose rotation of joint '" + name + "' is not a valid quaternion");
  }
  if (!pose.translation.allFinite())
    throw std::invalid_argument("pose translation is not finite");
  // Beyond a kilometre float32 node coordinates lose sub-millimetre precision and no body moves so far.
  if (pose.translation.cwiseAbs().maxCoeff() > kMaxTranslationMm) {
    std::ostringstream why;
    why << "pose translation (" << pose.translation.x() << ", " << pose.translation.y() << ", "
        << pose.translation.z() << ") mm is beyond " << kMaxTranslationMm << " mm (translations are in millimetres)";
    throw std::invalid_argument(why.str());
  }
}

std::vector<Eigen::Isometry3d> forwardKinematics(const Skeleton& skeleton, const Pose& pose) {
  validatePose(pose, skeleton);
  const std::size_t n = skeleton.joints.size();
  std::vector<Eigen::Isometry3d> global(n, Eigen::Isometry3d::Identity());
  for (std::size_t j = 0; j < n; ++j) {
    const Joint& joint = skeleton.joints[j];
    Eigen::Isometry3d local = Eigen::Isometry3d::Identity();
    auto it = pose.rotations.find(joint.name);
    if (it != pose.rotations.end()) {
      const Eigen::Quaterniond q = it->second.normalized();
      // T(c) R T(-c)
      local.linear() = q.toRotationMatrix();
      local.translation() = joint.center - local.linear() * joint.center;
    }
    if (joint.parent < 0) {
      global[j] = Eigen::Translation3d(pose.translation) * local;
    } else {
      if (std::size_t(joint.parent) >= j)
        throw std::invalid_argument("skeleton joint '" + joint.name +
                                    "' is not stored after its parent (parse it with parseSkeletonJson)");
      global[j] = global[joint.parent] * local;
    }
  }
  return global;
}

}  // namespace repose
