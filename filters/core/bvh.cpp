#include "bvh.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string_view>

namespace repose {
namespace {

constexpr double kDegree = 3.14159265358979323846 / 180.0;

bool isSpace(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v'; }

bool equalsNoCase(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    char x = a[i], y = b[i];
    if (x >= 'A' && x <= 'Z') x = char(x - 'A' + 'a');
    if (y >= 'A' && y <= 'Z') y = char(y - 'A' + 'a');
    if (x != y) return false;
  }
  return true;
}

// Beyond this no channel or offset is motion (10^9 cm is 10 000 km, 10^9 degrees 3 million turns):
// it is damage, and scaled to millimetres it would overflow into infinity downstream.
constexpr double kMaxBvhMagnitude = 1e9;

// Whole token must be a finite number of sane size (from_chars: no locale, no allocation).
bool parseDouble(std::string_view token, double& value) {
  const char* b = token.data();
  const char* e = b + token.size();
  if (b != e && *b == '+') ++b;
  if (b == e) return false;
  const auto result = std::from_chars(b, e, value);
  return result.ec == std::errc() && result.ptr == e && std::isfinite(value) && std::fabs(value) <= kMaxBvhMagnitude;
}

bool parseInt(std::string_view token, long& value) {
  const char* b = token.data();
  const char* e = b + token.size();
  if (b != e && *b == '+') ++b;
  if (b == e) return false;
  const auto result = std::from_chars(b, e, value);
  return result.ec == std::errc() && result.ptr == e;
}

bool parseChannel(std::string_view token, BvhChannel& channel) {
  static const BvhChannel all[] = {BvhChannel::Xposition, BvhChannel::Yposition, BvhChannel::Zposition,
                                   BvhChannel::Xrotation, BvhChannel::Yrotation, BvhChannel::Zrotation};
  for (BvhChannel c : all)
    if (equalsNoCase(token, bvhChannelName(c))) {
      channel = c;
      return true;
    }
  return false;
}

struct Token {
  std::string_view text;  // empty at end of input
  int line = 0;
};

// Whitespace-separated tokens; '{' and '}' are tokens of their own. Tracks line numbers.
class Lexer {
 public:
  Lexer(const std::string& text, const std::string& source)
      : p_(text.data()), end_(text.data() + text.size()), source_(source) {}

  [[noreturn]] void fail(int line, const std::string& message) const {
    throw std::invalid_argument("BVH '" + source_ + "', line " + std::to_string(line) + ": " + message);
  }

  Token next() {
    skipSpace();
    Token t;
    t.line = line_;
    if (p_ == end_) return t;
    const char* b = p_;
    if (*p_ == '{' || *p_ == '}') {
      ++p_;
    } else {
      while (p_ != end_ && !isSpace(*p_) && *p_ != '{' && *p_ != '}') ++p_;
    }
    t.text = std::string_view(b, std::size_t(p_ - b));
    return t;
  }

  // The rest of the current line, trimmed (joint names may contain spaces).
  Token restOfLine() {
    while (p_ != end_ && (*p_ == ' ' || *p_ == '\t')) ++p_;
    Token t;
    t.line = line_;
    const char* b = p_;
    while (p_ != end_ && *p_ != '\n' && *p_ != '{') ++p_;
    const char* e = p_;
    while (e != b && isSpace(e[-1])) --e;
    t.text = std::string_view(b, std::size_t(e - b));
    return t;
  }

  // Moves past the end of the current line; fails if anything but whitespace is left on it.
  void endLine(const char* what) {
    while (p_ != end_ && *p_ != '\n') {
      if (!isSpace(*p_)) fail(line_, std::string("unexpected text after ") + what);
      ++p_;
    }
    if (p_ != end_) {
      ++p_;
      ++line_;
    }
  }

  const char* position() const { return p_; }
  const char* end() const { return end_; }
  int line() const { return line_; }

 private:
  void skipSpace() {
    while (p_ != end_ && isSpace(*p_)) {
      if (*p_ == '\n') ++line_;
      ++p_;
    }
  }

  const char* p_;
  const char* end_;
  int line_ = 1;
  const std::string& source_;
};

std::string quoted(std::string_view s) { return "'" + std::string(s) + "'"; }

void readOffset(Lexer& lex, Eigen::Vector3d& offset) {
  for (int k = 0; k < 3; ++k) {
    const Token t = lex.next();
    if (t.text.empty()) lex.fail(t.line, "file ends inside OFFSET");
    if (!parseDouble(t.text, offset[k]))
      lex.fail(t.line, "bad number " + quoted(t.text) + " in OFFSET (expected 3 finite numbers within +-1e9)");
  }
}

void readChannels(Lexer& lex, BvhJoint& joint, int& channelCount, int keywordLine) {
  if (!joint.channels.empty()) lex.fail(keywordLine, "joint " + quoted(joint.name) + " has two CHANNELS lines");
  const Token countToken = lex.next();
  long count = 0;
  if (!parseInt(countToken.text, count) || count < 0 || count > 6)
    lex.fail(countToken.line, "CHANNELS count must be an integer from 0 to 6, found " + quoted(countToken.text));
  joint.firstChannel = channelCount;
  for (long k = 0; k < count; ++k) {
    const Token t = lex.next();
    BvhChannel channel;
    if (t.text.empty()) lex.fail(t.line, "file ends inside CHANNELS");
    if (!parseChannel(t.text, channel))
      lex.fail(t.line, "unknown channel " + quoted(t.text) + " for joint " + quoted(joint.name) + " (CHANNELS " +
                           std::to_string(count) + " at line " + std::to_string(keywordLine) +
                           " expects names among Xposition Yposition Zposition Xrotation Yrotation Zrotation)");
    for (BvhChannel c : joint.channels)
      if (c == channel) lex.fail(t.line, "channel " + quoted(t.text) + " repeated for joint " + quoted(joint.name));
    joint.channels.push_back(channel);
  }
  channelCount += int(count);
}

}  // namespace

const char* bvhChannelName(BvhChannel channel) {
  switch (channel) {
    case BvhChannel::Xposition: return "Xposition";
    case BvhChannel::Yposition: return "Yposition";
    case BvhChannel::Zposition: return "Zposition";
    case BvhChannel::Xrotation: return "Xrotation";
    case BvhChannel::Yrotation: return "Yrotation";
    case BvhChannel::Zrotation: return "Zrotation";
  }
  return "?";
}

int BvhMotion::find(const std::string& name) const {
  for (std::size_t i = 0; i < joints.size(); ++i)
    if (joints[i].name == name) return int(i);
  return -1;
}

BvhMotion parseBvh(const std::string& text, const std::string& sourceName) {
  Lexer lex(text, sourceName);
  BvhMotion motion;

  Token t = lex.next();
  if (t.text != "HIERARCHY")
    lex.fail(t.line, "missing HIERARCHY: the file must start with the HIERARCHY keyword, found " +
                         (t.text.empty() ? std::string("end of file") : quoted(t.text)));
  t = lex.next();
  if (t.text != "ROOT")
    lex.fail(t.line, "missing ROOT: expected 'ROOT name' after HIERARCHY, found " +
                         (t.text.empty() ? std::string("end of file") : quoted(t.text)));

  // Open braces: joint index (or the joint owning an End Site), line of '{'.
  struct Open {
    int joint;
    bool endSite;
    int line;
  };
  std::vector<Open> stack;
  int channelCount = 0;

  auto openJoint = [&](int parent, int keywordLine) {
    const Token name = lex.restOfLine();
    if (name.text.empty()) lex.fail(keywordLine, "joint without a name");
    BvhJoint joint;
    joint.name = std::string(name.text);
    joint.parent = parent;
    joint.firstChannel = channelCount;
    motion.joints.push_back(joint);
    const Token brace = lex.next();
    if (brace.text != "{")
      lex.fail(brace.line, "expected '{' after joint " + quoted(name.text) + ", found " +
                               (brace.text.empty() ? std::string("end of file") : quoted(brace.text)));
    stack.push_back({int(motion.joints.size()) - 1, false, brace.line});
  };
  auto unclosed = [&](const Open& open) {
    return "unbalanced braces: '{' opened at line " + std::to_string(open.line) + " for " +
           (open.endSite ? "the End Site of " : "joint ") + quoted(motion.joints[open.joint].name) + " is not closed";
  };

  openJoint(-1, t.line);
  while (!stack.empty()) {
    t = lex.next();
    const Open& top = stack.back();
    if (t.text.empty()) lex.fail(t.line, unclosed(top) + " at the end of the file");
    if (t.text == "OFFSET") {
      readOffset(lex, top.endSite ? motion.joints[top.joint].endSite : motion.joints[top.joint].offset);
    } else if (t.text == "CHANNELS") {
      if (top.endSite) lex.fail(t.line, "an End Site has no CHANNELS");
      readChannels(lex, motion.joints[top.joint], channelCount, t.line);
    } else if (t.text == "JOINT") {
      if (top.endSite) lex.fail(t.line, "an End Site has no child joints");
      openJoint(top.joint, t.line);
    } else if (t.text == "End") {
      if (top.endSite) lex.fail(t.line, "nested End Site");
      const Token site = lex.next();
      if (site.text != "Site") lex.fail(site.line, "expected 'End Site', found 'End " + std::string(site.text) + "'");
      const Token brace = lex.next();
      if (brace.text != "{") lex.fail(brace.line, "expected '{' after End Site");
      motion.joints[top.joint].hasEndSite = true;
      stack.push_back({top.joint, true, brace.line});
    } else if (t.text == "}") {
      stack.pop_back();
    } else if (t.text == "MOTION") {
      lex.fail(t.line, unclosed(top) + " before MOTION");
    } else {
      lex.fail(t.line, "unexpected " + quoted(t.text) + " in joint " + quoted(motion.joints[top.joint].name) +
                           " (expected OFFSET, CHANNELS, JOINT, End Site or '}')");
    }
  }

  t = lex.next();
  if (t.text == "}") lex.fail(t.line, "unbalanced braces: '}' without a matching '{'");
  if (t.text == "ROOT") lex.fail(t.line, "several ROOT hierarchies are not supported");
  if (t.text.empty()) lex.fail(t.line, "missing MOTION section after the hierarchy (end of file)");
  if (t.text != "MOTION") lex.fail(t.line, "missing MOTION section: expected MOTION, found " + quoted(t.text));

  // "Frames: N" (also accepts "Frames : N").
  t = lex.next();
  const int framesLine = t.line;
  std::string_view framesValue;
  if (t.text == "Frames:") {
    framesValue = lex.next().text;
  } else if (t.text == "Frames") {
    if (lex.next().text != ":") lex.fail(framesLine, "expected 'Frames: N' after MOTION");
    framesValue = lex.next().text;
  } else {
    lex.fail(framesLine, "expected 'Frames: N' after MOTION, found " +
                             (t.text.empty() ? std::string("end of file") : quoted(t.text)));
  }
  long frames = 0;
  if (!parseInt(framesValue, frames) || frames < 0 || frames > 100000000)
    lex.fail(framesLine, "bad frame count " + quoted(framesValue) + " (expected a non-negative integer)");

  t = lex.next();
  const int timeLine = t.line;
  if (t.text != "Frame" || lex.next().text != "Time:")
    lex.fail(timeLine, "expected 'Frame Time: seconds' after 'Frames:'");
  const Token timeToken = lex.next();
  double frameTime = 0;
  if (!parseDouble(timeToken.text, frameTime) || frameTime <= 0)
    lex.fail(timeToken.line, "bad frame time " + quoted(timeToken.text) + " (expected a positive number of seconds)");
  lex.endLine("the frame time");

  motion.frameCount = int(frames);
  motion.frameTime = frameTime;
  const int columns = channelCount;
  // A row of c values takes at least 2c-1 characters: never allocate for rows the text cannot hold.
  const long maxRows = columns > 0 ? long(lex.end() - lex.position()) / (2 * columns - 1) + 1 : frames;
  motion.frames.resize(std::min(frames, maxRows), columns);

  // Frame rows: one per non-blank line, exactly `columns` numbers each.
  const char* p = lex.position();
  const char* end = lex.end();
  int line = lex.line();
  long row = 0;
  int lastLine = line;
  while (p != end) {
    const char* lineEnd = p;
    while (lineEnd != end && *lineEnd != '\n') ++lineEnd;
    const char* q = p;
    while (q != lineEnd && isSpace(*q)) ++q;
    if (q != lineEnd) {
      if (row >= motion.frames.rows())
        lex.fail(line, "more frame rows than 'Frames: " + std::to_string(frames) + "' at line " +
                           std::to_string(framesLine) + " declares");
      double* out = columns > 0 ? motion.frames.row(row).data() : nullptr;
      int count = 0;
      while (q != lineEnd) {
        const char* b = q;
        while (q != lineEnd && !isSpace(*q)) ++q;
        const std::string_view token(b, std::size_t(q - b));
        if (count < columns) {
          if (!parseDouble(token, out[count]))
            lex.fail(line, "bad number " + quoted(token) + " in frame " + std::to_string(row) + ", value " +
                               std::to_string(count + 1) + " (expected a finite number within +-1e9)");
        }
        ++count;
        while (q != lineEnd && isSpace(*q)) ++q;
      }
      if (count != columns)
        lex.fail(line, "frame " + std::to_string(row) + " has " + std::to_string(count) +
                           " values but the hierarchy declares " + std::to_string(columns) +
                           " channels (the channels do not add up)");
      ++row;
      lastLine = line;
    }
    p = lineEnd;
    if (p != end) {
      ++p;
      ++line;
    }
  }
  if (row != frames)
    lex.fail(lastLine, "'Frames: " + std::to_string(frames) + "' at line " + std::to_string(framesLine) +
                           " but only " + std::to_string(row) + " frame row(s) follow (the last ends at line " +
                           std::to_string(lastLine) + ")");
  return motion;
}

BvhMotion readBvhFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::invalid_argument("cannot open BVH file '" + path + "'");
  std::ostringstream buffer;
  buffer << in.rdbuf();
  return parseBvh(buffer.str(), path);
}

std::vector<Eigen::Isometry3d> bvhGlobalPose(const BvhMotion& motion, const double* channelValues) {
  const std::size_t n = motion.joints.size();
  std::vector<Eigen::Isometry3d> global(n);
  for (std::size_t j = 0; j < n; ++j) {
    const BvhJoint& joint = motion.joints[j];
    Eigen::Vector3d t = joint.offset;
    Eigen::Matrix3d r = Eigen::Matrix3d::Identity();
    for (std::size_t k = 0; k < joint.channels.size(); ++k) {
      const double v = channelValues ? channelValues[joint.firstChannel + int(k)] : 0.0;
      switch (joint.channels[k]) {
        case BvhChannel::Xposition: t.x() += v; break;
        case BvhChannel::Yposition: t.y() += v; break;
        case BvhChannel::Zposition: t.z() += v; break;
        case BvhChannel::Xrotation: r = r * Eigen::AngleAxisd(v * kDegree, Eigen::Vector3d::UnitX()); break;
        case BvhChannel::Yrotation: r = r * Eigen::AngleAxisd(v * kDegree, Eigen::Vector3d::UnitY()); break;
        case BvhChannel::Zrotation: r = r * Eigen::AngleAxisd(v * kDegree, Eigen::Vector3d::UnitZ()); break;
      }
    }
    Eigen::Isometry3d local = Eigen::Isometry3d::Identity();
    local.linear() = r;
    local.translation() = t;
    global[j] = joint.parent < 0 ? local : global[std::size_t(joint.parent)] * local;
  }
  return global;
}

std::vector<Eigen::Isometry3d> bvhGlobalPose(const BvhMotion& motion, int frame) {
  if (frame < 0 || frame >= motion.frameCount || frame >= motion.frames.rows())
    throw std::invalid_argument("BVH frame " + std::to_string(frame) + " is out of range (the clip has " +
                                std::to_string(motion.frameCount) + " frames)");
  return bvhGlobalPose(motion, motion.channelCount() > 0 ? motion.frames.row(frame).data() : nullptr);
}

std::vector<Eigen::Isometry3d> bvhRestPose(const BvhMotion& motion) { return bvhGlobalPose(motion, nullptr); }

void scaleBvhLengths(BvhMotion& motion, double factor) {
  if (!(factor > 0) || !std::isfinite(factor)) throw std::invalid_argument("BVH: a length scale must be positive");
  for (BvhJoint& joint : motion.joints) {
    joint.offset *= factor;
    joint.endSite *= factor;
    for (std::size_t k = 0; k < joint.channels.size(); ++k)
      if (joint.channels[k] == BvhChannel::Xposition || joint.channels[k] == BvhChannel::Yposition ||
          joint.channels[k] == BvhChannel::Zposition)
        motion.frames.col(joint.firstChannel + int(k)) *= factor;
  }
}

namespace {

std::string lowerCase(std::string s) {
  for (char& c : s)
    if (c >= 'A' && c <= 'Z') c = char(c - 'A' + 'a');
  return s;
}

bool contains(const std::string& s, const char* part) { return s.find(part) != std::string::npos; }

// Knee joints by name: LeftKnee, LeftLeg, mixamorig:RightLeg, l_shin, ltibia, LowerLeg_R, RCalf.
bool namesKnee(const std::string& jointName) {
  const std::string n = lowerCase(jointName);
  for (const char* part : {"knee", "shin", "calf", "tibia", "lowerleg", "lowleg", "lower_leg"})
    if (contains(n, part)) return true;
  const auto leg = n.rfind("leg");
  return leg != std::string::npos && leg + 3 == n.size() && !contains(n, "up");
}

struct LengthUnit {
  const char* name;
  double mm;
};

}  // namespace

BvhUnits inferBvhUnits(const BvhMotion& motion) {
  BvhUnits units;
  // Leg: the knee's offset (hip to knee) plus its first child's or its End Site's (knee to ankle).
  double legs = 0;
  int knees = 0;
  for (std::size_t k = 0; k < motion.joints.size(); ++k) {
    const BvhJoint& knee = motion.joints[k];
    if (knee.parent < 0 || !namesKnee(knee.name)) continue;
    double shank = knee.hasEndSite ? knee.endSite.norm() : 0.0;
    for (const BvhJoint& child : motion.joints)
      if (child.parent == int(k)) {
        shank = child.offset.norm();
        break;
      }
    if (shank <= 0 || knee.offset.norm() <= 0) continue;
    legs += knee.offset.norm() + shank;
    ++knees;
  }
  double reference = 800;  // mm, an adult's hip joint to ankle joint
  if (knees > 0) {
    units.measure = "leg length";
    units.measuredUnits = legs / knees;
  } else {
    // Rest pose extent (standing height or arm span, joint centres and End Sites): about 1.5 m.
    const std::vector<Eigen::Isometry3d> rest = bvhRestPose(motion);
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    for (std::size_t j = 0; j < rest.size(); ++j) {
      lo = lo.cwiseMin(rest[j].translation());
      hi = hi.cwiseMax(rest[j].translation());
      if (motion.joints[j].hasEndSite) {
        const Eigen::Vector3d end = rest[j] * motion.joints[j].endSite;
        lo = lo.cwiseMin(end);
        hi = hi.cwiseMax(end);
      }
    }
    units.measure = "rest pose height";
    units.measuredUnits = rest.empty() ? 0.0 : (hi - lo).maxCoeff();
    reference = 1500;
  }
  if (!(units.measuredUnits > 0) || !std::isfinite(units.measuredUnits))
    throw std::invalid_argument("BVH: the skeleton has no length (every OFFSET is zero): its units cannot be "
                                "inferred; give them (millimetres per unit)");
  static const LengthUnit kUnits[] = {{"millimetres", 1.0},   {"centimetres", 10.0},
                                      {"inches", 25.4},       {"CMU units of 1/0.45 inch", 25.4 / 0.45},
                                      {"feet", 304.8},        {"metres", 1000.0}};
  double best = std::numeric_limits<double>::infinity();
  for (const LengthUnit& u : kUnits) {
    const double misfit = std::abs(std::log(units.measuredUnits * u.mm / reference));
    if (misfit < best) {
      best = misfit;
      units.name = u.name;
      units.mmPerUnit = u.mm;
    }
  }
  return units;
}

}  // namespace repose
