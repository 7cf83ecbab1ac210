#pragma once
// Label tables: label value -> name, tissue kind (bone, soft, background) and an optional colour.
// Read from Repose's TSV (value<TAB>name[<TAB>kind]) or a 3D Slicer colour table (.ctbl/.txt:
// "value name R G B A" lines); found beside a label volume when none is given.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace repose {

enum class LabelKind { Bone, Soft, Background };

struct LabelInfo {
  int value = 0;
  std::string name;
  LabelKind kind = LabelKind::Soft;
  bool hasColor = false;
  std::array<std::uint8_t, 4> rgba{0, 0, 0, 255};  ///< 0..255 each, when hasColor
};

/// Entries in the order given (values unique).
struct LabelTable {
  std::vector<LabelInfo> labels;
  std::string source;  ///< where it came from, for messages (a file, "the built-in ... table")
  const LabelInfo* find(int value) const;  ///< nullptr when absent
  /// The entry's name, or "label_<value>" when absent.
  std::string nameOf(int value) const;
};

/// "bone" | "soft" | "background" (case-insensitive); throws std::invalid_argument otherwise.
LabelKind parseLabelKind(const std::string& text);
const char* labelKindName(LabelKind kind);

/// Kind inferred from a name when a table gives none: names of bones in any spelling anatomy_names
/// recognises (femur_left, Femur_L, "left femur", vertebrae_L5, rib_left_3, "Humeri, upper half",
/// the phantom's skull, spine, ribcage, pelvis, ...) and generic ones (bones, skeleton) are Bone;
/// "background"/"none"/"unlabeled"/"clear label" are Background; everything else (costal
/// cartilage, vessels named after bones such as iliac_artery) is Soft.
LabelKind inferLabelKind(const std::string& name);

/// Parses a label table, one label per line; blank lines and lines starting with '#' are ignored,
/// and so is a first line whose first field is not a number (a header such as "value\tname\tkind").
/// - Tab-separated: value<TAB>name[<TAB>kind][<TAB>R<TAB>G<TAB>B[<TAB>A]]; names may hold spaces.
/// - Space-separated (3D Slicer colour tables, .ctbl/.txt): value name [kind] [R G B [A]]; the
///   name is every word between the value and the optional kind and colour (Slicer writes spaces
///   in names as '_').
/// Colours are integers 0..255 (alpha 255 when absent). Without a kind the kind is inferred from the
/// name. Throws std::invalid_argument naming sourceName and the line on a bad value, a missing
/// name, a duplicate value, an unknown kind or a colour outside 0..255.
LabelTable parseLabelTable(const std::string& text, const std::string& sourceName = "label table");
/// Reads and parses a file (any format above); errors name the file.
LabelTable readLabelTableFile(const std::string& path);
/// Serializes as "value\tname\tkind" lines with that header, plus "\tr\tg\tb\ta" columns when
/// some label has a colour (parseLabelTable reads it back).
std::string labelTableToTsv(const LabelTable& table);

/// Serializes as a 3D Slicer colour table (.ctbl: "value name R G B A" lines, spaces in names as '_'),
/// which Slicer loads as the volume's colour node. Labels without a colour get one: bones Slicer's
/// bone colour, the others hues spread by the golden angle (the same value, the same colour).
std::string labelTableToSlicerColorTable(const LabelTable& table);

/// The colour a label is shown in (0..255 RGBA): its own, else the one the Slicer colour table gives
/// it (bones Slicer's bone colour, other labels a hue by the golden angle of their value).
std::array<std::uint8_t, 4> displayColour(const LabelInfo& label);

/// The label tables stored beside a label volume, most specific first: for DIR/NAME.nii.gz (or
/// .nii, .nrrd, .nhdr, .mha, .mhd) those of DIR/NAME.tsv, DIR/NAME.ctbl, DIR/NAME_ColorTable.ctbl
/// (3D Slicer's export), DIR/NAME.txt and DIR/labels.tsv that exist.
std::vector<std::string> labelTablesBeside(const std::string& volumePath);
/// The first of labelTablesBeside(), or "" when there is none.
std::string findLabelTableBeside(const std::string& volumePath);

/// A table for a volume that came without one: every value of `values` (0 excepted) named
/// label_<value>, kind bone when it is in `boneValues`, else soft.
LabelTable genericLabelTable(const std::vector<int>& values, const std::vector<int>& boneValues);

/// TotalSegmentator v2 "total" task: its 117 classes (1 spleen ... 117 costal_cartilages) with
/// inferred kinds, recognised by value without a file.
LabelTable builtinTotalSegmentatorTable();

}  // namespace repose
