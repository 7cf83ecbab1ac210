// Automatic skeleton: autoRig recovering the built-in phantom's own skeleton, and its rules on
// synthetic volumes: fragments go to the bone they belong to, small pieces are never joints,
// parents and names by anatomy, and the wrong label table is refused.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

#include "anatomy_names.h"
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

// Puts the phantom's label `from` under `into` (both bones of a pair under one label) named `name`.
void mergeLabels(Phantom& ph, LabelTable& table, int from, int into, const std::string& name) {
  for (std::int32_t& v : ph.labels.data)
    if (v == from) v = into;
  table.labels.erase(std::remove_if(table.labels.begin(), table.labels.end(),
                                    [&](const LabelInfo& l) { return l.value == from; }),
                     table.labels.end());
  for (LabelInfo& l : table.labels)
    if (l.value == into) l.name = name;
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
  LabelTable table = phantomTable(ph);
  mergeLabels(ph, table, phantom_label::FemurRight, phantom_label::FemurLeft, "femur");
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
  // Left out, and why: the femur touches bones anatomy forbids as its parent (the old rule said only
  // "not within 6 mm of the skeleton").
  bool reported = false;
  for (const AutoRigReport::Bone& b : r.report.bones)
    if (b.name == "femur_left") reported = b.joint.empty() && b.note.find("anatomy forbids") != std::string::npos;
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

namespace {

using V3 = Eigen::Vector3d;

// Label values of the phantom with the given name, by the rig's output table.
int valueNamed(const AutoRigResult& r, const std::string& name) {
  for (const LabelInfo& l : r.table.labels)
    if (l.name == name) return l.value;
  return -1;
}

const Joint* jointNamed(const AutoRigResult& r, const std::string& name) {
  const int i = r.skeleton.find(name);
  return i < 0 ? nullptr : &r.skeleton.joints[i];
}

std::string parentOf(const AutoRigResult& r, const std::string& name) {
  const Joint* j = jointNamed(r, name);
  return !j ? "(missing)" : j->parent < 0 ? "" : r.skeleton.joints[j->parent].name;
}

bool hasLabel(const Joint* j, int value) {
  return j && std::find(j->labels.begin(), j->labels.end(), value) != j->labels.end();
}

// Sets to `label` the voxels of `v` whose centres lie in the physical box [lo, hi] and whose
// current value passes `keep` (default: any).
template <class Keep>
std::vector<std::size_t> paintBox(LabelVolume& v, const V3& lo, const V3& hi, int label, Keep keep) {
  std::vector<std::size_t> painted;
  const ImageGrid& g = v.grid;
  for (int k = 0; k < g.dims[2]; ++k)
    for (int j = 0; j < g.dims[1]; ++j)
      for (int i = 0; i < g.dims[0]; ++i) {
        const V3 x = g.indexToPhysical(V3(i, j, k));
        if ((x.array() < lo.array()).any() || (x.array() > hi.array()).any()) continue;
        std::int32_t& value = v.at(i, j, k);
        if (!keep(value)) continue;
        value = label;
        painted.push_back(g.linearIndex(i, j, k));
      }
  return painted;
}
std::vector<std::size_t> paintBox(LabelVolume& v, const V3& lo, const V3& hi, int label) {
  return paintBox(v, lo, hi, label, [](int) { return true; });
}

bool isPhantomBone(int v) { return v >= phantom_label::Skull && v <= phantom_label::HandRight; }

// A soft voxel of the phantom at least `distance` mm from every bone voxel (brute force).
std::size_t softVoxelFarFromBone(const Phantom& ph, double distance) {
  const ImageGrid& g = ph.labels.grid;
  std::vector<V3> bone;
  for (std::size_t p = 0; p < ph.labels.data.size(); ++p)
    if (isPhantomBone(ph.labels.data[p]))
      bone.push_back(g.indexToPhysical(V3(double(p % g.dims[0]), double((p / g.dims[0]) % g.dims[1]),
                                          double(p / (std::size_t(g.dims[0]) * g.dims[1])))));
  for (std::size_t p = 0; p < ph.labels.data.size(); ++p) {
    if (ph.labels.data[p] != phantom_label::Muscle && ph.labels.data[p] != phantom_label::Bowel) continue;
    const V3 x = g.indexToPhysical(V3(double(p % g.dims[0]), double((p / g.dims[0]) % g.dims[1]),
                                      double(p / (std::size_t(g.dims[0]) * g.dims[1]))));
    bool far = true;
    for (const V3& b : bone) far = far && (b - x).norm() > distance;
    if (far) return p;
  }
  return std::size_t(-1);
}

// A trunk of boxes at 2 mm (LPS: x left, y posterior, z up) in a block of muscle (label 1):
// sacrum and hip bones, vertebrae L5, T1, C7, C6, C1, a skull on C1, a sternum touching the skull
// (closer than C1), ribs 1 on T1 and ribs 2 between L5 and T1, and on each side a clavicle on the sternum, a scapula on
// the clavicle, a humerus 4 mm from its scapula but touching a rib, and a femur with a patella
// 12 mm in front of it (beyond the contact gap).
struct Trunk {
  LabelVolume v;
  LabelTable t;
  Trunk() {
    v.grid.origin = V3(-150, -100, -120);
    v.grid.spacing = V3(2, 2, 2);
    v.grid.dims = {151, 81, 151};
    v.data.assign(v.grid.voxelCount(), 1);
    t.labels.push_back({1, "muscle", LabelKind::Soft});
    add(2, "sacrum", V3(-20, 0, 0), V3(20, 30, 30));
    add(3, "vertebrae_L5", V3(-15, 5, 34), V3(15, 30, 50));
    add(4, "vertebrae_T1", V3(-15, 5, 54), V3(15, 30, 70));
    add(5, "vertebrae_C7", V3(-15, 5, 74), V3(15, 30, 82));
    add(6, "vertebrae_C6", V3(-15, 5, 86), V3(15, 30, 94));
    add(7, "vertebrae_C1", V3(-15, 5, 98), V3(15, 30, 106));
    add(8, "skull", V3(-40, -70, 112), V3(40, 40, 160));
    add(9, "sternum", V3(-8, -70, 60), V3(8, -60, 110));
    for (int side : {1, -1}) {
      const int o = side > 0 ? 10 : 20;
      const std::string s = side > 0 ? "_left" : "_right";
      auto box = [&](int label, const std::string& name, double x0, double x1, V3 lo, V3 hi) {
        lo.x() = side > 0 ? x0 : -x1;
        hi.x() = side > 0 ? x1 : -x0;
        add(label, name, lo, hi);
      };
      box(o + 0, "hip" + s, 22, 70, V3(0, -10, 0), V3(0, 30, 40));
      box(o + 1, "rib" + s + "_1", 18, 60, V3(0, -50, 56), V3(0, 25, 62));
      box(o + 2, "rib" + s + "_2", 18, 92, V3(0, -50, 44), V3(0, 25, 48));
      box(o + 3, "clavicula" + s, 10, 80, V3(0, -62, 100), V3(0, -56, 104));
      box(o + 4, "scapula" + s, 70, 90, V3(0, -54, 60), V3(0, 40, 100));
      box(o + 5, "humerus" + s, 94, 110, V3(0, -20, 0), V3(0, 20, 90));
      box(o + 6, "femur" + s, 40, 60, V3(0, -10, -120), V3(0, 20, -4));
      box(o + 7, "patella" + s, 44, 56, V3(0, -30, -60), V3(0, -22, -50));
    }
  }
  void add(int label, const std::string& name, const V3& lo, const V3& hi) {
    paintBox(v, lo, hi, label);
    t.labels.push_back({label, name, inferLabelKind(name)});
  }
};

}  // namespace

TEST(AutoRigRules, ParentsAndNamesByAnatomy) {
  const Trunk trunk;
  const AutoRigResult r = autoRig(trunk.v, trunk.t);
  std::printf("%s", r.report.text().c_str());
  const std::map<std::string, std::string> parents = {
      {"pelvis", ""},
      {"spine", "pelvis"},
      {"vertebra_T1", "spine"},
      {"neck", "vertebra_T1"},         // C7: the lowest cervical joint
      {"vertebra_C6", "neck"},
      {"vertebra_C1", "vertebra_C6"},
      {"head", "vertebra_C1"},         // the skull, on the atlas although the sternum touches it
      {"left_clavicle", "vertebra_T1"},  // on the sternum, which rides with T1 through rib 1
      {"right_clavicle", "vertebra_T1"},
      {"left_scapula", "left_clavicle"},
      {"right_scapula", "right_clavicle"},
      {"left_shoulder", "left_scapula"},  // 4 mm from the scapula, though it touches rib 2
      {"right_shoulder", "right_scapula"},
      {"left_hip", "pelvis"},
      {"right_hip", "pelvis"}};
  EXPECT_EQ(r.skeleton.size(), parents.size());
  for (const auto& [name, parent] : parents) EXPECT_EQ(parentOf(r, name), parent) << name;
  // Ribs ride with a thoracic vertebra (rib 2 touches L5 closer, 4 mm, than T1, 6 mm), the sternum
  // with them, patellae with the femur.
  EXPECT_TRUE(hasLabel(jointNamed(r, "vertebra_T1"), 11) && hasLabel(jointNamed(r, "vertebra_T1"), 21));
  EXPECT_TRUE(hasLabel(jointNamed(r, "vertebra_T1"), 12) && hasLabel(jointNamed(r, "vertebra_T1"), 22));
  EXPECT_TRUE(hasLabel(jointNamed(r, "vertebra_T1"), 9));
  EXPECT_TRUE(hasLabel(jointNamed(r, "left_hip"), 17));
  EXPECT_TRUE(hasLabel(jointNamed(r, "right_hip"), 27));
  for (const Joint& j : r.skeleton.joints) EXPECT_TRUE(isStandardJointName(j.name)) << j.name;
  // The head turns where the skull meets the atlas (z 106..112), not at the sternum (y -60).
  const Joint* head = jointNamed(r, "head");
  ASSERT_NE(head, nullptr);
  EXPECT_NEAR(head->center.z(), 109, 3);
  EXPECT_GT(head->center.y(), 0);
  // The clavicle turns where it meets the sternum (x 8..10, y -62..-60, z 100..104).
  const V3 sc = jointNamed(r, "left_clavicle")->center;
  EXPECT_LT((sc - V3(9, -61, 102)).norm(), 3) << sc.transpose();
}

TEST(AutoRigRules, WithoutCervicalVertebraeTheSkullIsTheNeck) {
  Trunk trunk;
  for (int cervical : {5, 6, 7})
    for (std::int32_t& v : trunk.v.data)
      if (v == cervical) v = 1;
  // Now the skull lies 40 mm above T1: beyond every gap, and anatomy allows no sternum as parent.
  AutoRigResult r = autoRig(trunk.v, trunk.t);
  EXPECT_EQ(r.skeleton.find("head"), -1);
  EXPECT_EQ(r.skeleton.find("neck"), -1) << r.report.text();
  bool leftOut = false;
  for (const AutoRigReport::Bone& b : r.report.bones)
    if (b.name == "skull") leftOut = b.joint.empty() && b.note.find("forbids") != std::string::npos;
  EXPECT_TRUE(leftOut) << r.report.text();
  // Bring T1 up to the skull: the skull hangs from it as "neck" (no cervical joint below it).
  paintBox(trunk.v, V3(-15, 5, 72), V3(15, 30, 106), 4);
  r = autoRig(trunk.v, trunk.t);
  EXPECT_EQ(parentOf(r, "neck"), "vertebra_T1") << r.report.text();
  EXPECT_TRUE(hasLabel(jointNamed(r, "neck"), 8));
}

TEST(AutoRigRules, APatellaRidesWithItsFemurWhereverItLies) {
  // Patellae in front of the tiny phantom's knees: the left one nearer the femur, the right one
  // nearer the tibia. Both ride with their femur: the same on every body.
  Phantom ph = makePhantom(PhantomSize::Tiny);
  LabelTable table = phantomTable(ph);
  table.labels.push_back({40, "patella_left", LabelKind::Bone});
  table.labels.push_back({41, "patella_right", LabelKind::Bone});
  const double knee = ph.skeleton.joints[ph.skeleton.find("left_knee")].center.z();
  const double kneeX = ph.skeleton.joints[ph.skeleton.find("left_knee")].center.x();
  auto soft = [](int v) { return !isPhantomBone(v) && v != 0; };
  const auto left = paintBox(ph.labels, V3(kneeX - 12, -50, knee + 4), V3(kneeX + 12, -30, knee + 30), 40, soft);
  const auto right = paintBox(ph.labels, V3(-kneeX - 12, -50, knee - 30), V3(-kneeX + 12, -30, knee - 4), 41, soft);
  ASSERT_GE(left.size(), 8u);
  ASSERT_GE(right.size(), 8u);
  const AutoRigResult r = autoRig(ph.labels, table);
  std::printf("%s", r.report.text().c_str());
  EXPECT_EQ(r.skeleton.size(), ph.skeleton.size());
  EXPECT_TRUE(hasLabel(jointNamed(r, "left_hip"), 40)) << r.report.text();
  EXPECT_TRUE(hasLabel(jointNamed(r, "right_hip"), 41)) << r.report.text();
  expectRecovers(ph, r);
}

TEST(AutoRigRules, FragmentsOfASplitLabelGoToTheirOwnSide) {
  // Both feet under one label "foot"; the right foot's toes cut off by a slab of muscle, a crumb
  // of the foot label against the right tibia, and one far in the belly.
  Phantom ph = makePhantom(PhantomSize::Tiny);
  LabelTable table = phantomTable(ph);
  mergeLabels(ph, table, phantom_label::FootRight, phantom_label::FootLeft, "foot");
  const Phantom original = makePhantom(PhantomSize::Tiny);
  const std::size_t farVoxel = softVoxelFarFromBone(original, 60);
  ASSERT_NE(farVoxel, std::size_t(-1));
  const ImageGrid& g = ph.labels.grid;
  auto isFoot = [](int v) { return v == phantom_label::FootLeft; };
  paintBox(ph.labels, V3(-400, -104, -1000), V3(0, -96, 0), phantom_label::Muscle, isFoot);  // cut the right toes
  std::vector<std::size_t> toes;
  for (std::size_t p = 0; p < g.voxelCount(); ++p) {
    const V3 x = g.indexToPhysical(V3(double(p % g.dims[0]), double((p / g.dims[0]) % g.dims[1]),
                                      double(p / (std::size_t(g.dims[0]) * g.dims[1]))));
    if (ph.labels.data[p] == phantom_label::FootLeft && x.x() < 0 && x.y() < -104) toes.push_back(p);
  }
  ASSERT_GE(toes.size(), 3u);
  // A crumb touching the right tibia at mid-shank, outside it.
  const Joint& rk = ph.skeleton.joints[ph.skeleton.find("right_knee")];
  const Joint& ra = ph.skeleton.joints[ph.skeleton.find("right_ankle")];
  const V3 mid = 0.5 * (rk.center + ra.center);
  std::size_t crumb = std::size_t(-1);
  for (int di = 1; di < 6 && crumb == std::size_t(-1); ++di) {
    const V3 ijk = g.physicalToIndex(mid).array().round();
    const int i = int(ijk.x()) + di, j = int(ijk.y()), k = int(ijk.z());
    if (ph.labels.at(i, j, k) != phantom_label::TibiaRight && ph.labels.at(i - 1, j, k) == phantom_label::TibiaRight)
      crumb = g.linearIndex(i, j, k);
    const int i2 = int(ijk.x()) - di;
    if (crumb == std::size_t(-1) && ph.labels.at(i2, j, k) != phantom_label::TibiaRight &&
        ph.labels.at(i2 + 1, j, k) == phantom_label::TibiaRight)
      crumb = g.linearIndex(i2, j, k);
  }
  ASSERT_NE(crumb, std::size_t(-1));
  ph.labels.data[crumb] = phantom_label::FootLeft;
  ph.labels.data[farVoxel] = phantom_label::FootLeft;
  // A crumb beside the right tibia's lowest voxel: it touches the tibia, but its own foot lies
  // within reach, and the label says it is foot.
  std::size_t ankleCrumb = std::size_t(-1);
  for (int k = 0; k < g.dims[2] && ankleCrumb == std::size_t(-1); ++k)
    for (int j = 0; j < g.dims[1] && ankleCrumb == std::size_t(-1); ++j)
      for (int i = 0; i + 1 < g.dims[0] && ankleCrumb == std::size_t(-1); ++i)
        if (ph.labels.at(i, j, k) == phantom_label::TibiaRight && ph.labels.at(i + 1, j, k) != phantom_label::TibiaRight)
          ankleCrumb = g.linearIndex(i + 1, j, k);
  ASSERT_NE(ankleCrumb, std::size_t(-1));
  ph.labels.data[ankleCrumb] = phantom_label::FootLeft;

  const AutoRigResult r = autoRig(ph.labels, table);
  std::printf("%s", r.report.text().c_str());
  const int footLeft = valueNamed(r, "foot_left"), footRight = valueNamed(r, "foot_right");
  const int tibiaRight = phantom_label::TibiaRight;
  ASSERT_GT(footLeft, 0);
  ASSERT_GT(footRight, 0);
  EXPECT_EQ(r.skeleton.size(), 15u);  // no joint for a fragment
  EXPECT_EQ(jointNamed(r, "right_ankle")->labels, std::vector<int>{footRight});
  EXPECT_EQ(jointNamed(r, "left_ankle")->labels, std::vector<int>{footLeft});
  for (std::size_t p : toes) EXPECT_EQ(r.labels.data[p], footRight) << "a right toe voxel";
  EXPECT_EQ(r.labels.data[crumb], tibiaRight);
  EXPECT_EQ(r.labels.data[ankleCrumb], footRight);
  // Every voxel of the original right foot is under the right foot's value.
  for (std::size_t p = 0; p < g.voxelCount(); ++p)
    if (original.labels.data[p] == phantom_label::FootRight && ph.labels.data[p] == phantom_label::FootLeft) {
      ASSERT_EQ(r.labels.data[p], footRight);
    }
  // The far crumb is soft tissue under a label of its own, and said so.
  const int unassigned = valueNamed(r, "unassigned_bone_fragments");
  ASSERT_GT(unassigned, 0);
  EXPECT_EQ(r.table.find(unassigned)->kind, LabelKind::Soft);
  EXPECT_EQ(r.labels.data[farVoxel], unassigned);
  for (const Joint& j : r.skeleton.joints) EXPECT_FALSE(hasLabel(&j, unassigned));
  EXPECT_EQ(r.report.noiseComponents, 1u);
  EXPECT_EQ(r.report.noiseVoxels, 1u);
  EXPECT_EQ(r.report.fragmentsReassigned, 3u);
  EXPECT_EQ(r.report.fragmentVoxelsReassigned, toes.size() + 2);
  const std::string text = r.report.text();
  EXPECT_NE(text.find("-> foot_right (label " + std::to_string(footRight) + "): nearest foot on its side"),
            std::string::npos);
  EXPECT_NE(text.find("touches tibia_right"), std::string::npos);
  EXPECT_NE(text.find("left as soft tissue"), std::string::npos);
  // Rigging the result again moves nothing (the toes are still a piece apart, under their foot).
  const AutoRigResult again = autoRig(r.labels, r.table);
  EXPECT_EQ(again.labels.data, r.labels.data);
  EXPECT_EQ(again.report.noiseVoxels, 0u);
  for (const AutoRigReport::Fragment& f : again.report.fragments) EXPECT_EQ(f.value, f.sourceLabel) << f.label;
}

TEST(AutoRigRules, SmallPiecesAreNeverJoints) {
  // A skull cap cut off the skull (a midline bone holds one), and a piece cut off the left
  // humerus of a label holding both humeri (one per side): neither becomes a joint.
  Phantom ph = makePhantom(PhantomSize::Tiny);
  LabelTable table = phantomTable(ph);
  const ImageGrid& g = ph.labels.grid;
  const double top = g.indexToPhysical(V3(0, 0, g.dims[2] - 1)).z();
  auto is = [](int label) { return [label](int v) { return v == label; }; };
  double skullTop = -1e9;
  for (std::size_t p = 0; p < g.voxelCount(); ++p)
    if (ph.labels.data[p] == phantom_label::Skull)
      skullTop = std::max(skullTop, g.indexToPhysical(V3(0, 0, double(p / (std::size_t(g.dims[0]) * g.dims[1])))).z());
  ASSERT_LT(skullTop, top);
  paintBox(ph.labels, V3(-500, -500, skullTop - 45), V3(500, 500, skullTop - 35), phantom_label::Brain,
           is(phantom_label::Skull));
  mergeLabels(ph, table, phantom_label::HumerusRight, phantom_label::HumerusLeft, "humerus");
  const Joint& elbow = ph.skeleton.joints[ph.skeleton.find("left_elbow")];
  paintBox(ph.labels, V3(0, -500, elbow.center.z() + 50), V3(500, 500, elbow.center.z() + 59.9), phantom_label::Muscle,
           is(phantom_label::HumerusLeft));
  const AutoRigResult r = autoRig(ph.labels, table);
  std::printf("%s", r.report.text().c_str());
  EXPECT_EQ(r.skeleton.size(), 15u);
  for (const Joint& j : r.skeleton.joints) EXPECT_TRUE(isStandardJointName(j.name)) << j.name;
  EXPECT_EQ(jointNamed(r, "neck")->labels, std::vector<int>{phantom_label::Skull});
  EXPECT_EQ(r.report.fragmentsReassigned, 2u);
  EXPECT_TRUE(r.report.missingBones.empty());
  const int humerusLeft = valueNamed(r, "humerus_left");
  EXPECT_EQ(jointNamed(r, "left_shoulder")->labels, std::vector<int>{humerusLeft});
  // Every voxel of the left arm's humerus label (x > 0) is under the left humerus, the cap under the skull.
  for (std::size_t p = 0; p < g.voxelCount(); ++p) {
    const double x = g.indexToPhysical(V3(double(p % g.dims[0]), 0, 0)).x();
    if (ph.labels.data[p] == phantom_label::Skull) {
      ASSERT_EQ(r.labels.data[p], phantom_label::Skull);
    } else if (ph.labels.data[p] == phantom_label::HumerusLeft && x > 0) {
      ASSERT_EQ(r.labels.data[p], humerusLeft);
    }
  }
  expectRecovers(makePhantom(PhantomSize::Tiny), r);
}

TEST(AutoRigRules, ALabelTheRigDoesNotKnowHoldsBonesAboveTheStatedSize) {
  // An unrecognised bone label with two pieces: the second is a bone of its own only from 25 % of
  // the largest (and 0.5 ml) on.
  for (const auto& [second, bones] : std::vector<std::pair<int, std::size_t>>{{20, 1}, {30, 2}}) {
    LabelVolume v;
    v.grid.spacing = V3(2, 2, 2);
    v.grid.dims = {60, 20, 20};
    v.data.assign(v.grid.voxelCount(), 1);
    paintBox(v, V3(0, 10, 10), V3(38, 26, 26), 5);             // 20 x 9 x 9 voxels
    paintBox(v, V3(60, 10, 10), V3(58 + 2 * (second / 5), 26, 26), 5);  // `second` % of it
    const AutoRigResult r = autoRig(v, parseLabelTable("1\tmuscle\n5\timplant\tbone\n"));
    EXPECT_EQ(r.report.bones.size(), bones) << r.report.text();
    EXPECT_EQ(r.report.fragments.size(), 2 - bones) << r.report.text();
  }
}

TEST(AutoRigRules, TheWrongTableIsAClearError) {
  const Phantom ph = makePhantom(PhantomSize::Tiny);
  try {
    autoRig(ph.labels, builtinTotalSegmentatorTable());
    FAIL() << "the TotalSegmentator names on the phantom: expected an error";
  } catch (const std::invalid_argument& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("the built-in TotalSegmentator table does not match the label volume: 11 of 11 bone labels"),
              std::string::npos)
        << m;
    EXPECT_EQ(m.find('\n'), std::string::npos);
  }
  AutoRigOptions unchecked;
  unchecked.checkTable = false;
  EXPECT_LT(autoRig(ph.labels, builtinTotalSegmentatorTable(), unchecked).skeleton.size(), 15u);
}

TEST(AutoRigRules, TouchingSidesOfOneLabelAreHalvedAtTheMidline) {
  // Both feet under one label, joined by a bridge of the same label between them (feet together):
  // one component across the midline, halved into the left and the right foot.
  Phantom ph = makePhantom(PhantomSize::Tiny);
  LabelTable table = phantomTable(ph);
  mergeLabels(ph, table, phantom_label::FootRight, phantom_label::FootLeft, "foot");
  const V3 ankle = ph.skeleton.joints[ph.skeleton.find("left_ankle")].center;
  const auto bridge = paintBox(ph.labels, V3(-70, -60, ankle.z() - 50), V3(70, -20, ankle.z() - 30),
                               phantom_label::FootLeft, [](int v) { return !isPhantomBone(v); });
  ASSERT_GE(bridge.size(), 4u);
  const AutoRigResult r = autoRig(ph.labels, table);
  std::printf("%s", r.report.text().c_str());
  const int left = valueNamed(r, "foot_left"), right = valueNamed(r, "foot_right");
  ASSERT_GT(left, 0);
  ASSERT_GT(right, 0);
  EXPECT_EQ(jointNamed(r, "left_ankle")->labels, std::vector<int>{left});
  EXPECT_EQ(jointNamed(r, "right_ankle")->labels, std::vector<int>{right});
  EXPECT_EQ(r.skeleton.size(), 15u);
  const ImageGrid& g = ph.labels.grid;
  double midX = 0;  // the phantom is symmetric about x = 0
  for (std::size_t p = 0; p < g.voxelCount(); ++p) {
    if (ph.labels.data[p] != phantom_label::FootLeft) continue;
    const double x = g.indexToPhysical(V3(double(p % g.dims[0]), 0, 0)).x();
    ASSERT_EQ(r.labels.data[p], x > midX ? left : right) << x;
  }
  EXPECT_NE(r.report.text().find("at the mid-sagittal plane"), std::string::npos);
}
