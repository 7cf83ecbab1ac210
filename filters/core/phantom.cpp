#include "phantom.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "parallel_for.h"

namespace repose {

PhantomSize parsePhantomSize(const std::string& name) {
  if (name == "tiny") return PhantomSize::Tiny;
  if (name == "small") return PhantomSize::Small;
  if (name == "medium") return PhantomSize::Medium;
  if (name == "large") return PhantomSize::Large;
  throw std::invalid_argument("unknown phantom size '" + name +
                              "': use one of tiny, small, medium, large");
}

PhantomRestPose parsePhantomRestPose(const std::string& name) {
  if (name == "apart") return PhantomRestPose::Apart;
  if (name == "contact") return PhantomRestPose::Contact;
  throw std::invalid_argument("unknown phantom rest pose '" + name + "': use apart or contact");
}

namespace {

using V3 = Eigen::Vector3d;

// Implicit primitives in physical space (mm, LPS). sdf() < 0 inside. Outside, the value never
// exceeds the true distance (ellipsoids use the Lipschitz bound), so carving clearances are safe.
enum class Kind { Sphere, Capsule, Cone, Ellipsoid, EllipsoidShell, Cup, Ring, EllipticCylinder };

struct Prim {
  Kind kind = Kind::Sphere;
  V3 a = V3::Zero(), b = V3::Zero();  // centre, or segment ends
  V3 r = V3::Ones();                  // semi-axes (outer for shells; ring: ar, br)
  V3 rin = V3::Ones();                // inner semi-axes of a shell
  double ra = 0, rb = 0;              // radii at a and b (cup: inner/outer; ring: radial/vertical tube)
  double zmin = 0, zmax = 0;          // cup: lowest z kept; cylinder: z range
  double ymax = 1e30;                 // ring: posterior cut (ribs end short of the spine)
  V3 lo = V3::Zero(), hi = V3::Zero();  // bounding box

  double sdf(const V3& p) const {
    switch (kind) {
      case Kind::Sphere: return (p - a).norm() - ra;
      case Kind::Capsule:
      case Kind::Cone: {
        const V3 ab = b - a;
        const double t = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
        return (p - a - t * ab).norm() - (ra + t * (rb - ra));
      }
      case Kind::Ellipsoid: return ellipsoid(p, r);
      case Kind::EllipsoidShell: return std::max(ellipsoid(p, r), -ellipsoid(p, rin));
      case Kind::Cup: {
        const double d = (p - a).norm();
        return std::max({ra - d, d - rb, zmin - p.z()});
      }
      case Kind::Ring: {
        const double qx = p.x() - a.x(), qy = p.y() - a.y();
        const double k0 = std::hypot(qx / r.x(), qy / r.y());
        const double k1 = std::hypot(qx / (r.x() * r.x()), qy / (r.y() * r.y()));
        const double dr = k1 > 0 ? k0 * (k0 - 1) / k1 : -std::min(r.x(), r.y());
        const double dz = p.z() - a.z();
        return std::max((std::hypot(dr / ra, dz / rb) - 1) * std::min(ra, rb), p.y() - ymax);
      }
      case Kind::EllipticCylinder: {  // semi-axes r at zmin, rin at zmax (equal: a cylinder)
        const double t = std::clamp((p.z() - zmin) / (zmax - zmin), 0.0, 1.0);
        const double ax = r.x() + (rin.x() - r.x()) * t, by = r.y() + (rin.y() - r.y()) * t;
        const double k = std::hypot((p.x() - a.x()) / ax, (p.y() - a.y()) / by);
        return std::max({(k - 1) * std::min(ax, by), zmin - p.z(), p.z() - zmax});
      }
    }
    return 1e30;
  }

  double ellipsoid(const V3& p, const V3& s) const {
    return ((p - a).cwiseQuotient(s).norm() - 1) * s.minCoeff();
  }
};

Prim finish(Prim p) {
  switch (p.kind) {
    case Kind::Sphere: p.lo = p.a.array() - p.ra; p.hi = p.a.array() + p.ra; break;
    case Kind::Capsule:
    case Kind::Cone: {
      const double m = std::max(p.ra, p.rb);
      p.lo = p.a.cwiseMin(p.b).array() - m;
      p.hi = p.a.cwiseMax(p.b).array() + m;
      break;
    }
    case Kind::Ellipsoid:
    case Kind::EllipsoidShell: p.lo = p.a - p.r; p.hi = p.a + p.r; break;
    case Kind::Cup:
      p.lo = p.a.array() - p.rb; p.hi = p.a.array() + p.rb;
      p.lo.z() = std::max(p.lo.z(), p.zmin);
      break;
    case Kind::Ring:
      p.lo = p.a - V3(p.r.x() + p.ra, p.r.y() + p.ra, p.rb);
      p.hi = p.a + V3(p.r.x() + p.ra, p.r.y() + p.ra, p.rb);
      p.hi.y() = std::min(p.hi.y(), p.ymax);
      break;
    case Kind::EllipticCylinder:
      p.lo = V3(p.a.x() - std::max(p.r.x(), p.rin.x()), p.a.y() - std::max(p.r.y(), p.rin.y()), p.zmin);
      p.hi = V3(p.a.x() + std::max(p.r.x(), p.rin.x()), p.a.y() + std::max(p.r.y(), p.rin.y()), p.zmax);
      break;
  }
  return p;
}
Prim sphere(const V3& c, double r) { Prim p; p.kind = Kind::Sphere; p.a = c; p.ra = r; return finish(p); }
Prim capsule(const V3& a, const V3& b, double r) {
  Prim p; p.kind = Kind::Capsule; p.a = a; p.b = b; p.ra = p.rb = r; return finish(p);
}
Prim cone(const V3& a, double ra, const V3& b, double rb) {
  Prim p; p.kind = Kind::Cone; p.a = a; p.b = b; p.ra = ra; p.rb = rb; return finish(p);
}
Prim ellipsoid(const V3& c, const V3& s) { Prim p; p.kind = Kind::Ellipsoid; p.a = c; p.r = s; return finish(p); }
Prim shell(const V3& c, const V3& outer, const V3& inner) {
  Prim p; p.kind = Kind::EllipsoidShell; p.a = c; p.r = outer; p.rin = inner; return finish(p);
}
Prim cup(const V3& c, double rin, double rout, double zmin) {
  Prim p; p.kind = Kind::Cup; p.a = c; p.ra = rin; p.rb = rout; p.zmin = zmin; return finish(p);
}
Prim ring(const V3& c, double ar, double br, double radial, double vertical, double ymax) {
  Prim p; p.kind = Kind::Ring; p.a = c; p.r = V3(ar, br, 0); p.ra = radial; p.rb = vertical; p.ymax = ymax;
  return finish(p);
}
/// Semi-axes (ax0, by) at z0 widening linearly to (ax1, by) at z1.
Prim ellipticCylinder(double cx, double cy, double ax0, double ax1, double by, double z0, double z1) {
  Prim p; p.kind = Kind::EllipticCylinder; p.a = V3(cx, cy, 0); p.r = V3(ax0, by, 1); p.rin = V3(ax1, by, 1);
  p.zmin = z0; p.zmax = z1;
  return finish(p);
}

struct Shape {
  std::vector<Prim> prims;
  V3 lo = V3::Constant(1e30), hi = V3::Constant(-1e30);
  void add(const Prim& p) { prims.push_back(p); lo = lo.cwiseMin(p.lo); hi = hi.cwiseMax(p.hi); }
  bool inBox(const V3& p, double pad = 0) const {
    return (p.array() >= lo.array() - pad).all() && (p.array() <= hi.array() + pad).all();
  }
  double sdf(const V3& p) const {
    double d = 1e30;
    for (const Prim& q : prims)
      if ((p.array() >= q.lo.array()).all() && (p.array() <= q.hi.array()).all()) d = std::min(d, q.sdf(p));
    return d;
  }
  /// Exact enough for clearance tests: evaluates every primitive (no box shortcut).
  double distanceBound(const V3& p) const {
    double d = 1e30;
    for (const Prim& q : prims) d = std::min(d, q.sdf(p));
    return d;
  }
};

/// A bone this one keeps `gap` away from, at rest and through a joint's range of motion: poses[k]
/// maps a point of the carved bone into the carver's frame for the k-th sampled relative rotation
/// about `centre` (identity first). Real joints do not collide within their range; neither may the
/// phantom's, or no deformation of the tissue between two bones could stay un-inverted.
struct Carver {
  int bone = -1;
  V3 centre = V3::Zero();
  std::vector<Eigen::Matrix3d> poses{Eigen::Matrix3d::Identity()};
};

/// A hinge joint's limit on a bone near it: within `reach` of the hinge axis (through `centre`
/// along `axis`), the bone keeps only the points at least `tip` from the axis whose direction from
/// it is within `halfAngle` of `direction`. Two bones so shaped, each in a wedge about the axis,
/// clear each other for any flexion below 180 degrees less both half angles (by at least
/// 2 tip cos(flexion / 2) near the axis): the phantom's stand-in for the rolling condyles of a real
/// knee or elbow, which never meet the opposite bone in flexion.
struct Wedge {
  V3 centre = V3::Zero(), axis = V3::UnitX(), direction = V3::UnitZ();
  double halfAngle = 0, reach = 0, tip = 0;
  bool keeps(const V3& p) const {
    V3 d = p - centre;
    d -= d.dot(axis) * axis;  // a zero axis makes the wedge a cone about `direction`
    const double r = d.norm();
    if (r >= reach) return true;
    return r >= tip && std::acos(std::clamp(d.dot(direction) / r, -1.0, 1.0)) <= halfAngle;
  }
};

struct Bone {
  int label = 0;
  Shape shape;
  std::vector<Carver> carvers;
  std::vector<Wedge> wedges;
  bool inWedges(const V3& p) const {
    for (const Wedge& w : wedges)
      if (!w.keeps(p)) return false;
    return true;
  }
};

/// Relative rotations of a ball joint: Rz(rotation) Ry(abduction) Rx(flexion) over the given
/// ranges (degrees), every `step`.
std::vector<Eigen::Matrix3d> ballRange(double x0, double x1, double y0, double y1, double z0, double z1,
                                       double step = 10) {
  std::vector<Eigen::Matrix3d> out{Eigen::Matrix3d::Identity()};
  const double d2r = 3.14159265358979323846 / 180;
  for (double z = z0; z <= z1 + 1e-9; z += step)
    for (double y = y0; y <= y1 + 1e-9; y += step)
      for (double x = x0; x <= x1 + 1e-9; x += step)
        out.push_back((Eigen::AngleAxisd(z * d2r, V3::UnitZ()) * Eigen::AngleAxisd(y * d2r, V3::UnitY()) *
                       Eigen::AngleAxisd(x * d2r, V3::UnitX())).toRotationMatrix());
  return out;
}

struct Organ {
  int label = 0;
  Prim prim;
};

struct Model {
  ImageGrid grid;
  double gap = 0;       // bone-to-bone clearance at joints (> voxel diagonal)
  double softGap = 0;   // background between arm and torso, between the thighs
  double fat = 12;      // subcutaneous fat depth (mm)
  Shape body;           // union of soft-tissue parts
  std::vector<Bone> bones;
  std::vector<Organ> organs;  // in priority order
  Prim brain;
  Skeleton skeleton;
};

V3 spacingOf(PhantomSize size) {
  switch (size) {
    case PhantomSize::Tiny: return V3(8, 8, 10);
    case PhantomSize::Small: return V3(5, 5, 6.5);
    case PhantomSize::Medium: return V3(3, 3, 4);
    case PhantomSize::Large: return V3(2, 2, 2.5);
  }
  throw std::invalid_argument("unknown phantom size");
}

// Half angles of the hinge wedges (see Wedge): knees clear each other to 180 - 2 * 20 = 140 degrees
// of flexion, elbows to 150. Elbows get cones rather than wedges: motion capture bends them in
// varying planes (the upper arm's twist is not captured), knees about their hinge axis.
constexpr double kKneeWedge = 20 * 3.14159265358979323846 / 180;
constexpr double kElbowWedge = 15 * 3.14159265358979323846 / 180;

// All lengths in mm. Body frame: x = patient left, y = posterior, z = up from the soles; the
// physical frame is shifted down by kSole so the origin is not zero.
constexpr double kSole = -880.0;

// Contact rest pose: surfaces that touch overlap by this much (mm), so no voxel centre of
// background lies between them at any size.
constexpr double kContactOverlap = 2.0;

Model buildModel(PhantomSize size, PhantomRestPose rest) {
  Model m;
  const V3 s = spacingOf(size);
  const bool contact = rest == PhantomRestPose::Contact;
  m.gap = 1.05 * s.norm();
  m.softGap = contact ? -kContactOverlap : 1.05 * s.norm();
  m.fat = std::max(12.0, 2 * s.maxCoeff());  // at least a voxel of fat under the skin
  const double g = m.gap;
  auto P = [](double x, double y, double z) { return V3(x, y, z + kSole); };

  // ---- soft tissue
  const double torsoA = 155, torsoB = 105;
  const double armR = 48;
  const double armX = torsoA + m.softGap + armR;  // arm skin clears the torso by softGap
  const double thighR = 75;
  const double kneeR = 52;
  // Thighs converge toward the knees with their inner surfaces softGap apart all the way down.
  const double legX = m.softGap / 2 + thighR, kneeX = m.softGap / 2 + kneeR;
  // Apart, the torso is a straight elliptic cylinder and the arm hangs straight beside it. In contact
  // the torso narrows to a waist (as people do), the upper arm lies along its side, the forearm
  // passes the hip touching it, and the hand turns in against the thigh; each contact overlaps by
  // kContactOverlap, so the tissues are welded in the voxels.
  const double waistA = contact ? 140 : torsoA;  // torso half-width at z = 860 (up to torsoA at 1360)
  auto torsoHalfWidth = [&](double z) { return waistA + (torsoA - waistA) * (z - 860) / (1360 - 860); };
  auto armRadius = [&](double z) { return armR + (30 - armR) * (1390 - z) / (1390 - 800); };
  auto thighOuter = [&](double z) {
    const double t = (930 - z) / (930 - 490);  // along the thigh cone, hip end to knee end
    return legX + t * (kneeX - legX) + thighR + t * (kneeR - thighR);
  };
  const double elbowZ = 1100, wristZ = 840, handZ = 745, handHalfWidth = 26;
  double elbowX = armX, wristX = armX, handX = armX;
  if (contact) {
    elbowX = torsoHalfWidth(elbowZ) - kContactOverlap + armRadius(elbowZ);
    const double passZ = 930;  // the forearm touches the hip where the thigh is widest
    const double passX = thighOuter(passZ) - kContactOverlap + armRadius(passZ);
    wristX = elbowX + (passX - elbowX) * (elbowZ - wristZ) / (elbowZ - passZ);
    handX = thighOuter(handZ) + handHalfWidth - kContactOverlap;
  }
  m.body.add(ellipticCylinder(0, 0, waistA, torsoA, torsoB, 860 + kSole, 1360 + kSole));
  m.body.add(ellipsoid(P(0, 0, 1360), V3(torsoA, torsoB, 70)));
  m.body.add(ellipsoid(P(0, 0, 860), V3(waistA, torsoB, 30)));
  m.body.add(capsule(P(-(armX - 10), 0, 1390), P(armX - 10, 0, 1390), 58));  // shoulders
  m.body.add(capsule(P(0, 10, 1380), P(0, 10, 1570), 52));                    // neck
  m.body.add(ellipsoid(P(0, 0, 1645), V3(80, 100, 105)));                     // head
  for (double side : {1.0, -1.0}) {
    if (contact) {  // upper arm, forearm: the straight arm's radii at the elbow and the wrist
      m.body.add(cone(P(side * armX, 0, 1390), armR, P(side * elbowX, 2, elbowZ), armRadius(elbowZ)));
      m.body.add(cone(P(side * elbowX, 2, elbowZ), armRadius(elbowZ), P(side * wristX, 3, wristZ), armRadius(wristZ)));
    } else {
      m.body.add(cone(P(side * armX, 0, 1390), armR, P(side * armX, 3, 800), 30));
    }
    m.body.add(ellipsoid(P(side * handX, 0, handZ), V3(handHalfWidth, 48, 100)));  // hand
    m.body.add(cone(P(side * legX, 0, 930), thighR, P(side * kneeX, 5, 490), kneeR));
    m.body.add(cone(P(side * kneeX, 5, 490), kneeR, P(side * kneeX, 10, 85), 36));
    m.body.add(ellipsoid(P(side * kneeX, -45, 45), V3(44, 128, 45)));           // foot
  }

  // ---- joint centres (the articulation centres the bones are built around)
  const V3 lumbosacral = P(0, 50, 1020);
  const V3 skullBase = P(0, 8, 1555);
  const double headR = 20;  // femoral and humeral head radius

  using namespace phantom_label;
  auto bone = [&](int label) -> Bone& {
    m.bones.emplace_back();
    m.bones.back().label = label;
    return m.bones.back();
  };
  // Carvers are set after all bones exist (indices by label).
  // Carvers are swept through their joint's range when `range` is set: `carverMoves` says whether
  // the carver is the joint's moving (child) bone or the carved one is.
  struct CarveRule {
    int bone, carver;
    V3 centre = V3::Zero();
    std::vector<Eigen::Matrix3d> range = {};
    bool carverMoves = false;
  };
  std::vector<CarveRule> rules;

  Skeleton& sk = m.skeleton;
  auto joint = [&](const std::string& name, const std::string& parent, const V3& c, std::vector<int> labels) {
    Joint j;
    j.name = name;
    j.parent = parent.empty() ? -1 : sk.find(parent);
    j.center = c;
    j.labels = std::move(labels);
    sk.joints.push_back(j);
  };

  {  // pelvis: sacrum, iliac wings, acetabular cups, pubic arch
    Bone& b = bone(Pelvis);
    b.shape.add(capsule(P(0, 50, 1020 - g / 2 - 16), P(0, 62, 935), 16));
    for (double side : {1.0, -1.0}) {
      const V3 hip = P(side * (legX + 4), 5, 920);
      b.shape.add(capsule(P(0, 55, 985), P(side * 70, 30, 990), 14));
      b.shape.add(ellipsoid(P(side * 80, 25, 990), V3(52, 15, 45)));
      b.shape.add(cup(hip, headR + g, headR + g + 14, hip.z() - 6));
      b.shape.add(capsule(hip + V3(0, 0, headR + g + 7), P(side * 80, 25, 990), 12));
      const V3 u = V3(-side * 0.75, -0.65, 0).normalized();
      b.shape.add(capsule(hip + (headR + g + 16) * u, P(0, -48, 905), 11));
    }
    // Hip range: flexion 125 degrees (rotation about -x) to extension 30, abduction and adduction
    // 45 (about y), rotation 40 either way (about z), and their combinations.
    for (double side : {1.0, -1.0})
      rules.push_back({Pelvis, side > 0 ? FemurLeft : FemurRight, P(side * (legX + 4), 5, 920),
                       ballRange(-125, 30, -45, 45, -40, 40), true});
    rules.push_back({Pelvis, Spine});
  }
  {
    Bone& b = bone(Spine);
    b.shape.add(capsule(lumbosacral + V3(0, 0, g / 2 + 15), skullBase - V3(0, 0, g / 2 + 15), 15));
  }
  {
    Bone& b = bone(Skull);
    const V3 c = P(0, 0, 1555 + g / 2 + 84);
    b.shape.add(shell(c, V3(66, 84, 84), V3(52, 70, 70)));
    m.brain = ellipsoid(c, V3(52, 70, 70));
    rules.push_back({Skull, Spine});
  }
  const V3 shoulderL = P(armX - 6, 5, 1385), shoulderR = P(-(armX - 6), 5, 1385);
  {  // ribs (C-shaped hoops ending beside the spine), sternum, clavicles
    Bone& b = bone(Ribcage);
    const int ribs = 8;
    for (int i = 0; i < ribs; ++i) {
      const double z = 1120 + i * (1345.0 - 1120.0) / (ribs - 1);
      const double ar = 100 + 30 * (1345 - z) / 225;
      b.shape.add(ring(P(0, -14, z), ar, 58, 9, 11, 36));
    }
    b.shape.add(capsule(P(0, -72, 1115), P(0, -72, 1370), 10));
    for (double side : {1.0, -1.0}) {
      const V3 sh = side > 0 ? shoulderL : shoulderR;
      const V3 end = sh + (headR + g + 8) * V3(-side, 0, 1).normalized();
      b.shape.add(capsule(P(side * 10, -72, 1370), end, 8));
    }
    rules.push_back({Ribcage, Spine});
    rules.push_back({Ribcage, HumerusLeft});
    rules.push_back({Ribcage, HumerusRight});
  }

  joint("pelvis", "", P(0, 25, 960), {Pelvis});
  joint("spine", "pelvis", lumbosacral, {Spine, Ribcage});
  joint("neck", "spine", skullBase, {Skull});

  for (double side : {1.0, -1.0}) {
    const bool left = side > 0;
    const std::string pre = left ? "left_" : "right_";
    const int femur = left ? FemurLeft : FemurRight, tibia = left ? TibiaLeft : TibiaRight;
    const int foot = left ? FootLeft : FootRight;
    const double x = side * kneeX;
    const V3 hip = P(side * (legX + 4), 5, 920), knee = P(x, 5, 490), ankle = P(x, 8, 80);
    {
      Bone& b = bone(femur);
      const V3 troch = P(side * (legX + 40), 5, 885);
      const V3 condyle = knee + V3(0, 0, g / 2 + 16);
      b.shape.add(sphere(hip, headR));
      b.shape.add(capsule(hip, troch, 12));
      b.shape.add(capsule(troch, condyle, 14));
      b.shape.add(ellipsoid(condyle, V3(28, 24, 16)));
      b.wedges.push_back({knee, V3::UnitX(), V3::UnitZ(), kKneeWedge, 60, g / 2});
    }
    {
      Bone& b = bone(tibia);
      const V3 plateau = knee - V3(0, 0, g / 2 + 14);
      b.shape.add(ellipsoid(plateau, V3(30, 26, 14)));
      b.shape.add(capsule(plateau, ankle + V3(0, 0, g / 2 + 13), 13));
      b.wedges.push_back({knee, V3::UnitX(), -V3::UnitZ(), kKneeWedge, 60, g / 2});
      rules.push_back({tibia, femur});
    }
    {
      Bone& b = bone(foot);
      b.shape.add(ellipsoid(ankle - V3(0, 0, g / 2 + 20), V3(20, 22, 20)));  // talus
      b.shape.add(ellipsoid(P(x, -40, 43), V3(22, 90, 14)));                // tarsals, metatarsals
      rules.push_back({foot, tibia});
    }
    joint(pre + "hip", "pelvis", hip, {femur});
    joint(pre + "knee", pre + "hip", knee, {tibia});
    joint(pre + "ankle", pre + "knee", ankle, {foot});
  }

  for (double side : {1.0, -1.0}) {
    const bool left = side > 0;
    const std::string pre = left ? "left_" : "right_";
    const int humerus = left ? HumerusLeft : HumerusRight, forearm = left ? ForearmLeft : ForearmRight;
    const int hand = left ? HandLeft : HandRight;
    const V3 shoulder = left ? shoulderL : shoulderR;
    const V3 elbow = P(side * elbowX, 5, elbowZ), wrist = P(side * wristX, 5, wristZ);
    const V3 up = (elbow - wrist).normalized();  // the forearm's axis, toward the elbow
    // The upper arm's axis toward the shoulder and the hand's away from the wrist: straight up and
    // down when the arm hangs straight, along the limb when it follows the body.
    const V3 humerusUp = contact ? V3((shoulder - elbow).normalized()) : V3::UnitZ();
    const V3 handDown = contact ? V3((P(side * handX, 0, handZ) - wrist).normalized()) : V3(-up);
    {
      Bone& b = bone(humerus);
      const V3 condyle = elbow + (g / 2 + 12) * humerusUp;
      b.shape.add(sphere(shoulder, headR));
      b.shape.add(capsule(shoulder, condyle, 12));
      b.shape.add(ellipsoid(condyle, V3(26, 15, 12)));
      b.wedges.push_back({elbow, V3::Zero(), humerusUp, kElbowWedge, 50, g / 2});
    }
    {
      Bone& b = bone(forearm);
      b.shape.add(capsule(elbow - (g / 2 + 13) * up, wrist + (g / 2 + 13) * up, 13));
      b.wedges.push_back({elbow, V3::Zero(), -up, kElbowWedge, 50, g / 2});
      rules.push_back({forearm, humerus});
    }
    {
      Bone& b = bone(hand);
      b.shape.add(ellipsoid(wrist + V3(0, -5, 0) + (g / 2 + 72) * handDown, V3(10, 28, 72)));
      rules.push_back({hand, forearm});
    }
    joint(pre + "shoulder", "spine", shoulder, {humerus});
    joint(pre + "elbow", pre + "shoulder", elbow, {forearm});
    joint(pre + "wrist", pre + "elbow", wrist, {hand});
  }

  auto indexOf = [&](int label) {
    for (std::size_t i = 0; i < m.bones.size(); ++i)
      if (m.bones[i].label == label) return int(i);
    throw std::logic_error("phantom: missing bone");
  };
  for (const CarveRule& r : rules) {
    Carver c;
    c.bone = indexOf(r.carver);
    c.centre = r.centre;
    // A point p of the carved bone meets the carver after the relative rotation M when
    // centre + M^T (p - centre) is in the carver (carver moving) or centre + M (p - centre) is
    // (carved bone moving).
    for (const Eigen::Matrix3d& M : r.range) c.poses.push_back(r.carverMoves ? Eigen::Matrix3d(M.transpose()) : M);
    if (!r.range.empty()) c.poses.erase(c.poses.begin());  // the range holds the identity already
    m.bones[indexOf(r.bone)].carvers.push_back(c);
  }

  // ---- organs, highest priority first
  m.organs.push_back({Heart, ellipsoid(P(15, -30, 1170), V3(45, 35, 48))});
  for (double side : {1.0, -1.0}) m.organs.push_back({Kidneys, ellipsoid(P(side * 62, 38, 1070), V3(24, 16, 42))});
  m.organs.push_back({Liver, ellipsoid(P(-50, -20, 1070), V3(80, 55, 48))});
  for (double side : {1.0, -1.0}) m.organs.push_back({Lungs, ellipsoid(P(side * 56, -14, 1250), V3(44, 44, 95))});
  m.organs.push_back({Bowel, ellipsoid(P(0, -40, 972), V3(90, 40, 50))});

  // ---- grid: body box plus a 2-voxel margin; LPS direction, so i and j run toward -x and -y
  ImageGrid& grid = m.grid;
  grid.spacing = s;
  grid.direction = Eigen::Vector3d(-1, -1, 1).asDiagonal();
  const V3 margin = 2 * s;
  const V3 lo = m.body.lo - margin, hi = m.body.hi + margin;
  for (int d = 0; d < 3; ++d) grid.dims[d] = int(std::ceil((hi[d] - lo[d]) / s[d])) + 1;
  grid.origin = V3(hi.x(), hi.y(), lo.z());
  return m;
}

std::vector<std::pair<int, std::string>> labelNames() {
  using namespace phantom_label;
  return {{Skin, "skin"},           {Fat, "fat"},
          {Muscle, "muscle"},       {Brain, "brain"},
          {Lungs, "lungs"},         {Heart, "heart"},
          {Liver, "liver"},         {Kidneys, "kidneys"},
          {Bowel, "bowel"},         {Skull, "skull"},
          {Spine, "spine"},         {Ribcage, "ribcage"},
          {Pelvis, "pelvis"},       {FemurLeft, "femur_left"},
          {FemurRight, "femur_right"}, {TibiaLeft, "tibia_left"},
          {TibiaRight, "tibia_right"}, {FootLeft, "foot_left"},
          {FootRight, "foot_right"}, {HumerusLeft, "humerus_left"},
          {HumerusRight, "humerus_right"}, {ForearmLeft, "forearm_left"},
          {ForearmRight, "forearm_right"}, {HandLeft, "hand_left"},
          {HandRight, "hand_right"}};
}

// Indices of the shapes whose box spans height z (per-slice culling).
template <class F>
std::vector<int> activeAt(std::size_t n, double z, F box) {
  std::vector<int> out;
  for (std::size_t i = 0; i < n; ++i) {
    V3 lo, hi;
    box(i, lo, hi);
    if (z >= lo.z() && z <= hi.z()) out.push_back(int(i));
  }
  return out;
}

}  // namespace

Phantom describePhantom(PhantomSize size, PhantomRestPose rest) {
  Model m = buildModel(size, rest);
  Phantom ph;
  ph.labels.grid = m.grid;
  ph.skeleton = m.skeleton;
  ph.labelNames = labelNames();
  return ph;
}

Phantom makePhantom(PhantomSize size, PhantomRestPose rest) {
  const Model m = buildModel(size, rest);
  const ImageGrid& grid = m.grid;
  const int nx = grid.dims[0], ny = grid.dims[1], nz = grid.dims[2];
  auto point = [&](int i, int j, int k) { return grid.indexToPhysical(V3(i, j, k)); };

  // Pass 1: inside the body (union of the soft-tissue parts).
  MaskVolume body;
  body.grid = grid;
  body.data.assign(grid.voxelCount(), 0);
  parallelFor(std::size_t(nz), [&](std::size_t k0, std::size_t k1) {
    for (int k = int(k0); k < int(k1); ++k) {
      const double z = point(0, 0, k).z();
      std::vector<const Prim*> slab;
      for (const Prim& q : m.body.prims)
        if (z >= q.lo.z() && z <= q.hi.z()) slab.push_back(&q);
      std::vector<const Prim*> row;
      for (int j = 0; j < ny; ++j) {
        const double y = point(0, j, k).y();
        row.clear();
        for (const Prim* q : slab)
          if (y >= q->lo.y() && y <= q->hi.y()) row.push_back(q);
        if (row.empty()) continue;
        for (int i = 0; i < nx; ++i) {
          const V3 p = point(i, j, k);
          for (const Prim* q : row)
            if (p.x() >= q->lo.x() && p.x() <= q->hi.x() && q->sdf(p) <= 0) {
              body.at(i, j, k) = 1;
              break;
            }
        }
      }
    }
  }, 1);

  // Pass 2: tissue labels.
  Phantom ph;
  ph.labels.grid = grid;
  ph.labels.data.assign(grid.voxelCount(), phantom_label::Background);
  ph.skeleton = m.skeleton;
  ph.labelNames = labelNames();
  const double gap = m.gap;
  auto inside = [&](int i, int j, int k) { return grid.contains(i, j, k) && body.at(i, j, k); };

  parallelFor(std::size_t(nz), [&](std::size_t k0, std::size_t k1) {
    for (int k = int(k0); k < int(k1); ++k) {
      const double z = point(0, 0, k).z();
      const std::vector<int> bones = activeAt(m.bones.size(), z, [&](std::size_t b, V3& lo, V3& hi) {
        lo = m.bones[b].shape.lo; hi = m.bones[b].shape.hi;
      });
      const std::vector<int> organs = activeAt(m.organs.size(), z, [&](std::size_t o, V3& lo, V3& hi) {
        lo = m.organs[o].prim.lo; hi = m.organs[o].prim.hi;
      });
      std::vector<const Prim*> parts;
      for (const Prim& q : m.body.prims)
        if (z >= q.lo.z() && z <= q.hi.z()) parts.push_back(&q);

      for (int j = 0; j < ny; ++j) {
        for (int i = 0; i < nx; ++i) {
          if (!body.at(i, j, k)) continue;
          std::int32_t& out = ph.labels.at(i, j, k);
          // Skin: every body voxel with a background voxel among its 26 neighbours, a closed layer.
          bool surface = false;
          for (int dk = -1; dk <= 1 && !surface; ++dk)
            for (int dj = -1; dj <= 1 && !surface; ++dj)
              for (int di = -1; di <= 1 && !surface; ++di) surface = !inside(i + di, j + dj, k + dk);
          if (surface) {
            out = phantom_label::Skin;
            continue;
          }
          const V3 p = point(i, j, k);
          int label = 0;
          for (int b : bones) {
            const Bone& bone = m.bones[b];
            if (!bone.shape.inBox(p) || bone.shape.sdf(p) > 0 || !bone.inWedges(p)) continue;
            bool carved = false;
            for (const Carver& c : bone.carvers) {
              const Bone& carver = m.bones[std::size_t(c.bone)];
              const Shape& cs = carver.shape;
              for (const Eigen::Matrix3d& M : c.poses) {
                const V3 q = c.centre + M * (p - c.centre);
                if (cs.inBox(q, gap) && cs.distanceBound(q) <= gap && carver.inWedges(q)) { carved = true; break; }
              }
              if (carved) break;
            }
            if (!carved) { label = bone.label; break; }
          }
          if (!label) {
            double depth = -1e30;
            for (const Prim* q : parts)
              if ((p.array() >= q->lo.array()).all() && (p.array() <= q->hi.array()).all())
                depth = std::max(depth, -q->sdf(p));
            if (depth < m.fat) label = phantom_label::Fat;
          }
          if (!label && m.brain.sdf(p) <= 0) label = phantom_label::Brain;
          if (!label)
            for (int o : organs)
              if (m.organs[o].prim.sdf(p) <= 0) { label = m.organs[o].label; break; }
          out = label ? label : phantom_label::Muscle;
        }
      }
    }
  }, 1);
  return ph;
}

}  // namespace repose
