// Touching body parts: geodesic nearest bones and contact separation.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>
#include <random>

#include "contact_separation.h"
#include "nearest_bones.h"
#include "volume_test_grids.h"

using namespace repose;
using namespace repose::testing;

namespace {

// 26-connected components of the set voxels.
int components(const MaskVolume& m) {
  const ImageGrid& g = m.grid;
  std::vector<int> seen(m.data.size(), 0);
  int count = 0;
  for (std::size_t s = 0; s < m.data.size(); ++s) {
    if (!m.data[s] || seen[s]) continue;
    ++count;
    std::deque<std::size_t> q{s};
    seen[s] = 1;
    while (!q.empty()) {
      const std::size_t v = q.front();
      q.pop_front();
      const int i = int(v % g.dims[0]), j = int((v / g.dims[0]) % g.dims[1]), k = int(v / (g.dims[0] * g.dims[1]));
      for (int dk = -1; dk <= 1; ++dk)
        for (int dj = -1; dj <= 1; ++dj)
          for (int di = -1; di <= 1; ++di) {
            if (!g.contains(i + di, j + dj, k + dk)) continue;
            const std::size_t w = g.linearIndex(i + di, j + dj, k + dk);
            if (m.data[w] && !seen[w]) seen[w] = 1, q.push_back(w);
          }
    }
  }
  return count;
}


}  // namespace

TEST(NearestBones, GeodesicAroundAWall) {
  // A U-shaped corridor: bone 0 at one end, bone 1 at the other; a wall between the arms makes the
  // geodesic distance longer than the straight one.
  const ImageGrid g = makeGrid(9, 7, 1);
  MaskVolume body = filled<std::uint8_t>(g, 1);
  for (int j = 0; j < 6; ++j) body.at(4, j, 0) = 0;  // the wall, open at j = 6
  Volume<std::int16_t> bone = filled<std::int16_t>(g, -1);
  bone.at(0, 0, 0) = 0;
  bone.at(8, 0, 0) = 1;
  const NearestBones nb = nearestBones(body, bone);
  const std::size_t v = g.linearIndex(3, 0, 0);
  EXPECT_EQ(nb.first[v], 0);
  EXPECT_NEAR(nb.firstMm[v], 3.0, 1e-6);
  EXPECT_EQ(nb.second[v], 1);
  // Up the right arm to the opening, across, and down: longer than the 5 mm straight line.
  EXPECT_GT(nb.secondMm[v], 10.0);
  EXPECT_EQ(nb.first[g.linearIndex(4, 0, 0)], -1);  // the wall is not body
}

namespace {

// A thin capsule (a hand) pressed against a thick cylinder (a thigh) along the line i = contactI,
// the voxels of that line in both: welded, with no background between them. Each has a bone
// along its axis.
struct TwoParts {
  MaskVolume body;
  Volume<std::int16_t> bone;
  Skeleton skeleton;
  int contactI = 0;
};

TwoParts pressedParts(int thinRadius, int thickRadius) {
  TwoParts t;
  const int margin = 3;
  const int nx = 2 * margin + 2 * thinRadius + 2 * thickRadius + 1, ny = 2 * margin + 2 * thickRadius + 1, nz = 34;
  const ImageGrid g = makeGrid(nx, ny, nz);
  t.body = filled<std::uint8_t>(g, 0);
  t.bone = filled<std::int16_t>(g, -1);
  t.contactI = margin + 2 * thinRadius;
  const int thinC = t.contactI - thinRadius, thickC = t.contactI + thickRadius, yc = ny / 2;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const double kOnAxis = std::clamp(k, 11, 22);
        const bool thin = std::sqrt(std::pow(i - thinC, 2) + std::pow(j - yc, 2) + std::pow(k - kOnAxis, 2)) <=
                          thinRadius + 0.01;
        const bool thick = k >= 2 && k < nz - 2 && std::hypot(i - thickC, j - yc) <= thickRadius + 0.01;
        if (thin || thick) t.body.at(i, j, k) = 1;
        if (thin && i == thinC && j == yc) t.bone.at(i, j, k) = 0;
        if (thick && std::hypot(i - thickC, j - yc) <= 1.5) t.bone.at(i, j, k) = 1;
      }
  for (int b = 0; b < 2; ++b) {
    Joint j;
    j.name = b == 0 ? "hand" : "thigh";
    j.parent = -1;
    j.labels = {b + 1};
    j.center = centre(g, b == 0 ? thinC : thickC, yc, b == 0 ? 22 : 30);
    t.skeleton.joints.push_back(j);
  }
  return t;
}

}  // namespace

TEST(ContactSeparation, PartsPressedTogetherAreCutAtTheirContact) {
  TwoParts t = pressedParts(5, 12);
  ASSERT_EQ(components(t.body), 1);
  const Volume<std::int16_t> bone = t.bone;
  const ContactSeparationReport r = separateContacts(t.body, t.bone, t.skeleton);
  ASSERT_EQ(r.contacts.size(), 1u);
  EXPECT_EQ(r.contacts[0].boneA, 0);
  EXPECT_EQ(r.contacts[0].boneB, 1);
  EXPECT_GT(r.voxelsCut, 0u);
  EXPECT_EQ(components(t.body), 2);  // apart
  // No bone voxel removed; the cut lies on the contact (the thin part keeps its tissue), not
  // halfway between the bones, which would be 4 voxels into the thick part.
  for (std::size_t v = 0; v < bone.data.size(); ++v)
    if (bone.data[v] >= 0) EXPECT_EQ(t.body.data[v], 1);
  const ImageGrid& g = t.body.grid;
  for (int k = 0; k < g.dims[2]; ++k)
    for (int j = 0; j < g.dims[1]; ++j)
      for (int i = 0; i < g.dims[0]; ++i)
        if (!t.body.at(i, j, k) && i > 0 && t.body.at(i - 1, j, k) && i + 1 < g.dims[0] && t.body.at(i + 1, j, k))
          EXPECT_NEAR(i, t.contactI, 1) << "a cut voxel away from the contact";
  std::cout << r.text(t.skeleton);
  EXPECT_NE(r.text(t.skeleton).find("hand | thigh"), std::string::npos);
}

TEST(ContactSeparation, AJointBetweenParentAndChildIsKept) {
  // One limb, two bones end to end (a knee): their boundary reaches the outside on plain skin.
  const ImageGrid g = makeGrid(15, 15, 40);
  MaskVolume body = filled<std::uint8_t>(g, 0);
  Volume<std::int16_t> bone = filled<std::int16_t>(g, -1);
  for (int k = 2; k < 38; ++k)
    for (int j = 0; j < 15; ++j)
      for (int i = 0; i < 15; ++i)
        if (std::hypot(i - 7, j - 7) <= 6) {
          body.at(i, j, k) = 1;
          if (std::hypot(i - 7, j - 7) <= 2 && std::abs(k - 20) > 2) bone.at(i, j, k) = k < 20 ? 1 : 0;
        }
  Skeleton s;
  Joint upper;
  upper.name = "hip", upper.parent = -1, upper.center = centre(g, 7, 7, 37), upper.labels = {1};
  Joint lower;
  lower.name = "knee", lower.parent = 0, lower.center = centre(g, 7, 7, 20), lower.labels = {2};
  s.joints = {upper, lower};
  const std::size_t before = std::count(body.data.begin(), body.data.end(), 1);
  const ContactSeparationReport r = separateContacts(body, bone, s);
  EXPECT_EQ(r.voxelsCut, 0u);
  EXPECT_EQ(std::size_t(std::count(body.data.begin(), body.data.end(), 1)), before);
}

TEST(ContactSeparation, TheTrunkFoldingIsNoContact) {
  // The same two parts pressed together, as segments of the spine (a roll of the belly between
  // two vertebral segments): one trunk, nothing cut. As an arm against the torso, they are cut
  // (but for the tissue around the shoulder, which the joint guard keeps).
  for (const bool spinal : {true, false}) {
    TwoParts t = pressedParts(5, 12);
    t.skeleton.joints[1].name = "vertebra_T12";
    t.skeleton.joints[0].name = spinal ? "vertebra_L1" : "left_shoulder";
    t.skeleton.joints[0].parent = 1;
    const ContactSeparationReport r = separateContacts(t.body, t.bone, t.skeleton);
    EXPECT_EQ(r.voxelsCut == 0, spinal) << r.text(t.skeleton);
    if (spinal) EXPECT_EQ(components(t.body), 1);
  }
}

TEST(ContactSeparation, PartsApartNeedNoCut) {
  TwoParts t = pressedParts(5, 12);
  // Open a background gap between the parts: nothing welds them, nothing is cut.
  const ImageGrid& g = t.body.grid;
  for (int k = 0; k < g.dims[2]; ++k)
    for (int j = 0; j < g.dims[1]; ++j) t.body.at(t.contactI, j, k) = 0;
  const ContactSeparationReport r = separateContacts(t.body, t.bone, t.skeleton);
  EXPECT_EQ(r.voxelsCut, 0u);
  EXPECT_EQ(components(t.body), 2);
}

TEST(ContactSeparation, BadInput) {
  TwoParts t = pressedParts(5, 12);
  Volume<std::int16_t> other = filled<std::int16_t>(makeGrid(3, 3, 3), -1);
  EXPECT_THROW(separateContacts(t.body, other, t.skeleton), std::invalid_argument);
  ContactSeparationOptions o;
  o.creaseReach = 0;
  EXPECT_THROW(separateContacts(t.body, t.bone, t.skeleton, o), std::invalid_argument);
}
