// Bone names by anatomy: recognition across spellings, and the joint vocabulary.
#include <gtest/gtest.h>

#include <fstream>
#include <set>
#include <sstream>

#include "anatomy_names.h"
#include "label_table.h"
#include "phantom.h"

using namespace repose;
using T = BoneType;
using S = BoneSide;

namespace {

void expectBone(const std::string& name, T type, S side, const std::string& level = "") {
  const BoneName b = recogniseBone(name);
  EXPECT_EQ(int(b.type), int(type)) << name << ": " << boneTypeName(b.type);
  EXPECT_EQ(int(b.side), int(side)) << name;
  EXPECT_EQ(b.level, level) << name;
}

}  // namespace

TEST(AnatomyNames, OneFemurInEverySpelling) {
  for (const char* n : {"femur_left", "Femur_L", "femur.L", "left femur", "LFemur", "Femur left", "FEMUR_LEFT",
                        "lfemur", "Left-Femur", "femurL", "Femur (lt)", "femur sinister", "LeftFemur"})
    expectBone(n, T::Femur, S::Left);
  for (const char* n : {"femur_right", "Femur_R", "femur.R", "right femur", "RFemur", "Femur right", "Femur_rt"})
    expectBone(n, T::Femur, S::Right);
  expectBone("femur", T::Femur, S::None);
  expectBone("Femora, upper half", T::Femur, S::None);
  expectBone("femoral head", T::Femur, S::None);
}

TEST(AnatomyNames, TablesOfTotalSegmentatorThePhantomVisibleHumanIcrpAndSlicer) {
  // TotalSegmentator "total" and appendicular names.
  expectBone("vertebrae_C1", T::Vertebra, S::None, "C1");
  expectBone("vertebrae_T12", T::Vertebra, S::None, "T12");
  expectBone("vertebrae_S1", T::Vertebra, S::None, "S1");
  expectBone("rib_left_3", T::Rib, S::Left, "3");
  expectBone("clavicula_right", T::Clavicle, S::Right);
  expectBone("scapula_left", T::Scapula, S::Left);
  expectBone("humerus_right", T::Humerus, S::Right);
  expectBone("hip_left", T::HipBone, S::Left);
  expectBone("costal_cartilages", T::CostalCartilage, S::None);
  expectBone("phalanges_feet", T::Foot, S::None);
  expectBone("phalanges_hand", T::Hand, S::None);
  expectBone("carpal", T::Hand, S::None);
  expectBone("metatarsal", T::Foot, S::None);
  for (const char* soft : {"iliac_artery_left", "iliac_vena_right", "spinal_cord", "subclavian_artery_left",
                           "gluteus_maximus_left", "iliopsoas_right", "autochthon_left", "kidney_left", "brain",
                           "renal pelvis", "femoral artery", "vertebral disc"})
    EXPECT_FALSE(recogniseBone(soft).known()) << soft;
  // The phantom.
  expectBone("skull", T::Skull, S::None);
  expectBone("spine", T::Spine, S::None);
  expectBone("ribcage", T::Ribcage, S::None);
  expectBone("pelvis", T::Pelvis, S::None);
  expectBone("forearm_left", T::Forearm, S::Left);
  expectBone("hand_right", T::Hand, S::Right);
  expectBone("foot_left", T::Foot, S::Left);
  expectBone("tibia_right", T::Tibia, S::Right);
  // Visible Human (HRA) files.
  expectBone("fibula_left", T::Fibula, S::Left);
  expectBone("patella_left", T::Patella, S::Left);
  expectBone("sacrum", T::Sacrum, S::None);
  expectBone("coccyx", T::Coccyx, S::None);
  // ICRP-style names (several bones or halves per label, no side).
  expectBone("Humeri, upper half", T::Humerus, S::None);
  expectBone("Humeri,_lower_half,_spongiosa", T::Humerus, S::None);
  expectBone("Ulnae and radii", T::Ulna, S::None);
  expectBone("Wrists and hand bones", T::Hand, S::None);
  expectBone("Tibiae, fibulae and patellae", T::Tibia, S::None);
  expectBone("Ankles and foot bones", T::Foot, S::None);
  expectBone("Clavicles", T::Clavicle, S::None);
  expectBone("Scapulae", T::Scapula, S::None);
  expectBone("Cranium", T::Skull, S::None);
  expectBone("Mandible", T::Mandible, S::None);
  expectBone("Os coxae", T::HipBone, S::None);
  expectBone("Cervical spine", T::CervicalSpine, S::None);
  expectBone("Thoracic spine", T::ThoracicSpine, S::None);
  expectBone("Lumbar spine", T::LumbarSpine, S::None);
  expectBone("Ribs", T::Rib, S::None);
  expectBone("rib cage", T::Ribcage, S::None);
  expectBone("Sternum", T::Sternum, S::None);
  // Slicer-style and other common ones.
  expectBone("Left_Humerus", T::Humerus, S::Left);
  expectBone("Right-Tibia", T::Tibia, S::Right);
  expectBone("L4", T::Vertebra, S::None, "L4");
  expectBone("T12 vertebra", T::Vertebra, S::None, "T12");
  expectBone("Kneecap R", T::Patella, S::Right);
}

TEST(AnatomyNames, EveryTotalSegmentatorBoneIsRecognisedWithItsSide) {
  std::ifstream in(REPOSE_SHARED_DATA "/totalsegmentator/labels_total_v2.tsv");
  ASSERT_TRUE(in.good());
  std::stringstream ss;
  ss << in.rdbuf();
  int bones = 0;
  for (const LabelInfo& l : parseLabelTable(ss.str()).labels) {
    if (l.kind != LabelKind::Bone) continue;
    ++bones;
    const BoneName b = recogniseBone(l.name);
    EXPECT_TRUE(b.known()) << l.name;
    const bool left = l.name.find("_left") != std::string::npos, right = l.name.find("_right") != std::string::npos;
    EXPECT_EQ(int(b.side), int(left ? S::Left : right ? S::Right : S::None)) << l.name;
  }
  EXPECT_EQ(bones, 62);
}

TEST(AnatomyNames, JointNamesKeepThePhantomsAndTheRigsNames) {
  // Every bone the phantom rotates maps onto the name its skeleton uses.
  const Phantom ph = describePhantom(PhantomSize::Tiny);
  for (const Joint& j : ph.skeleton.joints) {
    if (j.name == "pelvis" || j.name == "spine") continue;  // named by their place in the tree
    for (const auto& [value, name] : ph.labelNames) {
      if (value == j.labels[0]) {
        EXPECT_EQ(standardJointName(name), j.name) << name;
      }
    }
  }
  EXPECT_EQ(standardJointName("Femur_L"), "left_hip");
  EXPECT_EQ(standardJointName("left femur"), "left_hip");
  EXPECT_EQ(standardJointName("fibula_right"), "right_knee");
  EXPECT_EQ(standardJointName("Ulnae and radii"), "");  // no side: the rig gives it one by position
  EXPECT_EQ(jointNameOf(T::Ulna, S::Left), "left_elbow");
  EXPECT_EQ(jointNameOf(T::Hand, S::Right), "right_wrist");
  EXPECT_EQ(jointNameOf(T::Foot, S::Left), "left_ankle");
  EXPECT_EQ(jointNameOf(T::Clavicle, S::Left), "left_clavicle");
  EXPECT_EQ(jointNameOf(T::Scapula, S::Right), "right_scapula");
  EXPECT_EQ(standardJointName("vertebrae_L4"), "vertebra_L4");
  EXPECT_EQ(standardJointName("Cervical spine"), "neck");
  EXPECT_EQ(standardJointName("Thoracic spine"), "chest");
  EXPECT_EQ(standardJointName("mandible"), "jaw");
  EXPECT_EQ(standardJointName("patella_left"), "");  // rides with the femur
  EXPECT_EQ(standardJointName("rib_left_3"), "");    // rides with the spine
  EXPECT_EQ(standardJointName("kidney_left"), "");
}

TEST(AnatomyNames, Vocabulary) {
  std::set<std::string> names;
  int limbs = 0, girdles = 0;
  for (const StandardJoint& j : standardJoints()) {
    EXPECT_TRUE(names.insert(j.name).second) << j.name;
    EXPECT_TRUE(isStandardJointName(j.name));
    EXPECT_EQ(isLimbJoint(j.name), j.region == JointRegion::Limb);
    EXPECT_EQ(isGirdleJoint(j.name), j.region == JointRegion::Girdle);
    limbs += j.region == JointRegion::Limb;
    girdles += j.region == JointRegion::Girdle;
    if (j.region != JointRegion::Trunk) {
      EXPECT_EQ(int(jointSide(j.name)) != int(S::None), true) << j.name;
      EXPECT_TRUE(names.count(mirrorJointName(j.name)) || isStandardJointName(mirrorJointName(j.name))) << j.name;
      EXPECT_NE(mirrorJointName(j.name), j.name);
    }
  }
  EXPECT_EQ(limbs, 12);
  EXPECT_EQ(girdles, 4);
  EXPECT_EQ(names.size(), 22u);
  for (const char* n : {"pelvis", "spine", "chest", "neck", "head", "jaw", "left_hip", "right_knee", "left_ankle",
                        "right_shoulder", "left_elbow", "right_wrist", "left_scapula", "right_clavicle",
                        "vertebra_L4", "vertebra_C1", "vertebra_T12", "vertebra_S1"})
    EXPECT_TRUE(isStandardJointName(n)) << n;
  for (const char* n : {"vertebra_L6", "vertebra_C8", "vertebra_l4", "left_patella", "hip", "femur_left", ""})
    EXPECT_FALSE(isStandardJointName(n)) << n;
  EXPECT_TRUE(isLimbJoint("left_knee"));
  EXPECT_FALSE(isLimbJoint("left_scapula"));
  EXPECT_TRUE(isGirdleJoint("right_clavicle"));
  EXPECT_FALSE(isLimbJoint("spine"));
  EXPECT_FALSE(isLimbJoint("vertebra_L4"));
  EXPECT_EQ(mirrorJointName("left_knee"), "right_knee");
  EXPECT_EQ(mirrorJointName("right_wrist"), "left_wrist");
  EXPECT_EQ(mirrorJointName("neck"), "neck");
  EXPECT_EQ(int(jointSide("left_hip")), int(S::Left));
  EXPECT_EQ(int(jointSide("pelvis")), int(S::None));
}
