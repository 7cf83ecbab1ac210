// Rigid bone paths of the fold-free continuation: rigid at every s, joints kept with the hierarchy,
// exact at the ends.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <random>
#include <stdexcept>

#include "bone_path.h"

namespace {

using repose::BonePath;
using repose::Points;

// Two bones meeting at the joint (0, 0, 100): bone 0 (the parent) below it, bone 1 above. Node 0 of
// each bone sits on the joint, so the joint is kept exactly when those two nodes stay together.
struct Chain {
  Points rest, posed;
  std::vector<int> bone;
};

Chain makeChain() {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-20.0, 20.0), h(0.0, 90.0);
  const Eigen::Vector3d joint(0, 0, 100);
  Chain c;
  const int perBone = 30;
  c.rest.resize(2 * perBone, 3);
  for (int b = 0; b < 2; ++b)
    for (int k = 0; k < perBone; ++k) {
      const int v = b * perBone + k;
      c.bone.push_back(b);
      const double along = b == 0 ? -h(rng) : h(rng);
      c.rest.row(v) = k == 0 ? joint.transpose() : Eigen::RowVector3d(u(rng), u(rng), joint.z() + along);
    }
  // The whole skeleton turned and moved; bone 1 also bent by 120 degrees about the joint.
  const Eigen::Isometry3d global = Eigen::Translation3d(500, -200, 50) *
                                   Eigen::AngleAxisd(2.0, Eigen::Vector3d(1, 2, 3).normalized());
  const Eigen::Isometry3d bend = Eigen::Translation3d(joint) *
                                 Eigen::AngleAxisd(2.1, Eigen::Vector3d::UnitX()) * Eigen::Translation3d(-joint);
  c.posed.resize(c.rest.rows(), 3);
  for (Eigen::Index v = 0; v < c.rest.rows(); ++v) {
    const Eigen::Vector3d p = c.rest.row(v).transpose();
    c.posed.row(v) = (c.bone[std::size_t(v)] == 0 ? global * p : global * (bend * p)).transpose();
  }
  return c;
}

std::vector<int> nodesOf(const Chain& c, int b) {
  std::vector<int> nodes;
  for (std::size_t v = 0; v < c.bone.size(); ++v)
    if (b < 0 || c.bone[v] == b) nodes.push_back(int(v));
  return nodes;
}

// Largest change of the distance between any two of the nodes, from rest to x.
double distortion(const Points& rest, const Points& x, const std::vector<int>& nodes) {
  double worst = 0;
  for (int a : nodes)
    for (int b : nodes)
      worst = std::max(worst, std::abs((x.row(a) - x.row(b)).norm() - (rest.row(a) - rest.row(b)).norm()));
  return worst;
}

TEST(BonePath, RigidAtEverySJointKeptExactAtTheEnds) {
  const Chain c = makeChain();
  const BonePath path(c.rest, c.posed, c.bone, {-1, 0});
  const std::vector<int> all = nodesOf(c, -1);
  for (double s : {0.0, 0.1, 0.25, 0.5, 0.75, 0.9, 1.0}) {
    Points x = Points::Zero(c.rest.rows(), 3);
    path.place(s, all, x);
    EXPECT_LT(distortion(c.rest, x, nodesOf(c, 0)), 1e-9) << "s = " << s;
    EXPECT_LT(distortion(c.rest, x, nodesOf(c, 1)), 1e-9) << "s = " << s;
    EXPECT_LT((x.row(0) - x.row(30)).norm(), 1e-9) << "the joint parts at s = " << s;
    if (s == 0.0) {  // the rest shape moved rigidly as a whole, and start() agrees
      EXPECT_LT(distortion(c.rest, x, all), 1e-9);
      for (int v : all) EXPECT_LT((path.start(c.rest.row(v).transpose()) - x.row(v).transpose()).norm(), 1e-9);
    }
    if (s == 1.0) EXPECT_EQ(x, c.posed);
  }
  // Half way, bone 1 has turned half of its bend relative to bone 0.
  Points x = Points::Zero(c.rest.rows(), 3);
  path.place(0.5, all, x);
  auto rotationOf = [&](int b) {
    const std::vector<int> nodes = nodesOf(c, b);
    Eigen::Matrix3Xd from(3, Eigen::Index(nodes.size())), to(3, Eigen::Index(nodes.size()));
    for (std::size_t i = 0; i < nodes.size(); ++i) {
      from.col(Eigen::Index(i)) = c.rest.row(nodes[i]).transpose();
      to.col(Eigen::Index(i)) = x.row(nodes[i]).transpose();
    }
    return Eigen::Matrix3d(Eigen::umeyama(from, to, false).topLeftCorner<3, 3>());
  };
  const Eigen::AngleAxisd relative(rotationOf(0).transpose() * rotationOf(1));
  EXPECT_NEAR(relative.angle(), 1.05, 1e-9);
  EXPECT_NEAR(std::abs(relative.axis().x()), 1.0, 1e-9);
}

TEST(BonePath, WithoutTheHierarchyJointsDriftMidPath) {
  const Chain c = makeChain();
  const BonePath path(c.rest, c.posed, c.bone);
  Points x = Points::Zero(c.rest.rows(), 3);
  path.place(0.5, nodesOf(c, -1), x);
  EXPECT_LT(distortion(c.rest, x, nodesOf(c, 1)), 1e-9);  // still rigid per bone
  EXPECT_GT((x.row(0) - x.row(30)).norm(), 1.0);           // but the joint parts
  path.place(1.0, nodesOf(c, -1), x);
  EXPECT_EQ(x, c.posed);
}

TEST(BonePath, NonRigidMotionIsPhasedInAndEndsExactly) {
  Chain c = makeChain();
  c.posed(5, 0) += 3.0;  // one node off its bone's rigid motion
  const BonePath path(c.rest, c.posed, c.bone, {-1, 0});
  Points x = Points::Zero(c.rest.rows(), 3), y = x;
  path.place(1.0, nodesOf(c, -1), x);
  EXPECT_EQ(x, c.posed);
  path.place(0.0, nodesOf(c, -1), y);  // s = 0 has none of it: still a rigid motion of the rest
  EXPECT_LT(distortion(c.rest, y, nodesOf(c, -1)), 0.5);
}

TEST(BonePath, BadHierarchiesThrow) {
  const Chain c = makeChain();
  EXPECT_THROW(BonePath(c.rest, c.posed, c.bone, {1, 0}), std::invalid_argument);  // a cycle
  EXPECT_THROW(BonePath(c.rest, c.posed, c.bone, {-1}), std::invalid_argument);    // bone 1 missing
  EXPECT_THROW(BonePath(c.rest, c.posed, c.bone, {-1, 1}), std::invalid_argument); // its own parent
}

}  // namespace
