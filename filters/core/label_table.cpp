#include "label_table.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>

#include "anatomy_names.h"

namespace repose {

namespace {

std::string lower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// TotalSegmentator v2, task "total": class value i+1 is kTotalSegmentatorNames[i] (Apache-2.0).
const char* const kTotalSegmentatorNames[] = {
    "spleen", "kidney_right", "kidney_left", "gallbladder", "liver", "stomach", "pancreas",
    "adrenal_gland_right", "adrenal_gland_left", "lung_upper_lobe_left", "lung_lower_lobe_left",
    "lung_upper_lobe_right", "lung_middle_lobe_right", "lung_lower_lobe_right", "esophagus",
    "trachea", "thyroid_gland", "small_bowel", "duodenum", "colon", "urinary_bladder", "prostate",
    "kidney_cyst_left", "kidney_cyst_right", "sacrum", "vertebrae_S1", "vertebrae_L5",
    "vertebrae_L4", "vertebrae_L3", "vertebrae_L2", "vertebrae_L1", "vertebrae_T12",
    "vertebrae_T11", "vertebrae_T10", "vertebrae_T9", "vertebrae_T8", "vertebrae_T7",
    "vertebrae_T6", "vertebrae_T5", "vertebrae_T4", "vertebrae_T3", "vertebrae_T2", "vertebrae_T1",
    "vertebrae_C7", "vertebrae_C6", "vertebrae_C5", "vertebrae_C4", "vertebrae_C3", "vertebrae_C2",
    "vertebrae_C1", "heart", "aorta", "pulmonary_vein", "brachiocephalic_trunk",
    "subclavian_artery_right", "subclavian_artery_left", "common_carotid_artery_right",
    "common_carotid_artery_left", "brachiocephalic_vein_left", "brachiocephalic_vein_right",
    "atrial_appendage_left", "superior_vena_cava", "inferior_vena_cava",
    "portal_vein_and_splenic_vein", "iliac_artery_left", "iliac_artery_right", "iliac_vena_left",
    "iliac_vena_right", "humerus_left", "humerus_right", "scapula_left", "scapula_right",
    "clavicula_left", "clavicula_right", "femur_left", "femur_right", "hip_left", "hip_right",
    "spinal_cord", "gluteus_maximus_left", "gluteus_maximus_right", "gluteus_medius_left",
    "gluteus_medius_right", "gluteus_minimus_left", "gluteus_minimus_right", "autochthon_left",
    "autochthon_right", "iliopsoas_left", "iliopsoas_right", "brain", "skull", "rib_left_1",
    "rib_left_2", "rib_left_3", "rib_left_4", "rib_left_5", "rib_left_6", "rib_left_7",
    "rib_left_8", "rib_left_9", "rib_left_10", "rib_left_11", "rib_left_12", "rib_right_1",
    "rib_right_2", "rib_right_3", "rib_right_4", "rib_right_5", "rib_right_6", "rib_right_7",
    "rib_right_8", "rib_right_9", "rib_right_10", "rib_right_11", "rib_right_12", "sternum",
    "costal_cartilages",
};
constexpr int kTotalSegmentatorCount = int(sizeof(kTotalSegmentatorNames) / sizeof(kTotalSegmentatorNames[0]));
static_assert(kTotalSegmentatorCount == 117, "TotalSegmentator total task has 117 classes");

std::vector<std::string> splitFields(const std::string& line) {
  std::vector<std::string> fields;
  if (line.find('\t') != std::string::npos) {
    std::string field;
    std::istringstream in(line);
    while (std::getline(in, field, '\t')) {
      const auto b = field.find_first_not_of(" \r");
      const auto e = field.find_last_not_of(" \r");
      fields.push_back(b == std::string::npos ? std::string() : field.substr(b, e - b + 1));
    }
    while (!fields.empty() && fields.back().empty()) fields.pop_back();
  } else {
    std::istringstream in(line);
    std::string field;
    while (in >> field) fields.push_back(field);
  }
  return fields;
}

bool parseInt(const std::string& s, int& value);

bool isKindWord(const std::string& s) {
  const std::string t = lower(s);
  return t == "bone" || t == "soft" || t == "background";
}

// The fields after the value: name, optional kind, optional colour (see parseLabelTable).
void parseEntry(const std::vector<std::string>& f, bool tabs, LabelInfo& info) {
  const std::string expected = " (expected value<TAB>name[<TAB>kind][<TAB>R<TAB>G<TAB>B[<TAB>A]] or value name R G B A)";
  std::size_t end = f.size();  // fields [1, end) hold the name and the kind
  int trailing = 0, dummy = 0;
  while (trailing < int(end) - 2 && parseInt(f[end - 1 - trailing], dummy)) ++trailing;
  if (tabs && trailing > 0 && trailing < 3 && end > 3)
    throw std::invalid_argument("a colour needs 3 or 4 numbers" + expected);
  if (trailing >= 3) {
    const int n = std::min(trailing, 4);
    for (int c = 0; c < 4; ++c) {
      int v = 255;
      if (c < n && (!parseInt(f[end - n + c], v) || v > 255))
        throw std::invalid_argument("colour component '" + f[end - n + c] + "' is not within 0..255");
      info.rgba[c] = std::uint8_t(v);
    }
    info.hasColor = true;
    end -= n;
  }
  if (end < 2 || f[1].empty()) throw std::invalid_argument("label " + f[0] + " has no name" + expected);
  const bool kindGiven = end >= 3 && (tabs || isKindWord(f[end - 1]));
  if (tabs && end > 3) throw std::invalid_argument("too many fields" + expected);
  info.kind = kindGiven ? parseLabelKind(f[end - 1]) : LabelKind::Soft;
  info.name = f[1];
  for (std::size_t i = 2; i + (kindGiven ? 1 : 0) < end; ++i) info.name += " " + f[i];
  if (!kindGiven) info.kind = inferLabelKind(info.name);
}

bool parseInt(const std::string& s, int& value) {
  if (s.empty()) return false;
  std::size_t used = 0;
  try {
    const long v = std::stol(s, &used);
    if (used != s.size() || v < 0 || v > 2147483647L) return false;
    value = int(v);
  } catch (const std::exception&) {
    return false;
  }
  return true;
}

}  // namespace

const LabelInfo* LabelTable::find(int value) const {
  for (const LabelInfo& l : labels)
    if (l.value == value) return &l;
  return nullptr;
}

std::string LabelTable::nameOf(int value) const {
  const LabelInfo* l = find(value);
  return l ? l->name : "label_" + std::to_string(value);
}

LabelKind parseLabelKind(const std::string& text) {
  const std::string t = lower(text);
  if (t == "bone") return LabelKind::Bone;
  if (t == "soft") return LabelKind::Soft;
  if (t == "background") return LabelKind::Background;
  throw std::invalid_argument("unknown label kind '" + text + "': use bone, soft or background");
}

const char* labelKindName(LabelKind kind) {
  switch (kind) {
    case LabelKind::Bone: return "bone";
    case LabelKind::Soft: return "soft";
    case LabelKind::Background: return "background";
  }
  return "soft";
}

LabelKind inferLabelKind(const std::string& name) {
  const std::string n = lower(name);
  if (n == "background" || n == "none" || n == "unlabeled" || n == "unlabelled" || n == "clear label" ||
      n == "clear_label")
    return LabelKind::Background;
  return namesBone(name) ? LabelKind::Bone : LabelKind::Soft;
}

LabelTable parseLabelTable(const std::string& text, const std::string& sourceName) {
  LabelTable table;
  table.source = sourceName;
  std::set<int> seen;
  std::istringstream in(text);
  std::string line;
  int lineNo = 0;
  bool sawData = false;
  while (std::getline(in, line)) {
    ++lineNo;
    const bool tabs = line.find('\t') != std::string::npos;
    const std::vector<std::string> f = splitFields(line);
    if (f.empty() || f[0][0] == '#') continue;
    const std::string where = sourceName + " line " + std::to_string(lineNo) + ": ";
    LabelInfo info;
    if (!parseInt(f[0], info.value)) {
      if (!sawData) {  // a header line
        sawData = true;
        continue;
      }
      throw std::invalid_argument(where + "bad label value '" + f[0] +
                                  "' (expected a non-negative integer, then a tab and a name)");
    }
    sawData = true;
    try {
      parseEntry(f, tabs, info);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(where + e.what());
    }
    if (!seen.insert(info.value).second)
      throw std::invalid_argument(where + "duplicate label value " + f[0]);
    table.labels.push_back(info);
  }
  return table;
}

LabelTable readLabelTableFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::invalid_argument("cannot open label table '" + path + "'");
  std::ostringstream ss;
  ss << in.rdbuf();
  return parseLabelTable(ss.str(), path);
}

std::string labelTableToTsv(const LabelTable& table) {
  const bool colours = std::any_of(table.labels.begin(), table.labels.end(), [](const LabelInfo& l) { return l.hasColor; });
  std::ostringstream out;
  out << "value\tname\tkind" << (colours ? "\tr\tg\tb\ta" : "") << "\n";
  for (const LabelInfo& l : table.labels) {
    out << l.value << '\t' << l.name << '\t' << labelKindName(l.kind);
    if (l.hasColor)
      for (std::uint8_t c : l.rgba) out << '\t' << int(c);
    out << '\n';
  }
  return out.str();
}

namespace {

// A colour for a label the table gives none: distinct hues (golden angle), not too dark or pale.
std::array<std::uint8_t, 4> generatedColour(const LabelInfo& l) {
  if (l.kind == LabelKind::Bone) return {241, 214, 145, 255};  // Slicer's "bone"
  const double hue = std::fmod(double(l.value) * 137.508, 360.0) / 60.0;
  const double s = 0.55, v = 0.85, c = v * s, x = c * (1 - std::fabs(std::fmod(hue, 2.0) - 1)), m = v - c;
  const int sector = int(hue) % 6;
  const double rgb[6][3] = {{c, x, 0}, {x, c, 0}, {0, c, x}, {0, x, c}, {x, 0, c}, {c, 0, x}};
  std::array<std::uint8_t, 4> out{0, 0, 0, 255};
  for (int i = 0; i < 3; ++i) out[std::size_t(i)] = std::uint8_t(std::lround(255 * (rgb[sector][i] + m)));
  return out;
}

}  // namespace

std::array<std::uint8_t, 4> displayColour(const LabelInfo& label) {
  return label.hasColor ? label.rgba : generatedColour(label);
}

std::string labelTableToSlicerColorTable(const LabelTable& table) {
  std::ostringstream out;
  const auto values = std::count_if(table.labels.begin(), table.labels.end(), [](const LabelInfo& l) { return l.value != 0; });
  out << "# Color table file (3D Slicer): label value, name, R G B A\n# " << values + 1 << " values\n";
  out << "0 background 0 0 0 0\n";
  for (const LabelInfo& l : table.labels) {
    if (l.value == 0) continue;
    std::string name = l.name;
    std::replace(name.begin(), name.end(), ' ', '_');
    const auto rgba = displayColour(l);
    out << l.value << ' ' << name;
    for (std::uint8_t c : rgba) out << ' ' << int(c);
    out << '\n';
  }
  return out.str();
}

std::vector<std::string> labelTablesBeside(const std::string& volumePath) {
  namespace fs = std::filesystem;
  const fs::path p(volumePath);
  std::string name = p.filename().string();
  const std::string lowerName = lower(name);
  for (const char* ext : {".nii.gz", ".nii", ".nrrd", ".nhdr", ".mha", ".mhd"}) {
    const std::string e = ext;
    if (lowerName.size() > e.size() && lowerName.compare(lowerName.size() - e.size(), e.size(), e) == 0) {
      name.resize(name.size() - e.size());
      break;
    }
  }
  std::vector<std::string> found;
  for (const std::string& candidate : {name + ".tsv", name + ".ctbl", name + "_ColorTable.ctbl", name + ".txt",
                                       std::string("labels.tsv")}) {
    std::error_code ec;
    const fs::path c = p.parent_path() / candidate;
    if (fs::is_regular_file(c, ec) && std::find(found.begin(), found.end(), c.string()) == found.end())
      found.push_back(c.string());
  }
  return found;
}

std::string findLabelTableBeside(const std::string& volumePath) {
  const std::vector<std::string> found = labelTablesBeside(volumePath);
  return found.empty() ? std::string() : found.front();
}

LabelTable genericLabelTable(const std::vector<int>& values, const std::vector<int>& boneValues) {
  LabelTable table;
  table.source = "label values without names";
  const std::set<int> bones(boneValues.begin(), boneValues.end());
  for (int v : std::set<int>(values.begin(), values.end()))
    if (v != 0) table.labels.push_back({v, "label_" + std::to_string(v), bones.count(v) ? LabelKind::Bone : LabelKind::Soft});
  return table;
}

LabelTable builtinTotalSegmentatorTable() {
  LabelTable table;
  table.source = "the built-in TotalSegmentator table";
  for (int i = 0; i < kTotalSegmentatorCount; ++i)
    table.labels.push_back({i + 1, kTotalSegmentatorNames[i], inferLabelKind(kTotalSegmentatorNames[i])});
  return table;
}

}  // namespace repose
