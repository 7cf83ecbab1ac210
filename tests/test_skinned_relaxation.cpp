// relaxSkinnedMesh and its parts (relaxation_words, relaxation_regions, relaxation_progress_text,
// relaxation_warm_start): the words users type and their values, the regions each choice makes, the
// progress texts, and the warm start a second run takes from the first.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "body_segments.h"
#include "corotational_test_meshes.h"
#include "relaxation_progress_text.h"
#include "relaxation_words.h"
#include "skinned_relaxation.h"

using namespace repose;

namespace {

/// Weights of a bar split at x = 1.5 between bone 0 (left) and bone 1 (right), one bone per node.
SparseWeights leftRightWeights(const Points& nodes) {
  SparseWeights w;
  w.k = 1;
  for (Eigen::Index v = 0; v < nodes.rows(); ++v) {
    w.weight.push_back(1.0f);
    w.bone.push_back(nodes(v, 0) < 1.5 ? 0 : 1);
  }
  return w;
}

/// The stamped block's relaxation inputs (bottom fixed, a stamp pressed into the top).
RelaxationRestMesh stampedRest(const StampedBlock& s) {
  RelaxationRestMesh rest;
  rest.nodes = s.b.nodes;
  rest.tets = s.b.tets;
  rest.fixedBone = s.fixed;
  rest.key = 7;
  return rest;
}

}  // namespace

TEST(RelaxationWords, EachSettingListsItsWordsAndValues) {
  ASSERT_EQ(relaxationWords("model").size(), 2u);
  EXPECT_STREQ(relaxationWords("model")[0].word, "fixed-corotated");
  EXPECT_EQ(relaxationWordValue("model", "fixed-corotated"), CorotationalOptions::FixedCorotated);
  EXPECT_EQ(relaxationWordValue("model", "linear"), CorotationalOptions::Linear);
  const std::vector<std::string> volume = {"tissues", "segments", "body", "none"};
  ASSERT_EQ(relaxationWords("volume").size(), volume.size());
  for (std::size_t i = 0; i < volume.size(); ++i) EXPECT_EQ(relaxationWords("volume")[i].word, volume[i]);
  EXPECT_EQ(relaxationWordValue("volume", "tissues"), int(VolumeRegionChoice::Tissues));
  EXPECT_EQ(relaxationWordValue("volume", "segments"), int(VolumeRegionChoice::Segments));
  EXPECT_EQ(relaxationWordValue("volume", "body"), int(VolumeRegionChoice::Body));
  EXPECT_EQ(relaxationWordValue("volume", "none"), int(VolumeRegionChoice::None));
  EXPECT_EQ(relaxationWordValue("continuation", "if-inverted"), CorotationalOptions::IfInverted);
  EXPECT_EQ(relaxationWordValue("continuation", "never"), CorotationalOptions::Never);
  EXPECT_EQ(relaxationWordValue("continuation", "always"), CorotationalOptions::Always);
}

TEST(RelaxationWords, OtherWordsAndSettingsAreNone) {
  EXPECT_EQ(relaxationWordValue("model", "bogus"), -1);
  EXPECT_EQ(relaxationWordValue("model", "Linear"), -1);
  EXPECT_EQ(relaxationWordValue("volume", "linear"), -1);
  EXPECT_TRUE(relaxationWords("poisson").empty());
  EXPECT_EQ(relaxationWordValue("poisson", "linear"), -1);
}

TEST(RelaxationRegions, EachChoiceMakesItsRegions) {
  const Box b = makeBox(3, 1, 1, 1.0);
  const SparseWeights w = leftRightWeights(b.nodes);
  const std::vector<int> segments = bodySegments(w, b.tets);
  ASSERT_NE(std::count(segments.begin(), segments.end(), 0), 0);
  ASSERT_NE(std::count(segments.begin(), segments.end(), 1), 0);
  std::vector<int> labels(std::size_t(b.tets.rows()));
  for (std::size_t t = 0; t < labels.size(); ++t) labels[t] = t % 2 ? 5 : 6;
  const std::vector<int> whole(labels.size(), 0);
  auto regions = [&](VolumeRegionChoice c, const SparseWeights* weights, const std::vector<int>& tetLabels,
                     CorotationalOptions::Model model = CorotationalOptions::FixedCorotated) {
    CorotationalOptions o;
    o.model = model;
    setVolumeRegions(c, weights, tetLabels, b.tets, o);
    return std::make_pair(o.volumeRegions, o.pathVolumeRegions);
  };
  EXPECT_TRUE(regions(VolumeRegionChoice::None, &w, labels).first.empty());
  EXPECT_EQ(regions(VolumeRegionChoice::Body, &w, labels).first, whole);
  EXPECT_EQ(regions(VolumeRegionChoice::Segments, &w, labels).first, segments);
  EXPECT_TRUE(regions(VolumeRegionChoice::Segments, &w, labels).second.empty());
  // Without weights the body is one region; without labels (or labels of another length) the segments.
  EXPECT_EQ(regions(VolumeRegionChoice::Segments, nullptr, labels).first, whole);
  EXPECT_EQ(regions(VolumeRegionChoice::Tissues, nullptr, labels).first, whole);
  EXPECT_EQ(regions(VolumeRegionChoice::Tissues, &w, {}).first, segments);
  EXPECT_EQ(regions(VolumeRegionChoice::Tissues, &w, {1, 2}).first, segments);
  const auto tissues = regions(VolumeRegionChoice::Tissues, &w, labels);
  EXPECT_EQ(tissues.first, tissueSegments(segments, labels));
  EXPECT_EQ(tissues.second, segments);  // the continuation's path keeps the segments
  // The linear model has no region terms.
  EXPECT_TRUE(regions(VolumeRegionChoice::Tissues, &w, labels, CorotationalOptions::Linear).first.empty());
  EXPECT_TRUE(regions(VolumeRegionChoice::Body, &w, labels, CorotationalOptions::Linear).first.empty());
}

TEST(RelaxationProgressText, NamesEveryPhase) {
  RelaxationProgressText text;
  RelaxationProgress p;
  EXPECT_EQ(text(p), "FEM set-up");
  p.phase = RelaxationProgress::Newton;
  p.newtonIterations = 2;
  EXPECT_EQ(text(p), "Newton step 3");
  p.phase = RelaxationProgress::Untangling;
  EXPECT_EQ(text(p), "untangling inverted tets");
  p.phase = RelaxationProgress::Neighbourhood;
  EXPECT_EQ(text(p), "relaxing untangled neighbourhoods");
  p.phase = RelaxationProgress::StrainedRegion;
  EXPECT_EQ(text(p), "relaxing the strained region");
  p.phase = RelaxationProgress::Linear;
  p.outerIteration = 0;
  EXPECT_EQ(text(p), "linear solve 1");
  p.phase = RelaxationProgress::Continuation;
  p.continuationSteps = 11;
  p.pathFraction = 0.0;
  EXPECT_EQ(text(p).rfind("fold-free continuation, step 12, path 0 %", 0), 0u) << text(p);
}

TEST(RelaxationWarmStart, OffersOnlyItsOwnRestMeshAndTheNonlinearModel) {
  RelaxationWarmStart warm;
  const Points input = Points::Zero(4, 3);
  const Points output = Points::Constant(4, 3, 0.5);
  CorotationalOptions o;
  warm.offer(true, 3, 4, o);
  EXPECT_EQ(o.startCorrection.size(), 0) << "nothing remembered yet";
  warm.remember(3, input, output);
  warm.offer(false, 3, 4, o);
  EXPECT_EQ(o.startCorrection.size(), 0) << "not wanted";
  warm.offer(true, 4, 4, o);
  EXPECT_EQ(o.startCorrection.size(), 0) << "another rest mesh";
  warm.offer(true, 3, 5, o);
  EXPECT_EQ(o.startCorrection.size(), 0) << "another node count";
  o.model = CorotationalOptions::Linear;
  warm.offer(true, 3, 4, o);
  EXPECT_EQ(o.startCorrection.size(), 0) << "the linear model";
  o.model = CorotationalOptions::FixedCorotated;
  warm.offer(true, 3, 4, o);
  EXPECT_TRUE(o.startCorrection.isApprox(output - input));
  warm.forget();
  CorotationalOptions again;
  warm.offer(true, 3, 4, again);
  EXPECT_EQ(again.startCorrection.size(), 0) << "forgotten";
}

TEST(SkinnedRelaxation, IsRelaxCorotationalAndWarmStartsTheNextRun) {
  const StampedBlock s = stampedBlock(4, 2, 3, 1, 2, 0.4);
  const RelaxationRestMesh rest = stampedRest(s);
  CorotationalOptions options;
  options.strainedRegionThreshold = 0.0;
  // The same solve as relaxCorotational's, with the body as one region.
  Points direct = s.stamped;
  CorotationalOptions bodyOptions = options;
  bodyOptions.volumeRegions.assign(std::size_t(s.b.tets.rows()), 0);
  relaxCorotational(rest.nodes, rest.tets, rest.fixedBone, direct, bodyOptions);
  RelaxationWarmStart warm;
  Points first = s.stamped;
  CorotationalReport report;
  relaxSkinnedMesh(rest, VolumeRegionChoice::Body, options, true, warm, first, &report);
  EXPECT_EQ(first, direct);
  EXPECT_FALSE(report.correctedStart);
  // Run again from the same skinned start: it starts from the first result and stays there.
  Points second = s.stamped;
  CorotationalReport again;
  relaxSkinnedMesh(rest, VolumeRegionChoice::Body, options, true, warm, second, &again);
  EXPECT_TRUE(again.correctedStart);
  EXPECT_LT(again.newtonIterations, report.newtonIterations);
  EXPECT_LT((second - first).cwiseAbs().maxCoeff(), 1e-3);
  // Without the warm start the run is cold again.
  Points third = s.stamped;
  CorotationalReport cold;
  relaxSkinnedMesh(rest, VolumeRegionChoice::Body, options, false, warm, third, &cold);
  EXPECT_FALSE(cold.correctedStart);
  EXPECT_EQ(third, direct);
}
