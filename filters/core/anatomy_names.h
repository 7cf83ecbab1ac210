#pragma once
// Bones and joints by anatomy. recogniseBone() reads the bone a label names whatever the spelling
// (TotalSegmentator, the built-in phantom, Visible Human/HRA files, 3D Slicer and ICRP-style
// tables); the joint vocabulary below is what the automatic rig names its joints, so pose files
// and motion maps can rely on it whatever the label table calls the bones.
//
// Joint vocabulary (every name the rig gives a recognised bone; LEFT/RIGHT = left_/right_):
//   pelvis             root: hip bones, sacrum, coccyx, S vertebrae (one rigid group)
//   spine              the lowest joint of the spine above the pelvis: the vertebra (or the
//                      spine / lumbar spine label) that rests on the pelvis
//   chest              a thoracic spine labelled as one bone
//   neck               the lowest cervical joint (C7, or a cervical spine label); the skull's
//                      joint when no cervical bone lies below it (the phantom)
//   head               the skull, when a neck joint lies below it
//   jaw                the mandible (child of the skull's joint)
//   vertebra_<level>   every other vertebra labelled on its own: vertebra_C1 ... vertebra_L5
//   LEFT/RIGHT clavicle  the clavicle (child of the joint carrying the sternum, else the trunk)
//   LEFT/RIGHT scapula   the scapula (child of its clavicle, else of the trunk)
//   LEFT/RIGHT shoulder  the humerus (child of its scapula, else of the trunk)
//   LEFT/RIGHT elbow     the forearm: radius and ulna together
//   LEFT/RIGHT wrist     the hand: carpals, metacarpals, phalanges
//   LEFT/RIGHT hip       the femur, with its patella (see below)
//   LEFT/RIGHT knee      the shank: tibia and fibula together
//   LEFT/RIGHT ankle     the foot: tarsals, metatarsals, phalanges
// A bone whose name is not recognised keeps its label name as its joint's name. Names are made
// unique with _2, _3 (two bones of one kind and side, as a hand whose fingers lie apart).
// Ribs, sternum and costal cartilage (when labelled as bone) ride with the thoracic vertebra (or
// spine) they articulate with; they are never joints, and never parents of the neck or the head.
// The patella rides with its femur: it sits in the femoral trochlea, no motion format drives a
// patella of its own, and a joint of its own would only add an undriven name.
#include <string>
#include <vector>

namespace repose {

enum class BoneSide { None, Left, Right };

/// The bones the rig knows. Types marked "group" are several bones in one label.
enum class BoneType {
  Unknown,  ///< not a bone name the rig knows (a bone label may still be a bone by its table kind)
  Skull, Mandible,
  Vertebra,  ///< one vertebra, BoneName::level says which
  CervicalSpine, ThoracicSpine, LumbarSpine, Spine,  ///< group: a region, or the whole spine
  Sacrum, Coccyx, HipBone, Pelvis,  ///< Pelvis: group (hip bones + sacrum)
  Rib, Ribcage, Sternum, CostalCartilage,  ///< Ribcage: group
  Clavicle, Scapula, Humerus, Radius, Ulna, Forearm, Hand,  ///< Forearm, Hand: groups
  Femur, Patella, Tibia, Fibula, Foot,  ///< Foot: group
};

struct BoneName {
  BoneType type = BoneType::Unknown;
  BoneSide side = BoneSide::None;  ///< from the name alone; None when the name gives no side
  std::string level;               ///< vertebra: "C1".."C7", "T1".."T12", "L1".."L5", "S1".."S5";
                                   ///< rib: "1".."12" (the thoracic vertebra it articulates with)
  bool known() const { return type != BoneType::Unknown; }
};

/// The bone a label name denotes. Case, separators and word order do not matter: femur_left,
/// Femur_L, femur.L, "left femur", LFemur, "Femur left" and "Femora, upper half" are all femurs;
/// sides are left/l/lt/sinister or right/r/rt/dexter, also glued on (LFemur, rFemur); Latin and
/// plural forms (humeri, claviculae, os coxae, costae) and several bones in one label ("Tibiae,
/// fibulae and patellae": the first one named) are understood. Names of soft tissue that mention a
/// bone (iliac_artery_left, spinal_cord, renal pelvis, costal cartilage is CostalCartilage) are
/// Unknown, except costal cartilage, which has a type of its own (it is soft by default).
BoneName recogniseBone(const std::string& labelName);

/// True when a label name is bone tissue: a recognised bone other than costal cartilage, or a
/// generic word (bone, bones, skeleton, osseous, phalanges, ossicles) without a soft-tissue word.
bool namesBone(const std::string& labelName);

/// "femur", "vertebra", ...: a lower-case word for messages.
const char* boneTypeName(BoneType type);
/// Bones of which a body has one, on the midline (skull, mandible, vertebrae, spine, sacrum,
/// coccyx, pelvis, sternum, ribcage).
bool isMidlineBone(BoneType type);
/// Bones of which a body has one per side (limbs, girdles, hip bones, ribs).
bool isPairedBone(BoneType type);

/// Trunk: pelvis, spine, chest, neck, head, jaw, vertebrae. Girdle: clavicle and scapula (motion
/// formats seldom drive them). Limb: hip, knee, ankle, shoulder, elbow, wrist.
enum class JointRegion { Trunk, Girdle, Limb };

/// The vocabulary: one entry per name (vertebrae as the pattern "vertebra_<level>").
struct StandardJoint {
  const char* name;     ///< "left_knee"
  const char* rotates;  ///< "tibia and fibula": the bones the joint moves (for help texts)
  JointRegion region;
};
/// Every joint name of the vocabulary, trunk first, then left and right girdles and limbs.
const std::vector<StandardJoint>& standardJoints();
/// True for the names of standardJoints() and for vertebra_C1 ... vertebra_S5.
bool isStandardJointName(const std::string& name);
/// True for left_/right_ hip, knee, ankle, shoulder, elbow, wrist: the joints a motion clip is
/// expected to drive.
bool isLimbJoint(const std::string& name);
/// True for left_/right_ clavicle and scapula.
bool isGirdleJoint(const std::string& name);
/// The side of a joint name: Left for "left_...", Right for "right_...", else None.
BoneSide jointSide(const std::string& name);
/// "left_knee" <-> "right_knee"; other names unchanged.
std::string mirrorJointName(const std::string& name);

/// The joint name of a bone of this type and side when it is the bone's own joint (femur ->
/// hip, tibia and fibula -> knee, foot bones -> ankle, humerus -> shoulder, radius/ulna/forearm ->
/// elbow, hand bones -> wrist, clavicle, scapula, mandible -> jaw, vertebra -> vertebra_<level>,
/// skull -> neck, spine regions -> spine/chest/neck, hip bones, sacrum, coccyx, S vertebrae ->
/// pelvis). Context-dependent renames (the vertebra on the pelvis -> spine, the lowest cervical
/// joint -> neck, the skull above a neck -> head) are the rig's. "" for bones that are never
/// joints of their own (ribs, sternum, costal cartilage, patella), for paired bones without a
/// side, and for names it does not know.
std::string jointNameOf(BoneType type, BoneSide side, const std::string& level = "");

/// The joint name autoRig gives a bone named `labelName` on its own ("" when the name is not
/// recognised or the bone is never a joint of its own): jointNameOf(recogniseBone(labelName)).
std::string standardJointName(const std::string& labelName);

}  // namespace repose
