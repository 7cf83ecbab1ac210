// Dual quaternions and skinning of nodes (DQS and LBS).
#include <gtest/gtest.h>

#include "body_segments.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <random>
#include <stdexcept>

#include "dual_quaternion.h"
#include "skinning.h"

namespace {

Eigen::Isometry3d rigid(double degrees, const Eigen::Vector3d& axis, const Eigen::Vector3d& t) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(degrees * M_PI / 180.0, axis.normalized()).toRotationMatrix();
  T.translation() = t;
  return T;
}

repose::SparseWeights oneBoneWeights(std::size_t n, int k, int bone) {
  repose::SparseWeights w;
  w.k = k;
  w.weight.assign(n * k, 0.0f);
  w.bone.assign(n * k, 0);
  for (std::size_t i = 0; i < n; ++i) {
    w.weight[i * k] = 1.0f;
    w.bone[i * k] = std::uint16_t(bone);
  }
  return w;
}

repose::Points randomPoints(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-50, 50);
  repose::Points P(n, 3);
  for (int i = 0; i < n; ++i) P.row(i) << u(rng), u(rng), u(rng);
  return P;
}

}  // namespace

TEST(DualQuaternion, RoundTripAndTransformPoint) {
  const Eigen::Isometry3d T = rigid(73, {1, -2, 0.5}, {3, -4, 12});
  const repose::DualQuaternion dq = repose::DualQuaternion::fromIsometry(T);
  EXPECT_NEAR(dq.real.norm(), 1.0, 1e-15);
  EXPECT_NEAR(dq.real.coeffs().dot(dq.dual.coeffs()), 0.0, 1e-14);  // unit dual quaternion
  EXPECT_LT((dq.toIsometry().matrix() - T.matrix()).cwiseAbs().maxCoeff(), 1e-13);
  const Eigen::Vector3d p(7, 8, -9);
  EXPECT_LT((dq.transformPoint(p) - T * p).norm(), 1e-12);
  // Scaling the dual quaternion does not change the transform (both use the normalised one).
  repose::DualQuaternion scaled = dq;
  scaled.real.coeffs() *= 2.5;
  scaled.dual.coeffs() *= 2.5;
  EXPECT_LT((scaled.transformPoint(p) - T * p).norm(), 1e-12);
  EXPECT_LT((scaled.toIsometry().matrix() - T.matrix()).cwiseAbs().maxCoeff(), 1e-13);
}

TEST(Skinning, OneBoneIsItsRigidTransform) {
  const repose::Points rest = randomPoints(1000, 1);
  const std::vector<Eigen::Isometry3d> bones = {Eigen::Isometry3d::Identity(),
                                                rigid(131, {0.3, 1, -0.2}, {10, 20, -5})};
  for (int k : {1, 4, 6}) {  // compile-time and run-time k paths
    const repose::SparseWeights w = oneBoneWeights(1000, k, 1);
    for (auto method : {repose::SkinningMethod::DualQuaternion, repose::SkinningMethod::LinearBlend}) {
      repose::Points posed;
      repose::skinNodes(rest, w, {}, bones, method, posed);
      ASSERT_EQ(posed.rows(), rest.rows());
      for (int i = 0; i < rest.rows(); ++i) {
        const Eigen::Vector3d expected = bones[1] * Eigen::Vector3d(rest.row(i));
        EXPECT_LT((Eigen::Vector3d(posed.row(i)) - expected).norm(), 1e-9) << "k=" << k << " node " << i;
      }
    }
  }
}

TEST(Skinning, SameBoneTwiceIsStillRigid) {
  const repose::Points rest = randomPoints(50, 2);
  const std::vector<Eigen::Isometry3d> bones = {rigid(-40, {1, 1, 1}, {1, 2, 3})};
  repose::SparseWeights w = oneBoneWeights(50, 2, 0);
  for (int i = 0; i < 50; ++i) w.weight[2 * i] = w.weight[2 * i + 1] = 0.5f;
  repose::Points posed;
  repose::skinNodes(rest, w, {}, bones, repose::SkinningMethod::DualQuaternion, posed);
  for (int i = 0; i < 50; ++i)
    EXPECT_LT((Eigen::Vector3d(posed.row(i)) - bones[0] * Eigen::Vector3d(rest.row(i))).norm(), 1e-9);
}

TEST(Skinning, FixedNodesMoveExactlyWithTheirBone) {
  const int n = 200;
  const repose::Points rest = randomPoints(n, 3);
  const std::vector<Eigen::Isometry3d> bones = {rigid(20, {0, 0, 1}, {0, 0, 0}),
                                                rigid(-75, {1, 0, 0}, {5, 0, 1}),
                                                rigid(160, {0, 1, 1}, {-3, 2, 0})};
  // Weights deliberately blend all bones; the fixed tag must win.
  repose::SparseWeights w;
  w.k = 3;
  for (int i = 0; i < n; ++i)
    for (int b = 0; b < 3; ++b) {
      w.weight.push_back(b == 0 ? 0.5f : 0.25f);
      w.bone.push_back(std::uint16_t(b));
    }
  std::vector<int> fixed(n, -1);
  for (int i = 0; i < n; i += 3) fixed[i] = (i / 3) % 3;
  for (auto method : {repose::SkinningMethod::DualQuaternion, repose::SkinningMethod::LinearBlend}) {
    repose::Points posed;
    repose::skinNodes(rest, w, fixed, bones, method, posed);
    for (int i = 0; i < n; ++i) {
      if (fixed[i] < 0) continue;
      const Eigen::Vector3d expected = bones[fixed[i]] * Eigen::Vector3d(rest.row(i));
      EXPECT_LT((Eigen::Vector3d(posed.row(i)) - expected).norm(), 1e-12) << i;
    }
  }
}

// A cylinder along z between bone 0 (rest) and bone 1 twisted 120 degrees about the axis, weights
// linear in z. LBS collapses the middle (candy wrapper); DQS keeps the radius.
TEST(Skinning, TwistCandyWrapperLbsVersusDqs) {
  const double R = 10, L = 100;
  const int rings = 21, perRing = 36;
  repose::Points rest(rings * perRing, 3);
  repose::SparseWeights w;
  w.k = 2;
  for (int r = 0; r < rings; ++r)
    for (int a = 0; a < perRing; ++a) {
      const double z = L * r / (rings - 1), phi = 2 * M_PI * a / perRing;
      rest.row(r * perRing + a) << R * std::cos(phi), R * std::sin(phi), z;
      const float w1 = float(z / L);
      w.weight.push_back(std::max(w1, 1 - w1));
      w.weight.push_back(std::min(w1, 1 - w1));
      w.bone.push_back(w1 >= 0.5f ? 1 : 0);
      w.bone.push_back(w1 >= 0.5f ? 0 : 1);
    }
  const std::vector<Eigen::Isometry3d> bones = {Eigen::Isometry3d::Identity(),
                                                rigid(120, {0, 0, 1}, {0, 0, 0})};
  repose::Points lbs, dqs;
  repose::skinNodes(rest, w, {}, bones, repose::SkinningMethod::LinearBlend, lbs);
  repose::skinNodes(rest, w, {}, bones, repose::SkinningMethod::DualQuaternion, dqs);
  auto radius = [](const repose::Points& P, int i) { return std::hypot(P(i, 0), P(i, 1)); };
  const int mid = (rings / 2) * perRing;  // z = L/2, weights 0.5/0.5
  // LBS at the middle: radius R*cos(60 deg) = R/2.
  EXPECT_NEAR(radius(lbs, mid), R * 0.5, 1e-4);
  double minDqs = 1e9, maxDqs = 0, minLbs = 1e9;
  for (int i = 0; i < rest.rows(); ++i) {
    minDqs = std::min(minDqs, radius(dqs, i));
    maxDqs = std::max(maxDqs, radius(dqs, i));
    minLbs = std::min(minLbs, radius(lbs, i));
    EXPECT_NEAR(dqs(i, 2), rest(i, 2), 1e-9);  // a twist about the axis keeps z
  }
  EXPECT_LT(minLbs, 0.6 * R);
  EXPECT_GT(minDqs, 0.99 * R);
  EXPECT_LT(maxDqs, 1.01 * R);
  // DQS rotates the middle ring by 60 degrees.
  EXPECT_NEAR(std::atan2(dqs(mid, 1), dqs(mid, 0)) * 180 / M_PI, 60.0, 1e-3);
}

// Rotations of +100 and -100 degrees about z have quaternions with a negative dot product; without
// the sign flip their 50/50 blend is the identity instead of the 180-degree rotation between them.
TEST(Skinning, AntipodalQuaternionsAreAligned) {
  const std::vector<Eigen::Isometry3d> bones = {rigid(100, {0, 0, 1}, {0, 0, 0}),
                                                rigid(-100, {0, 0, 1}, {0, 0, 0})};
  const repose::DualQuaternion a = repose::DualQuaternion::fromIsometry(bones[0]);
  const repose::DualQuaternion b = repose::DualQuaternion::fromIsometry(bones[1]);
  ASSERT_LT(a.real.coeffs().dot(b.real.coeffs()), 0.0) << "test precondition: antipodal signs";
  repose::Points rest(2, 3);
  rest << 1, 0, 0, 0, 2, 5;
  repose::SparseWeights w;
  w.k = 2;
  w.weight = {0.5f, 0.5f, 0.5f, 0.5f};
  w.bone = {0, 1, 1, 0};  // either bone first
  repose::Points posed;
  repose::skinNodes(rest, w, {}, bones, repose::SkinningMethod::DualQuaternion, posed);
  EXPECT_LT((Eigen::Vector3d(posed.row(0)) - Eigen::Vector3d(-1, 0, 0)).norm(), 1e-6);
  EXPECT_LT((Eigen::Vector3d(posed.row(1)) - Eigen::Vector3d(0, -2, 5)).norm(), 1e-6);
}

TEST(Skinning, TranslationsBlendLinearly) {
  const std::vector<Eigen::Isometry3d> bones = {rigid(0, {0, 0, 1}, {0, 0, 0}),
                                                rigid(0, {0, 0, 1}, {10, -4, 2})};
  repose::Points rest(1, 3);
  rest << 1, 2, 3;
  repose::SparseWeights w;
  w.k = 2;
  w.weight = {0.75f, 0.25f};
  w.bone = {0, 1};
  for (auto method : {repose::SkinningMethod::DualQuaternion, repose::SkinningMethod::LinearBlend}) {
    repose::Points posed;
    repose::skinNodes(rest, w, {}, bones, method, posed);
    EXPECT_LT((Eigen::Vector3d(posed.row(0)) - Eigen::Vector3d(3.5, 1, 3.5)).norm(), 1e-6);
  }
}

TEST(Skinning, BadInputThrows) {
  const repose::Points rest = randomPoints(10, 4);
  const std::vector<Eigen::Isometry3d> bones = {Eigen::Isometry3d::Identity()};
  repose::Points posed;
  repose::SparseWeights w = oneBoneWeights(9, 4, 0);  // wrong node count
  EXPECT_THROW(repose::skinNodes(rest, w, {}, bones, repose::SkinningMethod::DualQuaternion, posed),
               std::invalid_argument);
  w = oneBoneWeights(10, 4, 1);  // bone 1 does not exist
  EXPECT_THROW(repose::skinNodes(rest, w, {}, bones, repose::SkinningMethod::LinearBlend, posed),
               std::invalid_argument);
  w = oneBoneWeights(10, 4, 0);
  std::vector<int> fixed(10, -1);
  fixed[3] = 2;  // out of range
  EXPECT_THROW(repose::skinNodes(rest, w, fixed, bones, repose::SkinningMethod::DualQuaternion, posed),
               std::invalid_argument);
  fixed.resize(5);  // wrong size
  EXPECT_THROW(repose::skinNodes(rest, w, fixed, bones, repose::SkinningMethod::DualQuaternion, posed),
               std::invalid_argument);
  EXPECT_THROW(repose::skinNodes(rest, w, {}, {}, repose::SkinningMethod::DualQuaternion, posed),
               std::invalid_argument);
}

// Throughput on 500k nodes, k = 4, 20 bones (prints the time; the bound only catches a gross
// regression such as per-node allocation).
TEST(Skinning, Throughput500kNodes) {
  const int n = 500000, k = 4, nb = 20;
  const repose::Points rest = randomPoints(n, 5);
  std::mt19937 rng(6);
  std::uniform_int_distribution<int> boneDist(0, nb - 1);
  std::uniform_real_distribution<float> u(0.1f, 1.0f);
  repose::SparseWeights w;
  w.k = k;
  for (int i = 0; i < n; ++i) {
    float s = 0, ws[k];
    for (int j = 0; j < k; ++j) s += ws[j] = u(rng);
    for (int j = 0; j < k; ++j) {
      w.weight.push_back(ws[j] / s);
      w.bone.push_back(std::uint16_t(boneDist(rng)));
    }
  }
  std::vector<Eigen::Isometry3d> bones;
  for (int b = 0; b < nb; ++b) bones.push_back(rigid(9.0 * b, {1.0, double(b), 2.0}, {double(b), 0.0, -double(b)}));
  std::vector<int> fixed(n, -1);
  for (int i = 0; i < n; i += 10) fixed[i] = i % nb;
  repose::Points posed;
  for (auto method : {repose::SkinningMethod::DualQuaternion, repose::SkinningMethod::LinearBlend}) {
    repose::skinNodes(rest, w, fixed, bones, method, posed);  // warm-up (allocates posed)
    const int reps = 10;
    const auto t0 = std::chrono::steady_clock::now();
    const std::clock_t c0 = std::clock();
    for (int r = 0; r < reps; ++r) repose::skinNodes(rest, w, fixed, bones, method, posed);
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count() / reps;
    // CPU time over all threads: robust when other processes share the cores.
    const double cpuMs = 1000.0 * double(std::clock() - c0) / CLOCKS_PER_SEC / reps;
    std::printf("[ timing   ] %s skinning of %d nodes (k=%d, %d bones): %.2f ms wall, %.2f ms CPU\n",
                method == repose::SkinningMethod::DualQuaternion ? "DQS" : "LBS", n, k, nb, ms, cpuMs);
    EXPECT_LT(ms, 500.0);
    EXPECT_TRUE(posed.allFinite());
  }
}

namespace {

// Random k-sparse weights over nb bones in random slot order, a few fixed and a few weightless nodes.
void randomRig(int n, int k, int nb, unsigned seed, repose::SparseWeights& w, std::vector<int>& fixed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> boneDist(0, nb - 1);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  w = repose::SparseWeights{};
  w.k = k;
  fixed.assign(n, -1);
  for (int i = 0; i < n; ++i) {
    std::vector<float> ws(k);
    float s = 0;
    for (int j = 0; j < k; ++j) s += ws[j] = (j == 2 ? 0.0f : u(rng));  // slot 2 unused
    for (int j = 0; j < k; ++j) {
      w.weight.push_back(i % 97 == 5 ? 0.0f : ws[j] / s);
      w.bone.push_back(std::uint16_t(boneDist(rng)));
    }
    if (i % 13 == 0) fixed[i] = boneDist(rng);
  }
}

}  // namespace

// The float cache path (what vtkReposeSkinning runs) agrees with the double path up to float
// rounding, for both methods, k = 2..6, fixed and weightless nodes, and antipodal bone quaternions.
TEST(Skinning, FloatCachePathMatchesDoublePath) {
  const int n = 40003, nb = 12;  // several threading chunks and a partial SIMD block
  repose::Points rest = randomPoints(n, 7);
  rest.rowwise() += Eigen::RowVector3d(800, -300, 1000);  // patient coordinates far from the origin
  std::vector<Eigen::Isometry3d> bones;
  for (int b = 0; b < nb; ++b)  // rotations up to ~330 degrees: many antipodal pairs
    bones.push_back(rigid(-170.0 + 29.0 * b, {1.0, 0.3 * b, -2.0}, {5.0 * b, -3.0, 2.0 * b}));
  for (int k : {2, 3, 4, 6}) {
    repose::SparseWeights w;
    std::vector<int> fixed;
    randomRig(n, k, nb, 100 + k, w, fixed);
    const repose::SkinningCache cache = repose::makeSkinningCache(rest, w, fixed);
    ASSERT_EQ(cache.nodeCount(), std::size_t(n));
    for (auto method : {repose::SkinningMethod::DualQuaternion, repose::SkinningMethod::LinearBlend}) {
      repose::Points expected;
      repose::skinNodes(rest, w, fixed, bones, method, expected);
      for (bool simd : {true, false}) {  // the SIMD kernels (if the CPU has them) and the portable ones
        if (!simd) setenv("REPOSE_NO_SIMD", "1", 1);
        std::vector<float> posed(3 * n, -1.0f);
        repose::skinNodes(cache, bones, method, posed.data());
        unsetenv("REPOSE_NO_SIMD");
        double err = 0;
        for (int i = 0; i < n; ++i)
          for (int c = 0; c < 3; ++c) err = std::max(err, std::abs(posed[3 * i + c] - expected(i, c)));
        // |x| ~ 1300 mm: float spacing 1.2e-4 mm, a few roundings.
        EXPECT_LT(err, 2e-3) << "k=" << k << (method == repose::SkinningMethod::LinearBlend ? " LBS" : " DQS")
                             << (simd ? "" : " portable");
        for (int i = 5; i < n; i += 97)
          if (fixed[i] < 0)  // weightless: stays at rest
            for (int c = 0; c < 3; ++c) EXPECT_EQ(posed[3 * i + c], float(rest(i, c)));
      }
    }
  }
}

TEST(Skinning, FloatCachePathBadInputThrows) {
  const repose::Points rest = randomPoints(10, 8);
  repose::SparseWeights w = oneBoneWeights(10, 4, 2);
  const repose::SkinningCache cache = repose::makeSkinningCache(rest, w, {});
  EXPECT_EQ(cache.maxBone, 2);
  std::vector<float> posed(30);
  const std::vector<Eigen::Isometry3d> two(2, Eigen::Isometry3d::Identity()), three(3, Eigen::Isometry3d::Identity());
  EXPECT_THROW(repose::skinNodes(cache, two, repose::SkinningMethod::DualQuaternion, posed.data()),
               std::invalid_argument);
  EXPECT_NO_THROW(repose::skinNodes(cache, three, repose::SkinningMethod::DualQuaternion, posed.data()));
  EXPECT_THROW(repose::makeSkinningCache(randomPoints(9, 8), w, {}), std::invalid_argument);
  EXPECT_THROW(repose::makeSkinningCache(rest, w, std::vector<int>(4, -1)), std::invalid_argument);
}

TEST(Skinning, FloatCacheThroughput500kNodes) {
  const int n = 500000, k = 4, nb = 20;
  const repose::Points rest = randomPoints(n, 9);
  repose::SparseWeights w;
  std::vector<int> fixed;
  randomRig(n, k, nb, 10, w, fixed);
  std::vector<Eigen::Isometry3d> bones;
  for (int b = 0; b < nb; ++b) bones.push_back(rigid(9.0 * b, {1.0, double(b), 2.0}, {double(b), 0.0, -double(b)}));
  const repose::SkinningCache cache = repose::makeSkinningCache(rest, w, fixed);
  std::vector<float> posed(3 * std::size_t(n));
  for (auto method : {repose::SkinningMethod::DualQuaternion, repose::SkinningMethod::LinearBlend}) {
    repose::skinNodes(cache, bones, method, posed.data());  // warm-up
    const int reps = 10;
    const auto t0 = std::chrono::steady_clock::now();
    const std::clock_t c0 = std::clock();
    for (int r = 0; r < reps; ++r) repose::skinNodes(cache, bones, method, posed.data());
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count() / reps;
    const double cpuMs = 1000.0 * double(std::clock() - c0) / CLOCKS_PER_SEC / reps;
    std::printf("[ timing   ] float %s skinning of %d nodes (k=%d, %d bones): %.2f ms wall, %.2f ms CPU\n",
                method == repose::SkinningMethod::DualQuaternion ? "DQS" : "LBS", n, k, nb, ms, cpuMs);
    EXPECT_LT(ms, 500.0);
    for (float v : posed) ASSERT_TRUE(std::isfinite(v));
  }
}

// A tet's segment is the bone with the largest weight summed over its nodes, even where no single
// node has that bone first; ties go to the lower bone.
TEST(BodySegments, LargestSummedWeightWins) {
  repose::SparseWeights w;
  w.k = 2;
  // node: (bone, weight) pairs
  const std::vector<std::pair<int, float>> rows = {{3, 0.6f}, {5, 0.4f},   // 0
                                                   {3, 0.55f}, {5, 0.45f}, // 1
                                                   {7, 0.5f}, {5, 0.5f},   // 2
                                                   {7, 0.9f}, {5, 0.1f},   // 3
                                                   {1, 1.0f}, {0, 0.0f},   // 4
                                                   {2, 1.0f}, {0, 0.0f}};  // 5
  for (const auto& [bone, weight] : rows) {
    w.bone.push_back(std::uint16_t(bone));
    w.weight.push_back(weight);
  }
  repose::Tets tets(3, 4);
  tets << 0, 1, 2, 3,   // bone 3: 1.15, bone 5: 1.45, bone 7: 1.4 -> 5, first at no node
      0, 1, 4, 5,       // bone 3: 1.15, bones 1 and 2: 1.0 -> 3
      4, 5, 4, 5;       // bones 1 and 2 tie at 2.0 -> 1
  EXPECT_EQ(repose::bodySegments(w, tets), (std::vector<int>{5, 3, 1}));
  repose::Tets bad(1, 4);
  bad << 0, 1, 2, 6;
  EXPECT_THROW(repose::bodySegments(w, bad), std::invalid_argument);
}

// Segments split by tissue label: one region per (segment, label) pair, numbered as they occur.
TEST(BodySegments, TissueSegmentsSplitEachSegmentByLabel) {
  const std::vector<int> segments{2, 2, 5, 2, 5, -1, 2};
  const std::vector<int> labels{7, 3, 7, 7, 7, 3, 3};
  EXPECT_EQ(repose::tissueSegments(segments, labels), (std::vector<int>{0, 1, 2, 0, 2, -1, 1}));
  EXPECT_THROW(repose::tissueSegments(segments, {7, 3}), std::invalid_argument);
}
