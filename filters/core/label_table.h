#pragma once
// Label tables: label value -> name and tissue kind (bone, soft, background).
#include <string>
#include <vector>

namespace repose {

enum class LabelKind { Bone, Soft, Background };

struct LabelInfo {
  int value = 0;
  std::string name;
  LabelKind kind = LabelKind::Soft;
};

/// Entries in the order given (values unique).
struct LabelTable {
  std::vector<LabelInfo> labels;
  const LabelInfo* find(int value) const;  ///< nullptr when absent
  /// The entry's name, or "label_<value>" when absent.
  std::string nameOf(int value) const;
};

/// "bone" | "soft" | "background" (case-insensitive); throws std::invalid_argument otherwise.
LabelKind parseLabelKind(const std::string& text);
const char* labelKindName(LabelKind kind);

/// Kind inferred from a name when a table gives none: the bone names of TotalSegmentator's "total"
/// task (femur_left, hip_right, sacrum, vertebrae_L5, rib_left_3, ...) and of the built-in phantom
/// (skull, spine, ribcage, pelvis, femur_left, tibia_left, ...) are Bone, "background"/"none"/
/// "unlabeled" are Background, everything else (cartilage included) is Soft.
LabelKind inferLabelKind(const std::string& name);

/// Parses `value<TAB>name[<TAB>kind]` lines. A first line whose first field is not a number
/// (a header such as "value\tname\tkind") is skipped; blank lines and lines starting with '#' are
/// ignored; fields may also be separated by runs of spaces. Without a kind the kind is inferred from
/// the name. Throws std::invalid_argument naming sourceName and the line on a bad value, a missing
/// name, a duplicate value or an unknown kind.
LabelTable parseLabelTable(const std::string& text, const std::string& sourceName = "label table");
/// Reads and parses a file; errors name the file.
LabelTable readLabelTableFile(const std::string& path);
/// Serializes as "value\tname\tkind" lines with that header (parseLabelTable reads it back).
std::string labelTableToTsv(const LabelTable& table);

/// TotalSegmentator v2 "total" task: its 117 classes (1 spleen ... 117 costal_cartilages) with
/// inferred kinds, recognised by value without a file.
LabelTable builtinTotalSegmentatorTable();

}  // namespace repose
