// Automatic skeleton: label tables, and autoRig recovering the built-in phantom's own skeleton.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

#include "auto_rig.h"
#include "label_table.h"
#include "phantom.h"
#include "skeleton.h"

using namespace repose;

namespace {

LabelTable phantomTable(const Phantom& ph) {
  LabelTable t;
  for (const auto& [value, name] : ph.labelNames) t.labels.push_back({value, name, inferLabelKind(name)});
  return t;
}

std::string parentName(const Skeleton& s, const Joint& j) { return j.parent < 0 ? "" : s.joints[j.parent].name; }

// Every joint of the phantom's true skeleton is found with the same parent, and non-root centres lie
// within 1.5 voxels (of the largest spacing) of the truth.
void expectRecovers(const Phantom& ph, const AutoRigResult& r) {
  const double tol = 1.5 * ph.labels.grid.spacing.maxCoeff();
  EXPECT_EQ(r.skeleton.size(), ph.skeleton.size()) << r.report.text();
  for (const Joint& truth : ph.skeleton.joints) {
    const int i = r.skeleton.find(truth.name);
    ASSERT_GE(i, 0) << "missing joint " << truth.name << "\n" << r.report.text();
    const Joint& got = r.skeleton.joints[i];
    EXPECT_EQ(parentName(r.skeleton, got), parentName(ph.skeleton, truth)) << truth.name;
    if (truth.parent >= 0) {
      std::printf("  %-15s error %.2f voxels\n", truth.name.c_str(),
                  (got.center - truth.center).norm() / ph.labels.grid.spacing.maxCoeff());
      EXPECT_LE((got.center - truth.center).norm(), tol)
          << truth.name << ": found " << got.center.transpose() << ", true " << truth.center.transpose();
    }
  }
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
  EXPECT_EQ(t.find(2), nullptr);
  EXPECT_EQ(t.nameOf(2), "label_2");
  // Round trip.
  const LabelTable u = parseLabelTable(labelTableToTsv(t));
  ASSERT_EQ(u.labels.size(), t.labels.size());
  for (std::size_t i = 0; i < t.labels.size(); ++i) {
    EXPECT_EQ(u.labels[i].value, t.labels[i].value);
    EXPECT_EQ(u.labels[i].name, t.labels[i].name);
    EXPECT_EQ(u.labels[i].kind, t.labels[i].kind);
  }
}

TEST(LabelTable, ErrorsNameTheLine) {
  auto message = [](const std::string& text) {
    try {
      parseLabelTable(text, "t.tsv");
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message("value\tname\n1\tliver\nx2\tspleen\n").find("t.tsv line 3"), std::string::npos);
  EXPECT_NE(message("1\tliver\n1\tspleen\n").find("line 2: duplicate label value 1"), std::string::npos);
  EXPECT_NE(message("1\tliver\n\n4\tfemur\tbony\n").find("line 3: unknown label kind 'bony'"), std::string::npos);
  EXPECT_NE(message("1\tliver\n-4\tfemur\n").find("line 2: bad label value"), std::string::npos);
  EXPECT_NE(message("1\n").find("line 1"), std::string::npos);
  EXPECT_THROW(readLabelTableFile("/nonexistent/labels.tsv"), std::invalid_argument);
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
  for (const char* soft : {"spinal_cord", "costal_cartilages", "iliac_artery_left", "hip_bogus_not"})
    EXPECT_EQ(inferLabelKind(soft), std::string(soft) == "hip_bogus_not" ? LabelKind::Bone : LabelKind::Soft)
        << soft;
  for (const char* bone : {"skull", "spine", "ribcage", "pelvis", "femur_left", "tibia_right", "foot_left",
                           "humerus_right", "forearm_left", "hand_right", "vertebrae_L5", "rib_right_12"})
    EXPECT_EQ(inferLabelKind(bone), LabelKind::Bone) << bone;
}

TEST(AutoRig, StandardNames) {
  EXPECT_EQ(standardJointName("femur_left"), "left_hip");
  EXPECT_EQ(standardJointName("humerus_right"), "right_shoulder");
  EXPECT_EQ(standardJointName("tibia_left"), "left_knee");
  EXPECT_EQ(standardJointName("skull"), "neck");
  EXPECT_EQ(standardJointName("vertebrae_L4"), "vertebra_L4");
  EXPECT_EQ(standardJointName("kidney_left"), "");
}

TEST(AutoRig, RecoversTinyPhantomSkeleton) {
  const Phantom ph = makePhantom(PhantomSize::Tiny);
  const auto t0 = std::chrono::steady_clock::now();
  const AutoRigResult r = autoRig(ph.labels, phantomTable(ph));
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("tiny phantom (%d x %d x %d): autoRig %.3f s\n%s", ph.labels.grid.dims[0], ph.labels.grid.dims[1],
              ph.labels.grid.dims[2], s, r.report.text().c_str());
  expectRecovers(ph, r);
  EXPECT_EQ(r.skeleton.joints[0].name, "pelvis");
  // The ribcage rides with the spine, as in the phantom's own skeleton.
  const Joint& spine = r.skeleton.joints[r.skeleton.find("spine")];
  EXPECT_EQ(spine.labels, (std::vector<int>{phantom_label::Spine, phantom_label::Ribcage}));
  // Nothing split: the volume comes back unchanged and the JSON round-trips.
  EXPECT_EQ(r.labels.data, ph.labels.data);
  EXPECT_EQ(parseSkeletonJson(skeletonToJson(r.skeleton)).size(), r.skeleton.size());
}

TEST(AutoRig, RecoversSmallPhantomSkeleton) {
  const Phantom ph = makePhantom(PhantomSize::Small);
  const auto t0 = std::chrono::steady_clock::now();
  const AutoRigResult r = autoRig(ph.labels, phantomTable(ph));
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("small phantom (%d x %d x %d): autoRig %.3f s\n%s", ph.labels.grid.dims[0], ph.labels.grid.dims[1],
              ph.labels.grid.dims[2], s, r.report.text().c_str());
  expectRecovers(ph, r);
}

TEST(AutoRig, SplitsALabelHoldingBothFemursBySide) {
  Phantom ph = makePhantom(PhantomSize::Tiny);
  for (std::int32_t& v : ph.labels.data)
    if (v == phantom_label::FemurRight) v = phantom_label::FemurLeft;
  LabelTable table = phantomTable(ph);
  table.labels.erase(std::remove_if(table.labels.begin(), table.labels.end(),
                                    [](const LabelInfo& l) { return l.value == phantom_label::FemurRight; }),
                     table.labels.end());
  for (LabelInfo& l : table.labels)
    if (l.value == phantom_label::FemurLeft) l.name = "femur";
  // A stray voxel of the femur label far from both femurs is noise, not a third femur.
  ph.labels.at(2, 2, 2) = phantom_label::FemurLeft;

  const AutoRigResult r = autoRig(ph.labels, table);
  const int left = r.skeleton.find("left_hip"), right = r.skeleton.find("right_hip");
  ASSERT_GE(left, 0) << r.report.text();
  ASSERT_GE(right, 0) << r.report.text();
  const Joint& L = r.skeleton.joints[left];
  const Joint& R = r.skeleton.joints[right];
  ASSERT_EQ(L.labels.size(), 1u);
  ASSERT_EQ(R.labels.size(), 1u);
  EXPECT_NE(L.labels[0], R.labels[0]);
  EXPECT_EQ(r.table.find(L.labels[0])->name, "femur_left");
  EXPECT_EQ(r.table.find(R.labels[0])->name, "femur_right");
  EXPECT_GT(std::max(L.labels[0], R.labels[0]), phantom_label::HandRight);  // a new value
  // The relabelled volume puts each femur's voxels under its own value, on its own side (LPS +x = left).
  const ImageGrid& g = r.labels.grid;
  std::size_t nl = 0, nr = 0;
  for (int k = 0; k < g.dims[2]; ++k)
    for (int j = 0; j < g.dims[1]; ++j)
      for (int i = 0; i < g.dims[0]; ++i) {
        const int v = r.labels.at(i, j, k);
        const double x = g.indexToPhysical(Eigen::Vector3d(i, j, k)).x();
        if (v == L.labels[0] && !(i == 2 && j == 2 && k == 2)) { ++nl; EXPECT_GT(x, 0); }
        if (v == R.labels[0]) { ++nr; EXPECT_LT(x, 0); }
      }
  EXPECT_GT(nl, 400u);
  EXPECT_GT(nr, 400u);
  EXPECT_EQ(r.report.noiseComponents, 1u);
  EXPECT_EQ(r.report.noiseVoxels, 1u);
  expectRecovers(ph, r);
  // Idempotent: the relabelled volume with the extended table gives the same skeleton, no split.
  const AutoRigResult again = autoRig(r.labels, r.table);
  EXPECT_EQ(again.labels.data, r.labels.data);
  ASSERT_EQ(again.skeleton.size(), r.skeleton.size());
  for (std::size_t j = 0; j < r.skeleton.size(); ++j) {
    EXPECT_EQ(again.skeleton.joints[j].name, r.skeleton.joints[j].name);
    EXPECT_EQ(again.skeleton.joints[j].labels, r.skeleton.joints[j].labels);
    EXPECT_LT((again.skeleton.joints[j].center - r.skeleton.joints[j].center).norm(), 1e-9);
  }
}

TEST(AutoRig, FieldOfViewCutAtTheKneesKeepsTheHipsAndReportsTheCut) {
  const Phantom full = makePhantom(PhantomSize::Small);
  // Keep the slices from mid-thigh (z of the knee + 150 mm) up: femurs cut, shanks and feet gone.
  const ImageGrid& g = full.labels.grid;
  const double zCut = full.skeleton.joints[full.skeleton.find("left_knee")].center.z() + 150;
  const int k0 = int(std::ceil(g.physicalToIndex(Eigen::Vector3d(0, 0, zCut)).z()));
  LabelVolume cut;
  cut.grid = g;
  cut.grid.dims[2] = g.dims[2] - k0;
  cut.grid.origin = g.indexToPhysical(Eigen::Vector3d(0, 0, k0));
  cut.data.assign(full.labels.data.begin() + std::ptrdiff_t(g.linearIndex(0, 0, k0)), full.labels.data.end());
  const AutoRigResult r = autoRig(cut, phantomTable(full));
  std::map<std::string, const AutoRigReport::Bone*> bones;
  for (const AutoRigReport::Bone& b : r.report.bones) bones[b.name] = &b;
  ASSERT_TRUE(bones.count("femur_left"));
  EXPECT_TRUE(bones["femur_left"]->cutByFieldOfView);
  EXPECT_TRUE(bones["femur_right"]->cutByFieldOfView);
  EXPECT_FALSE(bones["pelvis"]->cutByFieldOfView);
  EXPECT_EQ(bones["femur_left"]->joint, "left_hip");
  for (const char* gone : {"tibia_left", "tibia_right", "foot_left", "foot_right"}) {
    EXPECT_FALSE(bones.count(gone)) << gone;
    EXPECT_NE(std::find(r.report.missingBones.begin(), r.report.missingBones.end(), gone), r.report.missingBones.end())
        << gone;
  }
  EXPECT_EQ(r.skeleton.find("left_knee"), -1);
  const double tol = 1.5 * g.spacing.maxCoeff();
  for (const char* name : {"left_hip", "right_hip", "spine", "left_shoulder", "neck"}) {
    const int i = r.skeleton.find(name), t = full.skeleton.find(name);
    ASSERT_GE(i, 0) << name;
    EXPECT_LE((r.skeleton.joints[i].center - full.skeleton.joints[t].center).norm(), tol) << name;
  }
  EXPECT_NE(r.report.text().find("cut by the field of view"), std::string::npos);
}

TEST(AutoRig, WithoutAPelvisTheRootIsTheLargestCentralBone) {
  Phantom ph = makePhantom(PhantomSize::Tiny);
  LabelTable table = phantomTable(ph);
  for (LabelInfo& l : table.labels)
    if (l.value == phantom_label::Pelvis) l.kind = LabelKind::Soft;
  const AutoRigResult r = autoRig(ph.labels, table);
  // Spine + ribcage is the largest central group; the legs are not connected to it any more.
  EXPECT_EQ(r.skeleton.joints[0].name, "spine") << r.report.text();
  EXPECT_EQ(r.skeleton.find("left_hip"), -1);
  EXPECT_GE(r.skeleton.find("left_wrist"), 0);
  bool reported = false;
  for (const AutoRigReport::Bone& b : r.report.bones)
    if (b.name == "femur_left") reported = b.joint.empty() && b.note.find("not within") != std::string::npos;
  EXPECT_TRUE(reported) << r.report.text();
}

TEST(AutoRig, BadInput) {
  LabelVolume empty;
  EXPECT_THROW(autoRig(empty, LabelTable{}), std::invalid_argument);
  LabelVolume v;
  v.grid.dims = {4, 4, 4};
  v.data.assign(10, 0);
  EXPECT_THROW(autoRig(v, LabelTable{}), std::invalid_argument);  // size mismatch
  v.data.assign(64, 3);
  try {
    autoRig(v, parseLabelTable("3\tliver\n"));
    FAIL() << "no bone: expected an error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("no bone"), std::string::npos);
  }
  v.grid.spacing.x() = 0;
  EXPECT_THROW(autoRig(v, parseLabelTable("3\tfemur\n")), std::invalid_argument);
}
