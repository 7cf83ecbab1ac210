#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cstdio>
#include <array>
#include <map>
#include <set>
#include <stdexcept>

#include "phantom.h"

using namespace repose;
namespace pl = repose::phantom_label;

namespace {

const Phantom& tiny() {
  static const Phantom ph = makePhantom(PhantomSize::Tiny);
  return ph;
}

const std::vector<int> kBones = {pl::Skull,       pl::Spine,        pl::Ribcage,    pl::Pelvis,
                                 pl::FemurLeft,   pl::FemurRight,   pl::TibiaLeft,  pl::TibiaRight,
                                 pl::FootLeft,    pl::FootRight,    pl::HumerusLeft, pl::HumerusRight,
                                 pl::ForearmLeft, pl::ForearmRight, pl::HandLeft,   pl::HandRight};

bool isBone(int label) { return std::find(kBones.begin(), kBones.end(), label) != kBones.end(); }

// Number of 6-connected components of the voxels where pred holds.
template <class Pred>
int components(const LabelVolume& v, Pred pred) {
  const auto& d = v.grid.dims;
  std::vector<char> seen(v.data.size(), 0);
  std::vector<std::array<int, 3>> stack;
  int count = 0;
  for (int k = 0; k < d[2]; ++k)
    for (int j = 0; j < d[1]; ++j)
      for (int i = 0; i < d[0]; ++i) {
        const std::size_t id = v.grid.linearIndex(i, j, k);
        if (seen[id] || !pred(v.data[id])) continue;
        ++count;
        seen[id] = 1;
        stack.push_back({i, j, k});
        while (!stack.empty()) {
          const auto c = stack.back();
          stack.pop_back();
          static const int off[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
          for (const auto& o : off) {
            const int a = c[0] + o[0], b = c[1] + o[1], e = c[2] + o[2];
            if (!v.grid.contains(a, b, e)) continue;
            const std::size_t n = v.grid.linearIndex(a, b, e);
            if (!seen[n] && pred(v.data[n])) { seen[n] = 1; stack.push_back({a, b, e}); }
          }
        }
      }
  return count;
}

// Smallest distance (mm) from x to the centre of a voxel carrying one of the labels.
double distanceToLabels(const LabelVolume& v, const Eigen::Vector3d& x, const std::vector<int>& labels) {
  double best = 1e30;
  const auto& d = v.grid.dims;
  for (int k = 0; k < d[2]; ++k)
    for (int j = 0; j < d[1]; ++j)
      for (int i = 0; i < d[0]; ++i)
        if (std::find(labels.begin(), labels.end(), v.at(i, j, k)) != labels.end())
          best = std::min(best, (v.grid.indexToPhysical(Eigen::Vector3d(i, j, k)) - x).norm());
  return best;
}

// 4-connected components of the non-background voxels of axial slice k.
int sliceComponents(const LabelVolume& v, int k) {
  LabelVolume slice;
  slice.grid = v.grid;
  slice.grid.dims[2] = 1;
  slice.data.assign(v.data.begin() + std::ptrdiff_t(v.grid.linearIndex(0, 0, k)),
                    v.data.begin() + std::ptrdiff_t(v.grid.linearIndex(0, 0, k + 1)));
  return components(slice, [](int x) { return x != pl::Background; });
}

int jointIndex(const Skeleton& s, const std::string& name) {
  for (std::size_t i = 0; i < s.joints.size(); ++i)
    if (s.joints[i].name == name) return int(i);
  return -1;
}

}  // namespace

TEST(Phantom, ParseSize) {
  EXPECT_EQ(parsePhantomSize("tiny"), PhantomSize::Tiny);
  EXPECT_EQ(parsePhantomSize("small"), PhantomSize::Small);
  EXPECT_EQ(parsePhantomSize("medium"), PhantomSize::Medium);
  EXPECT_EQ(parsePhantomSize("large"), PhantomSize::Large);
  EXPECT_THROW(parsePhantomSize("huge"), std::invalid_argument);
  EXPECT_THROW(parsePhantomSize(""), std::invalid_argument);
}

TEST(Phantom, GridIsLpsAnisotropicWithNonZeroOrigin) {
  const ImageGrid& g = tiny().labels.grid;
  EXPECT_EQ(g.voxelCount(), tiny().labels.data.size());
  Eigen::Matrix3d lps = Eigen::Vector3d(-1, -1, 1).asDiagonal();
  EXPECT_LT((g.direction - lps).norm(), 1e-12);
  EXPECT_GT(g.origin.cwiseAbs().minCoeff(), 1.0);
  EXPECT_GT(g.spacing.maxCoeff() - g.spacing.minCoeff(), 0.5);
  // Background margin all round: the body never touches the border.
  const auto& d = g.dims;
  for (int k = 0; k < d[2]; ++k)
    for (int j = 0; j < d[1]; ++j)
      for (int i = 0; i < d[0]; ++i)
        if (i == 0 || j == 0 || k == 0 || i == d[0] - 1 || j == d[1] - 1 || k == d[2] - 1) {
          ASSERT_EQ(tiny().labels.at(i, j, k), pl::Background);
        }
  // About 1.75 m tall: the body's z extent.
  int kmin = d[2], kmax = -1;
  for (std::size_t n = 0; n < tiny().labels.data.size(); ++n)
    if (tiny().labels.data[n] != pl::Background) {
      const int k = int(n / (std::size_t(d[0]) * d[1]));
      kmin = std::min(kmin, k);
      kmax = std::max(kmax, k);
    }
  const double height = (kmax - kmin + 1) * g.spacing.z();
  EXPECT_GT(height, 1650);
  EXPECT_LT(height, 1850);
}

TEST(Phantom, HasEveryLabelAndNames) {
  const Phantom& ph = tiny();
  std::map<int, std::size_t> count;
  for (int v : ph.labels.data) ++count[v];
  std::set<int> named;
  for (const auto& [value, name] : ph.labelNames) {
    EXPECT_FALSE(name.empty());
    EXPECT_TRUE(named.insert(value).second) << "duplicate " << value;
    EXPECT_GT(count[value], 0u) << name << " is empty";
  }
  for (const auto& [value, n] : count) {
    if (value != pl::Background) {
      EXPECT_TRUE(named.count(value)) << "label " << value << " has no name";
    }
  }
  EXPECT_EQ(named.size(), 25u);
  // Soft tissue dominates bone.
  EXPECT_GT(count[pl::Muscle], count[pl::Pelvis]);
}

TEST(Phantom, EachBoneIsOneComponentSeparatedFromTheOthers) {
  const LabelVolume& v = tiny().labels;
  for (int b : kBones) EXPECT_EQ(components(v, [b](int x) { return x == b; }), 1) << "bone label " << b;
  // Joints have a cartilage gap: no two different bones are 26-neighbours.
  const auto& d = v.grid.dims;
  int touching = 0;
  for (int k = 1; k < d[2] - 1; ++k)
    for (int j = 1; j < d[1] - 1; ++j)
      for (int i = 1; i < d[0] - 1; ++i) {
        const int a = v.at(i, j, k);
        if (!isBone(a)) continue;
        for (int dk = -1; dk <= 1; ++dk)
          for (int dj = -1; dj <= 1; ++dj)
            for (int di = -1; di <= 1; ++di) {
              const int b = v.at(i + di, j + dj, k + dk);
              if (isBone(b) && b != a) ++touching;
            }
      }
  EXPECT_EQ(touching, 0);
  // The union of all bones is 16 separate components too.
  EXPECT_EQ(components(v, isBone), 16);
}

TEST(Phantom, BodyIsOneComponentAndBonesAreInsideTheSkin) {
  const LabelVolume& v = tiny().labels;
  EXPECT_EQ(components(v, [](int x) { return x != pl::Background; }), 1);
  EXPECT_EQ(components(v, [](int x) { return x == pl::Skin; }), 1) << "skin is one closed layer";
  const auto& d = v.grid.dims;
  for (int k = 1; k < d[2] - 1; ++k)
    for (int j = 1; j < d[1] - 1; ++j)
      for (int i = 1; i < d[0] - 1; ++i) {
        const int a = v.at(i, j, k);
        if (a == pl::Background) continue;
        bool boundary = false;
        for (int dk = -1; dk <= 1; ++dk)
          for (int dj = -1; dj <= 1; ++dj)
            for (int di = -1; di <= 1; ++di) boundary = boundary || v.at(i + di, j + dj, k + dk) == 0;
        // Skin is exactly the outer (26-neighbourhood) layer, so bones and organs never reach the surface.
        ASSERT_EQ(boundary, a == pl::Skin) << "voxel " << i << "," << j << "," << k << " label " << a;
        if (isBone(a)) {
          // ... so bones are wrapped in skin: no background among the 26 neighbours.
          for (int dk = -1; dk <= 1; ++dk)
            for (int dj = -1; dj <= 1; ++dj)
              for (int di = -1; di <= 1; ++di)
                ASSERT_NE(v.at(i + di, j + dj, k + dk), pl::Background) << "bone " << a << " at the surface";
        }
      }
}

TEST(Phantom, ArmsAndThighsAreSeparatedByBackground) {
  const Phantom& ph = tiny();
  const LabelVolume& v = ph.labels;
  const Skeleton& s = ph.skeleton;
  for (const char* side : {"left", "right"}) {
    const Eigen::Vector3d shoulder = s.joints[jointIndex(s, std::string(side) + "_shoulder")].center;
    const Eigen::Vector3d elbow = s.joints[jointIndex(s, std::string(side) + "_elbow")].center;
    const Eigen::Vector3d hip = s.joints[jointIndex(s, std::string(side) + "_hip")].center;
    const Eigen::Vector3d knee = s.joints[jointIndex(s, std::string(side) + "_knee")].center;
    // Mid upper arm: walking in i from the humerus toward the midline meets background before the torso.
    {
      const Eigen::Vector3d mid = 0.5 * (shoulder + elbow);
      const Eigen::Vector3d ijk = v.grid.physicalToIndex(mid);
      const int j = int(std::lround(ijk.y())), k = int(std::lround(ijk.z()));
      const int i0 = int(std::lround(ijk.x()));
      const int iMid = int(std::lround(v.grid.physicalToIndex(Eigen::Vector3d(0, mid.y(), mid.z())).x()));
      ASSERT_TRUE(v.at(i0, j, k) == pl::HumerusLeft || v.at(i0, j, k) == pl::HumerusRight) << side;
      ASSERT_NE(v.at(iMid, j, k), pl::Background);
      const int step = iMid > i0 ? 1 : -1;
      int background = 0;
      bool leftArm = false;
      for (int i = i0; i != iMid; i += step) {
        if (v.at(i, j, k) == pl::Background) { ++background; leftArm = true; }
        else if (leftArm) break;  // reached the torso
      }
      EXPECT_GE(background, 1) << side << " arm touches the torso";
      EXPECT_LE(background, 3) << side << " arm is far from the torso";
    }
    // Mid thigh: background between the thighs at the midline.
    {
      const Eigen::Vector3d mid = 0.5 * (hip + knee);
      const Eigen::Vector3d ijk = v.grid.physicalToIndex(Eigen::Vector3d(0, mid.y(), mid.z()));
      const int i = int(std::lround(ijk.x())), j = int(std::lround(ijk.y())), k = int(std::lround(ijk.z()));
      EXPECT_EQ(v.at(i, j, k), pl::Background) << "thighs touch";
      EXPECT_NE(v.at(i - 2, j, k), pl::Background);
      EXPECT_NE(v.at(i + 2, j, k), pl::Background);
    }
  }
  // Below the armpit (8 cm under the shoulder joints) down to the elbows every axial slice shows
  // three separate parts: two arms and the torso.
  const auto sliceOf = [&](const Eigen::Vector3d& x) { return int(std::lround(v.grid.physicalToIndex(x).z())); };
  const int kElbow = sliceOf(s.joints[jointIndex(s, "left_elbow")].center);
  const int kArmpit = sliceOf(s.joints[jointIndex(s, "left_shoulder")].center - Eigen::Vector3d(0, 0, 80));
  ASSERT_LT(kElbow, kArmpit);
  for (int k = kElbow; k <= kArmpit; ++k) EXPECT_EQ(sliceComponents(v, k), 3) << "slice " << k;
  // The hands hang beside the thighs without touching them: 2 hands + 2 thighs.
  const Eigen::Vector3d wrist = s.joints[jointIndex(s, "left_wrist")].center;
  EXPECT_EQ(sliceComponents(v, sliceOf(wrist - Eigen::Vector3d(0, 0, 60))), 4);
  // The thighs are apart from the knees to 12 cm below the hips.
  const Eigen::Vector3d hip = s.joints[jointIndex(s, "left_hip")].center;
  const Eigen::Vector3d knee = s.joints[jointIndex(s, "left_knee")].center;
  for (int k = sliceOf(knee); k <= sliceOf(hip - Eigen::Vector3d(0, 0, 120)); ++k) {
    const int n = sliceComponents(v, k);
    EXPECT_TRUE(n == 2 || n == 4) << "slice " << k << " has " << n << " parts";
  }
}

TEST(Phantom, ContactRestPoseWeldsArmsHandsAndThighs) {
  // As real scans are taken: the same body and skeleton names, but no background between the arms
  // and the torso, the hands and the thighs, or the two thighs, where the apart pose has some.
  const Phantom ph = makePhantom(PhantomSize::Small, PhantomRestPose::Contact);
  const LabelVolume& v = ph.labels;
  const Skeleton& s = ph.skeleton;
  ASSERT_EQ(s.joints.size(), tiny().skeleton.joints.size());
  for (std::size_t j = 0; j < s.joints.size(); ++j) EXPECT_EQ(s.joints[j].name, tiny().skeleton.joints[j].name);
  const auto sliceOf = [&](const Eigen::Vector3d& x) { return int(std::lround(v.grid.physicalToIndex(x).z())); };
  const auto centre = [&](const char* name) { return s.joints[jointIndex(s, name)].center; };
  // Upper arms and torso are one part below the armpit: 3 parts apart, 1 in contact.
  const int kMidArm = sliceOf(0.5 * (centre("left_shoulder") + centre("left_elbow")));
  EXPECT_EQ(sliceComponents(v, kMidArm), 1);
  // The thighs touch from 12 cm below the hips to the knees: no background on the midline between them.
  for (int k = sliceOf(centre("left_knee") + Eigen::Vector3d(0, 0, 40));
       k <= sliceOf(centre("left_hip") - Eigen::Vector3d(0, 0, 120)); ++k) {
    const Eigen::Vector3d ijk = v.grid.physicalToIndex(Eigen::Vector3d(0, centre("left_hip").y(), 0));
    EXPECT_NE(v.at(int(std::lround(ijk.x())), int(std::lround(ijk.y())), k), pl::Background) << "slice " << k;
  }
  // The hands lie against the thighs: one part where the apart pose has four.
  EXPECT_EQ(sliceComponents(v, sliceOf(centre("left_wrist") - Eigen::Vector3d(0, 0, 60))), 1);
  // Every bone is present, inside the body, and the skin is the outer layer only (no skin where
  // two parts are welded).
  std::set<int> present(v.data.begin(), v.data.end());
  for (const Joint& j : s.joints)
    for (int label : j.labels) EXPECT_TRUE(present.count(label)) << j.name;
  const Phantom apart = makePhantom(PhantomSize::Small);
  const auto count = [](const LabelVolume& l, int label) { return std::count(l.data.begin(), l.data.end(), label); };
  EXPECT_LT(count(v, pl::Skin), count(apart.labels, pl::Skin));
  EXPECT_EQ(parsePhantomRestPose("contact"), PhantomRestPose::Contact);
  EXPECT_THROW(parsePhantomRestPose("lying"), std::invalid_argument);
}

TEST(Phantom, SkeletonMatchesTheBones) {
  const Phantom& ph = tiny();
  const Skeleton& s = ph.skeleton;
  ASSERT_EQ(s.joints.size(), 15u);
  EXPECT_EQ(s.joints[0].name, "pelvis");
  EXPECT_EQ(s.joints[0].parent, -1);
  std::set<int> used;
  for (std::size_t i = 0; i < s.joints.size(); ++i) {
    const Joint& j = s.joints[i];
    if (i > 0) {
      ASSERT_GE(j.parent, 0) << j.name;
      EXPECT_LT(j.parent, int(i)) << j.name << " is not parents-first";
    }
    for (int l : j.labels) {
      EXPECT_TRUE(isBone(l));
      EXPECT_TRUE(used.insert(l).second) << "label used twice: " << l;
    }
  }
  EXPECT_EQ(used.size(), kBones.size());
  const std::map<std::string, std::string> parent = {
      {"spine", "pelvis"},         {"neck", "spine"},          {"left_hip", "pelvis"},
      {"left_knee", "left_hip"},   {"left_ankle", "left_knee"}, {"right_hip", "pelvis"},
      {"right_knee", "right_hip"}, {"right_ankle", "right_knee"}, {"left_shoulder", "spine"},
      {"left_elbow", "left_shoulder"}, {"left_wrist", "left_elbow"}, {"right_shoulder", "spine"},
      {"right_elbow", "right_shoulder"}, {"right_wrist", "right_elbow"}};
  for (const auto& [child, par] : parent) {
    const int c = jointIndex(s, child);
    ASSERT_GE(c, 0) << child;
    EXPECT_EQ(s.joints[c].parent, jointIndex(s, par)) << child;
  }
  // Patient left is +x.
  EXPECT_GT(s.joints[jointIndex(s, "left_hip")].center.x(), 0);
  EXPECT_LT(s.joints[jointIndex(s, "right_shoulder")].center.x(), 0);
  EXPECT_GT(s.joints[jointIndex(s, "neck")].center.z(), s.joints[jointIndex(s, "spine")].center.z());

  // Each joint centre sits between its parent's bone and its own: both are within a few voxels.
  // Ball joints (hips, shoulders) have the centre inside the child's head, a head radius plus the
  // cartilage gap from the socket; hinge joints have it in the gap, close to both bones.
  const double voxel = ph.labels.grid.spacing.maxCoeff();
  for (std::size_t i = 1; i < s.joints.size(); ++i) {
    const Joint& j = s.joints[i];
    const std::vector<int>& parentLabels = s.joints[j.parent].labels;
    const double dChild = distanceToLabels(ph.labels, j.center, j.labels);
    const double dParent = distanceToLabels(ph.labels, j.center, parentLabels);
    const Eigen::Vector3d ijk = ph.labels.grid.physicalToIndex(j.center);
    const int at = ph.labels.at(int(std::lround(ijk.x())), int(std::lround(ijk.y())), int(std::lround(ijk.z())));
    EXPECT_NE(at, pl::Background) << j.name;
    EXPECT_TRUE(std::find(parentLabels.begin(), parentLabels.end(), at) == parentLabels.end()) << j.name;
    const bool ball = j.name.find("hip") != std::string::npos || j.name.find("shoulder") != std::string::npos;
    if (ball) {
      EXPECT_TRUE(std::find(j.labels.begin(), j.labels.end(), at) != j.labels.end()) << j.name;
      EXPECT_LT(dChild, voxel) << j.name;
      EXPECT_LT(dParent, 5 * voxel) << j.name;
    } else {
      EXPECT_TRUE(isBone(at) == false) << j.name << ": centre should be in the cartilage gap";
      EXPECT_LT(dChild, 2.5 * voxel) << j.name;
      EXPECT_LT(dParent, 2.5 * voxel) << j.name;
    }
  }
}

TEST(Phantom, SizesDescribeTheSameBodyWithMoreVoxels) {
  std::size_t last = 0;
  Eigen::Vector3d lastSpacing = Eigen::Vector3d::Constant(1e9);
  const Phantom t = describePhantom(PhantomSize::Tiny);
  for (PhantomSize size : {PhantomSize::Tiny, PhantomSize::Small, PhantomSize::Medium, PhantomSize::Large}) {
    const Phantom d = describePhantom(size);
    EXPECT_TRUE(d.labels.data.empty());
    const ImageGrid& g = d.labels.grid;
    EXPECT_GT(g.voxelCount(), last);
    EXPECT_TRUE((g.spacing.array() < lastSpacing.array()).all());
    EXPECT_GT(g.spacing.maxCoeff() - g.spacing.minCoeff(), 0.1);
    last = g.voxelCount();
    lastSpacing = g.spacing;
    // Same body: physical extent and joints agree up to the size-dependent joint gaps.
    const Eigen::Vector3d extent = g.spacing.cwiseProduct(Eigen::Vector3d(g.dims[0], g.dims[1], g.dims[2]));
    const ImageGrid& tg = t.labels.grid;
    const Eigen::Vector3d tinyExtent = tg.spacing.cwiseProduct(Eigen::Vector3d(tg.dims[0], tg.dims[1], tg.dims[2]));
    EXPECT_LT((extent - tinyExtent).cwiseAbs().maxCoeff(), 60.0);
    ASSERT_EQ(d.skeleton.joints.size(), t.skeleton.joints.size());
    for (std::size_t j = 0; j < t.skeleton.joints.size(); ++j)
      EXPECT_LT((d.skeleton.joints[j].center - t.skeleton.joints[j].center).norm(), 15.0);
  }
  // describePhantom matches makePhantom.
  EXPECT_TRUE(t.labels.grid.sameGridAs(tiny().labels.grid));
}

// Voxel centres of one label.
std::vector<Eigen::Vector3d> voxelsOf(const Phantom& ph, int label) {
  const ImageGrid& g = ph.labels.grid;
  std::vector<Eigen::Vector3d> out;
  for (int k = 0; k < g.dims[2]; ++k)
    for (int j = 0; j < g.dims[1]; ++j)
      for (int i = 0; i < g.dims[0]; ++i)
        if (ph.labels.at(i, j, k) == label) out.push_back(g.indexToPhysical(Eigen::Vector3d(i, j, k)));
  return out;
}

// Smallest distance between the fixed bone's voxels and the moving bone's voxels turned about
// `centre` by each rotation (moving voxels farther than `reach` from the centre are skipped).
double clearance(const std::vector<Eigen::Vector3d>& fixed, const std::vector<Eigen::Vector3d>& moving,
                 const Eigen::Vector3d& centre, const std::vector<Eigen::Matrix3d>& rotations, double reach) {
  // Turning keeps the distance to the centre: only fixed voxels at about the same radius can be
  // nearest, so they are sorted by radius and scanned within the current best distance.
  std::vector<std::pair<double, Eigen::Vector3d>> byRadius;
  for (const Eigen::Vector3d& f : fixed) byRadius.push_back({(f - centre).norm(), f});
  std::sort(byRadius.begin(), byRadius.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  double worst = 1e30;
  for (const Eigen::Vector3d& m : moving) {
    const double r = (m - centre).norm();
    if (r > reach) continue;
    for (const Eigen::Matrix3d& R : rotations) {
      const Eigen::Vector3d q = centre + R * (m - centre);
      auto it = std::lower_bound(byRadius.begin(), byRadius.end(), r - worst,
                                 [](const auto& e, double v) { return e.first < v; });
      for (; it != byRadius.end() && it->first <= r + worst; ++it) worst = std::min(worst, (q - it->second).norm());
    }
  }
  return worst;
}

Eigen::Matrix3d rotation(double degrees, const Eigen::Vector3d& axis) {
  return Eigen::AngleAxisd(degrees * 3.14159265358979 / 180, axis).toRotationMatrix();
}

// The joints move through their range without bone running into bone (no deformation of the tissue
// between two colliding bones could stay un-inverted), sampled more finely than the phantom carves:
// - each femur, turned about its hip centre through flexion 120 to extension 20 degrees (about -x),
//   abduction and adduction 45 (about y) and rotation 40 either way (about z), stays clear of the pelvis;
// - each tibia, flexed about its knee to 130 degrees (about +x), stays clear of the femur;
// - each forearm, flexed about its elbow to 145 degrees (about -x), stays clear of the humerus.
TEST(Phantom, BonesClearEachOtherThroughTheirJointsRange) {
  for (PhantomSize size : {PhantomSize::Tiny, PhantomSize::Small}) {
    const Phantom ph = makePhantom(size);
    const double voxel = ph.labels.grid.spacing.minCoeff();
    const std::vector<Eigen::Vector3d> pelvis = voxelsOf(ph, pl::Pelvis);
    for (const std::string side : {"left", "right"}) {
      const bool left = side == "left";
      auto centre = [&](const std::string& joint) {
        return ph.skeleton.joints[std::size_t(jointIndex(ph.skeleton, side + "_" + joint))].center;
      };
      const std::vector<Eigen::Vector3d> femur = voxelsOf(ph, left ? pl::FemurLeft : pl::FemurRight);
      std::vector<Eigen::Matrix3d> hipRange;
      for (double rot = -40; rot <= 40; rot += 20)
        for (double abd = -45; abd <= 45; abd += 15)
          for (double flex = -120; flex <= 20; flex += 5)
            hipRange.push_back(rotation(rot, Eigen::Vector3d::UnitZ()) * rotation(abd, Eigen::Vector3d::UnitY()) *
                               rotation(flex, Eigen::Vector3d::UnitX()));
      const double hip = clearance(pelvis, femur, centre("hip"), hipRange, 150);
      std::vector<Eigen::Matrix3d> knee, elbow;
      for (double flex = 0; flex <= 130; flex += 5) knee.push_back(rotation(flex, Eigen::Vector3d::UnitX()));
      for (double flex = 0; flex <= 145; flex += 5) elbow.push_back(rotation(-flex, Eigen::Vector3d::UnitX()));
      const double kneeClear =
          clearance(femur, voxelsOf(ph, left ? pl::TibiaLeft : pl::TibiaRight), centre("knee"), knee, 120);
      const double elbowClear = clearance(voxelsOf(ph, left ? pl::HumerusLeft : pl::HumerusRight),
                                          voxelsOf(ph, left ? pl::ForearmLeft : pl::ForearmRight), centre("elbow"),
                                          elbow, 120);
      std::printf("size %d %s: nearest bone voxels through the range: hip %.1f mm, knee %.1f, elbow %.1f (voxel %.1f)\n",
                  int(size), side.c_str(), hip, kneeClear, elbowClear, voxel);
      EXPECT_GT(hip, voxel) << side << ", size " << int(size);
      EXPECT_GT(kneeClear, 0.5 * voxel) << side << ", size " << int(size);
      EXPECT_GT(elbowClear, 0.5 * voxel) << side << ", size " << int(size);
    }
  }
}
