#include "anatomy_names.h"

#include <cctype>
#include <map>
#include <set>

namespace repose {

namespace {

bool isLower(char c) { return std::islower(static_cast<unsigned char>(c)) != 0; }
bool isUpper(char c) { return std::isupper(static_cast<unsigned char>(c)) != 0; }
bool isDigit(char c) { return std::isdigit(static_cast<unsigned char>(c)) != 0; }
bool isAlpha(char c) { return std::isalpha(static_cast<unsigned char>(c)) != 0; }

// Lower-case words of a name: split at non-alphanumerics, at camelCase humps (LFemur -> l femur,
// femurL -> femur l) and between a word and a number (rib3 -> rib 3; C7 and T12 stay whole).
std::vector<std::string> words(const std::string& name) {
  std::vector<std::string> out;
  std::string w;
  auto flush = [&] {
    if (!w.empty()) out.push_back(w);
    w.clear();
  };
  for (std::size_t i = 0; i < name.size(); ++i) {
    const char c = name[i];
    if (!isAlpha(c) && !isDigit(c)) {
      flush();
      continue;
    }
    if (!w.empty()) {
      const char p = name[i - 1];
      const bool hump = (isLower(p) && isUpper(c)) ||
                        (isUpper(p) && isUpper(c) && i + 1 < name.size() && isLower(name[i + 1]));
      const bool number = isAlpha(p) && isDigit(c) && w.size() >= 2;
      const bool afterNumber = isDigit(p) && isAlpha(c);
      if (hump || number || afterNumber) flush();
    }
    w += char(std::tolower(static_cast<unsigned char>(c)));
  }
  flush();
  return out;
}

const std::map<std::string, BoneType>& boneWords() {
  using T = BoneType;
  static const std::map<std::string, BoneType> m = [] {
    std::map<std::string, BoneType> w;
    auto add = [&](T t, std::initializer_list<const char*> names) {
      for (const char* n : names) w[n] = t;
    };
    add(T::Skull, {"skull", "skulls", "cranium", "crania", "calvaria", "calvarium", "neurocranium", "maxilla"});
    add(T::Mandible, {"mandible", "mandibles", "mandibula", "mandibulae", "jaw", "jawbone"});
    add(T::Vertebra, {"vertebra", "vertebrae", "vertebras"});
    add(T::Spine, {"spine", "spines", "backbone"});
    add(T::Sacrum, {"sacrum", "sacral"});
    add(T::Coccyx, {"coccyx", "coccygeal", "tailbone"});
    add(T::HipBone, {"hip", "hips", "coxa", "coxae", "coxal", "innominate", "ilium", "ilia", "iliac", "ischium",
                     "pubis", "pubic", "acetabulum"});
    add(T::Pelvis, {"pelvis", "pelves"});
    add(T::Rib, {"rib", "ribs", "costa", "costae"});
    add(T::Ribcage, {"ribcage", "ribcages"});
    add(T::Sternum, {"sternum", "sterna", "manubrium", "xiphoid", "breastbone"});
    add(T::Clavicle, {"clavicle", "clavicles", "clavicula", "claviculae", "collarbone"});
    add(T::Scapula, {"scapula", "scapulae", "scapulas", "shoulderblade"});
    add(T::Humerus, {"humerus", "humeri", "humeral"});
    add(T::Radius, {"radius", "radii"});
    add(T::Ulna, {"ulna", "ulnae", "ulnas"});
    add(T::Forearm, {"forearm", "forearms", "antebrachium"});
    add(T::Hand, {"hand", "hands", "carpal", "carpals", "carpus", "carpi", "metacarpal", "metacarpals", "metacarpus",
                  "metacarpi", "wrist", "wrists", "scaphoid", "lunate", "triquetrum", "pisiform", "trapezium",
                  "capitate", "hamate", "finger", "fingers", "thumb", "manus"});
    add(T::Femur, {"femur", "femurs", "femora", "femoral", "thighbone"});
    add(T::Patella, {"patella", "patellae", "patellas", "kneecap"});
    add(T::Tibia, {"tibia", "tibiae", "tibias", "shinbone"});
    add(T::Fibula, {"fibula", "fibulae", "fibulas"});
    add(T::Foot, {"foot", "feet", "tarsal", "tarsals", "tarsus", "tarsi", "metatarsal", "metatarsals", "metatarsus",
                  "metatarsi", "talus", "tali", "calcaneus", "calcanei", "calcaneum", "navicular", "cuboid",
                  "cuneiform", "cuneiforms", "ankle", "ankles", "toe", "toes", "hallux", "pedis"});
    return w;
  }();
  return m;
}

// Words that make a name soft tissue even when it mentions a bone (iliac_artery, spinal_cord).
bool isSoftWord(const std::string& w) {
  static const std::set<std::string> soft = {
      "artery", "arteries", "arterial", "vein",   "veins",    "vena",   "venae",    "venous",  "vessel",
      "vessels", "muscle",  "muscles",  "nerve",  "nerves",   "cord",   "canal",    "ligament", "ligaments",
      "tendon",  "tendons", "gland",    "glands", "lymph",    "skin",   "fat",      "renal",   "kidney",
      "disc",    "disk",    "discs",    "meniscus", "menisci", "bursa", "capsule",  "synovial", "cartilage",
      "cartilages", "plexus", "fascia"};
  return soft.count(w) != 0;
}

BoneSide sideWord(const std::string& w) {
  if (w == "left" || w == "l" || w == "lt" || w == "sinister" || w == "sinistra" || w == "sin") return BoneSide::Left;
  if (w == "right" || w == "r" || w == "rt" || w == "dexter" || w == "dextra" || w == "dex") return BoneSide::Right;
  return BoneSide::None;
}

// "L4" for "l4" when it names a vertebra level, else "".
std::string levelOf(const std::string& w) {
  if (w.size() < 2 || w.size() > 3 || !isDigit(w[1]) || (w.size() == 3 && !isDigit(w[2]))) return "";
  const int n = std::stoi(w.substr(1));
  const int most = w[0] == 'c' ? 7 : w[0] == 't' ? 12 : w[0] == 'l' ? 5 : w[0] == 's' ? 5 : 0;
  if (n < 1 || n > most) return "";
  return std::string(1, char(std::toupper(static_cast<unsigned char>(w[0])))) + w.substr(1);
}

BoneType typeOfWord(const std::string& w) {
  const auto& m = boneWords();
  const auto it = m.find(w);
  return it == m.end() ? BoneType::Unknown : it->second;
}

}  // namespace

BoneName recogniseBone(const std::string& labelName) {
  BoneName b;
  std::vector<std::string> ws = words(labelName);
  bool costal = false, cartilage = false, cage = false, onlyLevels = !ws.empty();
  std::string region, number;
  for (const std::string& w : ws) {
    costal = costal || w == "costal";
    cartilage = cartilage || w == "cartilage" || w == "cartilages";
    cage = cage || w == "cage";
    if (w == "cervical" || w == "thoracic" || w == "dorsal" || w == "lumbar") region = w;
  }
  if (costal && cartilage) return {BoneType::CostalCartilage, BoneSide::None, ""};
  for (std::string& w : ws) {
    if (isSoftWord(w)) return {};
    if (const BoneSide s = sideWord(w); s != BoneSide::None) {
      b.side = s;
      continue;
    }
    const std::string level = levelOf(w);
    if (!level.empty()) {
      b.level = level;
      continue;
    }
    onlyLevels = false;
    if (isDigit(w[0])) {
      if (number.empty()) number = w;
      continue;
    }
    BoneType t = typeOfWord(w);
    // A side glued on: lfemur, rhumerus, leftfemur.
    for (const char* prefix : {"left", "right", "l", "r"}) {
      const std::string p = prefix;
      if (t != BoneType::Unknown || w.size() <= p.size() + 2 || w.compare(0, p.size(), p) != 0) continue;
      const BoneType glued = typeOfWord(w.substr(p.size()));
      if (glued != BoneType::Unknown) {
        t = glued;
        b.side = sideWord(p);
      }
    }
    if (b.type == BoneType::Unknown) b.type = t;
  }
  if (b.type == BoneType::Rib && cage) b.type = BoneType::Ribcage;
  if (b.type == BoneType::Unknown && onlyLevels && !b.level.empty()) b.type = BoneType::Vertebra;
  if (b.type == BoneType::Spine || (b.type == BoneType::Vertebra && b.level.empty())) {
    b.type = region == "cervical"                        ? BoneType::CervicalSpine
             : region == "thoracic" || region == "dorsal" ? BoneType::ThoracicSpine
             : region == "lumbar"                        ? BoneType::LumbarSpine
             : b.level.empty()                           ? BoneType::Spine
                                                         : BoneType::Vertebra;
  }
  if (b.type == BoneType::Rib && !number.empty() && number.size() <= 2 && std::stoi(number) >= 1 &&
      std::stoi(number) <= 12)
    b.level = number;  // rib_left_7: the rib of T7
  else if (b.type != BoneType::Vertebra)
    b.level.clear();
  if (isMidlineBone(b.type)) b.side = BoneSide::None;
  return b;
}

bool namesBone(const std::string& labelName) {
  const BoneName b = recogniseBone(labelName);
  if (b.known()) return b.type != BoneType::CostalCartilage;
  static const std::set<std::string> generic = {"bone",     "bones",  "skeleton", "skeletal", "osseous",
                                                "phalanges", "phalanx", "ossicle", "ossicles"};
  bool bone = false;
  for (const std::string& w : words(labelName)) {
    if (isSoftWord(w)) return false;
    bone = bone || generic.count(w) != 0;
  }
  return bone;
}

const char* boneTypeName(BoneType type) {
  switch (type) {
    case BoneType::Unknown: return "unknown bone";
    case BoneType::Skull: return "skull";
    case BoneType::Mandible: return "mandible";
    case BoneType::Vertebra: return "vertebra";
    case BoneType::CervicalSpine: return "cervical spine";
    case BoneType::ThoracicSpine: return "thoracic spine";
    case BoneType::LumbarSpine: return "lumbar spine";
    case BoneType::Spine: return "spine";
    case BoneType::Sacrum: return "sacrum";
    case BoneType::Coccyx: return "coccyx";
    case BoneType::HipBone: return "hip bone";
    case BoneType::Pelvis: return "pelvis";
    case BoneType::Rib: return "rib";
    case BoneType::Ribcage: return "ribcage";
    case BoneType::Sternum: return "sternum";
    case BoneType::CostalCartilage: return "costal cartilage";
    case BoneType::Clavicle: return "clavicle";
    case BoneType::Scapula: return "scapula";
    case BoneType::Humerus: return "humerus";
    case BoneType::Radius: return "radius";
    case BoneType::Ulna: return "ulna";
    case BoneType::Forearm: return "forearm";
    case BoneType::Hand: return "hand";
    case BoneType::Femur: return "femur";
    case BoneType::Patella: return "patella";
    case BoneType::Tibia: return "tibia";
    case BoneType::Fibula: return "fibula";
    case BoneType::Foot: return "foot";
  }
  return "unknown bone";
}

bool isMidlineBone(BoneType t) {
  switch (t) {
    case BoneType::Skull: case BoneType::Mandible: case BoneType::Vertebra: case BoneType::CervicalSpine:
    case BoneType::ThoracicSpine: case BoneType::LumbarSpine: case BoneType::Spine: case BoneType::Sacrum:
    case BoneType::Coccyx: case BoneType::Pelvis: case BoneType::Ribcage: case BoneType::Sternum:
    case BoneType::CostalCartilage:
      return true;
    default:
      return false;
  }
}

bool isPairedBone(BoneType t) { return t != BoneType::Unknown && !isMidlineBone(t); }

const std::vector<StandardJoint>& standardJoints() {
  using R = JointRegion;
  static const std::vector<StandardJoint> joints = {
      {"pelvis", "hip bones, sacrum and coccyx (the root)", R::Trunk},
      {"spine", "the lowest vertebra (or spine label) above the pelvis", R::Trunk},
      {"chest", "a thoracic spine labelled as one bone", R::Trunk},
      {"neck", "the lowest cervical vertebra (or cervical spine); the skull when no cervical bone is below it",
       R::Trunk},
      {"head", "the skull, above a neck joint", R::Trunk},
      {"jaw", "the mandible", R::Trunk},
      {"left_clavicle", "clavicle", R::Girdle},      {"left_scapula", "scapula", R::Girdle},
      {"right_clavicle", "clavicle", R::Girdle},     {"right_scapula", "scapula", R::Girdle},
      {"left_shoulder", "humerus", R::Limb},         {"left_elbow", "radius and ulna", R::Limb},
      {"left_wrist", "hand bones", R::Limb},         {"left_hip", "femur and patella", R::Limb},
      {"left_knee", "tibia and fibula", R::Limb},    {"left_ankle", "foot bones", R::Limb},
      {"right_shoulder", "humerus", R::Limb},        {"right_elbow", "radius and ulna", R::Limb},
      {"right_wrist", "hand bones", R::Limb},        {"right_hip", "femur and patella", R::Limb},
      {"right_knee", "tibia and fibula", R::Limb},   {"right_ankle", "foot bones", R::Limb},
  };
  return joints;
}

bool isStandardJointName(const std::string& name) {
  for (const StandardJoint& j : standardJoints())
    if (name == j.name) return true;
  const std::string prefix = "vertebra_";
  if (name.compare(0, prefix.size(), prefix) != 0) return false;
  std::string level = name.substr(prefix.size());
  if (level.empty() || !isUpper(level[0])) return false;
  level[0] = char(std::tolower(static_cast<unsigned char>(level[0])));
  return levelOf(level) == name.substr(prefix.size());
}

namespace {
bool inRegion(const std::string& name, JointRegion region) {
  for (const StandardJoint& j : standardJoints())
    if (name == j.name) return j.region == region;
  return false;
}
}  // namespace

bool isLimbJoint(const std::string& name) { return inRegion(name, JointRegion::Limb); }
bool isGirdleJoint(const std::string& name) { return inRegion(name, JointRegion::Girdle); }

BoneSide jointSide(const std::string& name) {
  if (name.compare(0, 5, "left_") == 0) return BoneSide::Left;
  if (name.compare(0, 6, "right_") == 0) return BoneSide::Right;
  return BoneSide::None;
}

std::string mirrorJointName(const std::string& name) {
  switch (jointSide(name)) {
    case BoneSide::Left: return "right_" + name.substr(5);
    case BoneSide::Right: return "left_" + name.substr(6);
    default: return name;
  }
}

std::string jointNameOf(BoneType type, BoneSide side, const std::string& level) {
  const std::string pre = side == BoneSide::Left ? "left_" : side == BoneSide::Right ? "right_" : "";
  auto sided = [&](const char* joint) { return pre.empty() ? std::string() : pre + joint; };
  switch (type) {
    case BoneType::Skull: return "neck";
    case BoneType::Mandible: return "jaw";
    case BoneType::Vertebra:
      return level.empty() ? "spine" : level[0] == 'S' ? "pelvis" : "vertebra_" + level;
    case BoneType::CervicalSpine: return "neck";
    case BoneType::ThoracicSpine: return "chest";
    case BoneType::LumbarSpine: case BoneType::Spine: return "spine";
    case BoneType::Sacrum: case BoneType::Coccyx: case BoneType::HipBone: case BoneType::Pelvis: return "pelvis";
    case BoneType::Clavicle: return sided("clavicle");
    case BoneType::Scapula: return sided("scapula");
    case BoneType::Humerus: return sided("shoulder");
    case BoneType::Radius: case BoneType::Ulna: case BoneType::Forearm: return sided("elbow");
    case BoneType::Hand: return sided("wrist");
    case BoneType::Femur: return sided("hip");
    case BoneType::Tibia: case BoneType::Fibula: return sided("knee");
    case BoneType::Foot: return sided("ankle");
    default: return "";
  }
}

std::string standardJointName(const std::string& labelName) {
  const BoneName b = recogniseBone(labelName);
  return jointNameOf(b.type, b.side, b.level);
}

}  // namespace repose
