// Label tables: Repose's TSV, 3D Slicer colour tables, the built-in TotalSegmentator names, the
// table beside a volume, and whether a table fits a volume.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <unistd.h>

#include "label_table.h"
#include "label_table_fit.h"
#include "phantom.h"

using namespace repose;

namespace {

std::string message(const std::string& text) {
  try {
    parseLabelTable(text, "t.tsv");
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "no error";
}

LabelTable phantomTable(const Phantom& ph) {
  LabelTable t;
  for (const auto& [value, name] : ph.labelNames) t.labels.push_back({value, name, inferLabelKind(name)});
  return t;
}

}  // namespace

TEST(LabelTable, ParsesHeaderCommentsKindsAndInference) {
  const LabelTable t = parseLabelTable(
      "value\tname\tkind\n# comment\n\n1\tliver\n25\tsacrum\n75\tfemur_left\tbone\n117\tcostal_cartilages\n"
      "0\tbackground\n9\tmy_plate\tBone\n");
  ASSERT_EQ(t.labels.size(), 6u);
  EXPECT_EQ(t.find(1)->kind, LabelKind::Soft);
  EXPECT_EQ(t.find(25)->kind, LabelKind::Bone);
  EXPECT_EQ(t.find(75)->name, "femur_left");
  EXPECT_EQ(t.find(117)->kind, LabelKind::Soft);  // cartilage bends
  EXPECT_EQ(t.find(0)->kind, LabelKind::Background);
  EXPECT_EQ(t.find(9)->kind, LabelKind::Bone);
  EXPECT_FALSE(t.find(1)->hasColor);
  EXPECT_EQ(t.find(2), nullptr);
  EXPECT_EQ(t.nameOf(2), "label_2");
  EXPECT_EQ(t.source, "label table");
  // Round trip.
  const LabelTable u = parseLabelTable(labelTableToTsv(t));
  ASSERT_EQ(u.labels.size(), t.labels.size());
  for (std::size_t i = 0; i < t.labels.size(); ++i) {
    EXPECT_EQ(u.labels[i].value, t.labels[i].value);
    EXPECT_EQ(u.labels[i].name, t.labels[i].name);
    EXPECT_EQ(u.labels[i].kind, t.labels[i].kind);
  }
  // Names in other spellings are inferred as bone too, vessels named after bones are not.
  for (const char* bone : {"Femur_L", "left femur", "Humeri, upper half", "Os coxae", "LFemur", "bones"})
    EXPECT_EQ(inferLabelKind(bone), LabelKind::Bone) << bone;
  for (const char* soft : {"iliac_artery_left", "spinal_cord", "costal cartilage", "femoral vein", "Clear Label"})
    EXPECT_NE(inferLabelKind(soft), LabelKind::Bone) << soft;
}

TEST(LabelTable, ErrorsNameTheLine) {
  EXPECT_NE(message("value\tname\n1\tliver\nx2\tspleen\n").find("t.tsv line 3"), std::string::npos);
  EXPECT_NE(message("1\tliver\n1\tspleen\n").find("line 2: duplicate label value 1"), std::string::npos);
  EXPECT_NE(message("1\tliver\n\n4\tfemur\tbony\n").find("line 3: unknown label kind 'bony'"), std::string::npos);
  EXPECT_NE(message("1\tliver\n-4\tfemur\n").find("line 2: bad label value"), std::string::npos);
  EXPECT_NE(message("1\n").find("line 1"), std::string::npos);
  EXPECT_NE(message("1\tliver\tsoft\textra\n").find("line 1: too many fields"), std::string::npos);
  EXPECT_NE(message("1 liver 300 0 0 255\n").find("line 1: colour component '300'"), std::string::npos);
  EXPECT_NE(message("1\tliver\t12\t40\n").find("line 1: a colour needs 3 or 4 numbers"), std::string::npos);
  EXPECT_THROW(readLabelTableFile("/nonexistent/labels.tsv"), std::invalid_argument);
}

TEST(LabelTable, SlicerColourTables) {
  // As 3D Slicer writes a .ctbl (spaces in names as '_').
  const std::string ctbl =
      "# Color table file /somewhere/Segmentation-label_ColorTable.ctbl\n"
      "# 5 values\n"
      "0 Background 0 0 0 0\n"
      "1 Femur_L 241 214 145 255\n"
      "2 Femur_R 241 214 145 255\n"
      "3 connective_tissue 111 184 210 255\n"
      "7 Humeri,_upper_half 200 10 20\n";
  const LabelTable t = parseLabelTable(ctbl, "seg.ctbl");
  ASSERT_EQ(t.labels.size(), 5u);
  EXPECT_EQ(t.source, "seg.ctbl");
  EXPECT_EQ(t.find(0)->kind, LabelKind::Background);
  EXPECT_EQ(t.find(1)->name, "Femur_L");
  EXPECT_EQ(t.find(1)->kind, LabelKind::Bone);
  EXPECT_EQ(t.find(3)->kind, LabelKind::Soft);
  EXPECT_EQ(t.find(7)->kind, LabelKind::Bone);
  ASSERT_TRUE(t.find(1)->hasColor);
  EXPECT_EQ(t.find(1)->rgba, (std::array<std::uint8_t, 4>{241, 214, 145, 255}));
  EXPECT_EQ(t.find(7)->rgba, (std::array<std::uint8_t, 4>{200, 10, 20, 255}));  // alpha defaults to opaque
  // Space-separated names and a kind, and tab-separated colours; the TSV keeps the colours.
  const LabelTable u = parseLabelTable("4 left femur bone 1 2 3 4\n5 Humeri, upper half\n6\tliver\tsoft\t9\t8\t7\n");
  EXPECT_EQ(u.find(4)->name, "left femur");
  EXPECT_EQ(u.find(4)->rgba, (std::array<std::uint8_t, 4>{1, 2, 3, 4}));
  EXPECT_EQ(u.find(5)->name, "Humeri, upper half");
  EXPECT_FALSE(u.find(5)->hasColor);
  EXPECT_EQ(u.find(6)->rgba, (std::array<std::uint8_t, 4>{9, 8, 7, 255}));
  const std::string tsv = labelTableToTsv(t);
  EXPECT_EQ(tsv.substr(0, tsv.find('\n')), "value\tname\tkind\tr\tg\tb\ta");
  const LabelTable back = parseLabelTable(tsv);
  for (const LabelInfo& l : t.labels) {
    EXPECT_EQ(back.find(l.value)->name, l.name);
    EXPECT_EQ(back.find(l.value)->rgba, l.rgba);
    EXPECT_EQ(back.find(l.value)->kind, l.kind);
  }
}

TEST(LabelTable, FoundBesideTheVolume) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("repose_label_table_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  auto touch = [&](const std::string& name) { std::ofstream(dir / name) << "1\tfemur\n"; };
  const std::string volume = (dir / "seg.nii.gz").string();
  EXPECT_EQ(findLabelTableBeside(volume), "");
  touch("labels.tsv");
  EXPECT_EQ(findLabelTableBeside(volume), (dir / "labels.tsv").string());
  touch("seg.txt");
  EXPECT_EQ(findLabelTableBeside(volume), (dir / "seg.txt").string());
  touch("seg_ColorTable.ctbl");
  EXPECT_EQ(findLabelTableBeside(volume), (dir / "seg_ColorTable.ctbl").string());
  touch("seg.ctbl");
  EXPECT_EQ(findLabelTableBeside(volume), (dir / "seg.ctbl").string());
  touch("seg.tsv");
  EXPECT_EQ(findLabelTableBeside(volume), (dir / "seg.tsv").string());
  EXPECT_EQ(findLabelTableBeside((dir / "seg.nrrd").string()), (dir / "seg.tsv").string());
  EXPECT_EQ(findLabelTableBeside((dir / "labels.mha").string()), (dir / "labels.tsv").string());
  const std::vector<std::string> all = labelTablesBeside(volume);
  ASSERT_EQ(all.size(), 5u);
  EXPECT_EQ(all[3], (dir / "seg.txt").string());
  EXPECT_EQ(all[4], (dir / "labels.tsv").string());
  fs::remove_all(dir);
}

TEST(LabelTable, BuiltinTotalSegmentatorMatchesTheClassMap) {
  const LabelTable t = builtinTotalSegmentatorTable();
  ASSERT_EQ(t.labels.size(), 117u);
  std::ifstream in(REPOSE_SHARED_DATA "/totalsegmentator/labels_total_v2.tsv");
  ASSERT_TRUE(in.good());
  std::stringstream ss;
  ss << in.rdbuf();
  const LabelTable file = parseLabelTable(ss.str());
  ASSERT_EQ(file.labels.size(), 117u);
  std::size_t bones = 0;
  for (const LabelInfo& l : file.labels) {
    ASSERT_NE(t.find(l.value), nullptr);
    EXPECT_EQ(t.find(l.value)->name, l.name);
    bones += l.kind == LabelKind::Bone;
  }
  // sacrum, 25 vertebrae, humerus/scapula/clavicula/femur/hip x2, skull, 24 ribs, sternum.
  EXPECT_EQ(bones, 1u + 25 + 10 + 1 + 24 + 1);
}

TEST(LabelTableFit, ThePhantomFitsItsOwnTableNotTotalSegmentators) {
  const Phantom ph = makePhantom(PhantomSize::Tiny);
  const LabelTableFit own = checkLabelTableFit(ph.labels, phantomTable(ph));
  EXPECT_TRUE(own.fits()) << own.problem();
  EXPECT_EQ(own.misplaced, 0);
  EXPECT_EQ(own.boneLabels, 16);
  EXPECT_EQ(own.checked, 16);  // skull, spine, ribcage, pelvis and twelve sided limb bones
  // TotalSegmentator's names put the sacrum and vertebrae on the phantom's limb bones (25..35).
  const LabelTableFit ts = checkLabelTableFit(ph.labels, builtinTotalSegmentatorTable());
  EXPECT_FALSE(ts.fits());
  EXPECT_EQ(ts.boneLabels, 11);
  EXPECT_EQ(ts.checked, 11);
  EXPECT_EQ(ts.misplaced, 11);
  EXPECT_NE(ts.problem().find("11 of 11 bone labels lie where their names cannot be: sacrum (25) lies"),
            std::string::npos)
      << ts.problem();
  // Only two or fewer checked bones: no verdict.
  LabelTable two;
  two.labels = {{20, "sacrum", LabelKind::Bone}, {24, "sternum", LabelKind::Bone}};
  EXPECT_TRUE(checkLabelTableFit(ph.labels, two).fits());
}

TEST(LabelTable, SlicerColourTableReadsBack) {
  const LabelTable table = parseLabelTable("value\tname\tkind\tr\tg\tb\ta\n"
                                           "24\tfemur left\tbone\t200\t180\t120\t255\n"
                                           "5\tmuscle\tsoft\n"
                                           "75\tfemur_right\tbone\n");
  const std::string ctbl = labelTableToSlicerColorTable(table);
  const LabelTable back = parseLabelTable(ctbl, "posed_labels.ctbl");
  ASSERT_EQ(back.labels.size(), 4u);  // background first, then the three
  EXPECT_EQ(back.nameOf(24), "femur_left");
  EXPECT_EQ(back.find(24)->rgba, (std::array<std::uint8_t, 4>{200, 180, 120, 255}));  // its own colour kept
  EXPECT_EQ(back.find(75)->rgba, (std::array<std::uint8_t, 4>{241, 214, 145, 255}));  // a bone: Slicer's bone
  // A soft tissue without a colour gets a stable, visible one.
  const auto muscle = back.find(5)->rgba;
  EXPECT_EQ(muscle, parseLabelTable(labelTableToSlicerColorTable(table)).find(5)->rgba);
  EXPECT_GT(int(muscle[0]) + muscle[1] + muscle[2], 150);
  EXPECT_EQ(back.find(0)->kind, LabelKind::Background);
}
