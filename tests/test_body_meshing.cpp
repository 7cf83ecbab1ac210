// meshBody (core/body_meshing.h), the order and heuristics of `repose prepare`'s meshing, with a
// surface extraction of the test's own (the box around the body mask): the tet mesh fills the box,
// bones get fixed nodes and tets their labels, a surface TetGen refuses (a decimated one that
// intersects itself) is meshed again undecimated, TetGen's size is announced before each run, a
// bone without voxels is a warning, and the budget's second pass runs exactly when TetGen overshoots.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <string>
#include <vector>

#include "body_meshing.h"
#include "tet_mesh.h"
#include "triangle_soups.h"

using namespace repose;

namespace {

/// Soft tissue (3) in a 30x12x12 grid of 1 mm voxels, bones 20 and 21 inside it.
LabelVolume twoBones() {
  LabelVolume v;
  v.grid.dims = {30, 12, 12};
  v.grid.origin = {0, 0, 0};
  v.grid.spacing = {1, 1, 1};
  v.grid.direction.setIdentity();
  v.data.assign(v.grid.voxelCount(), 0);
  for (int k = 1; k < 11; ++k)
    for (int j = 1; j < 11; ++j)
      for (int i = 1; i < 29; ++i) {
        int label = 3;
        if (j >= 3 && j < 9 && k >= 3 && k < 9) label = i >= 3 && i < 13 ? 20 : (i >= 17 && i < 27 ? 21 : 3);
        v.at(i, j, k) = label;
      }
  return v;
}

Skeleton threeJoints() {
  Skeleton s;
  s.joints.resize(3);
  s.joints[0] = {"root", -1, {8, 6, 6}, {20}};
  s.joints[1] = {"knee", 0, {15, 6, 6}, {21}};
  s.joints[2] = {"ghost", 1, {25, 6, 6}, {22}};  // a label the volume does not have
  return s;
}

/// The box around the mask's voxels, in mm; for a decimated request (reduction > 0) that box with a
/// second one pushed through its side, which TetGen refuses (the surface intersects itself).
struct BoxExtraction {
  std::vector<double> reductions;
  bool operator()(const MaskVolume& body, double reduction, Points& V, Triangles& F) {
    reductions.push_back(reduction);
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
    for (int k = 0; k < body.grid.dims[2]; ++k)
      for (int j = 0; j < body.grid.dims[1]; ++j)
        for (int i = 0; i < body.grid.dims[0]; ++i)
          if (body.at(i, j, k)) {
            const Eigen::Vector3d p = body.grid.indexToPhysical(Eigen::Vector3d(i, j, k));
            lo = lo.cwiseMin(p);
            hi = hi.cwiseMax(p);
          }
    if (lo.x() > hi.x()) return false;
    const Eigen::Vector3d half = 0.5 * Eigen::Map<const Eigen::Vector3d>(body.grid.spacing.data());
    TriangleMesh m = box(lo - half, hi + half);
    if (reduction > 0) m = concat(m, box(0.5 * (lo + hi), hi + 4 * half));
    V = m.V;
    F = m.F;
    return true;
  }
};

}  // namespace

TEST(BodyMeshing, RefusedDecimatedSurfaceIsMeshedAgainWhole) {
  const LabelVolume labels = twoBones();
  BodyMeshingOptions options;
  options.mask.meshSpacingMm = 1;  // the scan's grid: no budget
  options.surfaceReduction = 0.5;
  BoxExtraction boxes;
  std::vector<std::string> told;
  BodyMeshing out;
  meshBody(labels, nullptr, threeJoints(), options, std::ref(boxes),
           [&](const std::string& text) { told.push_back(text); }, out);

  ASSERT_EQ(boxes.reductions, (std::vector<double>{0.5, 0.0}));
  EXPECT_NE(out.report.find("decimated surface rejected"), std::string::npos) << out.report;
  ASSERT_EQ(told.size(), 2u);  // announced before each TetGen run
  EXPECT_EQ(told[1].rfind("TetGen: 12 surface triangles and ", 0), 0u) << told[1];

  const TetMesh& m = out.mesh;
  ASSERT_GT(m.tets.rows(), 0);
  for (Eigen::Index t = 0; t < m.tets.rows(); ++t)
    ASSERT_GT(tetVolume(m.nodes.row(m.tets(t, 0)), m.nodes.row(m.tets(t, 1)), m.nodes.row(m.tets(t, 2)),
                        m.nodes.row(m.tets(t, 3))),
              0.0);
  // The peeled body (one voxel layer off the 28x10x10 mm block) is what is meshed.
  EXPECT_NEAR(meshVolume(m.nodes, m.tets), 26.0 * 8 * 8, 1e-6);
  ASSERT_EQ(m.fixedBone.size(), std::size_t(m.nodes.rows()));
  std::size_t fixed[3] = {0, 0, 0};
  for (int b : m.fixedBone) {
    ASSERT_LT(b, 2);  // the ghost bone has no voxel, so no node
    if (b >= 0) ++fixed[b];
  }
  EXPECT_GT(fixed[0], 0u);
  EXPECT_GT(fixed[1], 0u);
  EXPECT_EQ(out.fixedNodes, fixed[0] + fixed[1]);
  for (int label : m.tetLabel) EXPECT_TRUE(label == 3 || label == 20 || label == 21) << label;
  EXPECT_EQ(out.surfaceTriangles, 12u);
  EXPECT_GT(out.seedPoints, 0u);
  EXPECT_EQ(out.meshingSpacingMm, 1.0);
  ASSERT_EQ(out.warnings.size(), 1u);
  EXPECT_NE(out.warnings[0].find("bone 'ghost' has no mesh node"), std::string::npos) << out.warnings[0];
  for (const char* line : {"body mask: ", "meshing grid: 30x12x12 at 1 mm", "bone seeds: ", "tetgen: ", "tagging: ",
                           "  ghost: 0 fixed nodes"})
    EXPECT_NE(out.report.find(line), std::string::npos) << line << "\n" << out.report;
}

TEST(BodyMeshing, BudgetMeshesAgainExactlyWhenTetGenOvershoots) {
  const LabelVolume labels = twoBones();
  for (double budget : {1000.0, 100000.0}) {
    BodyMeshingOptions options;
    options.mask.maxTets = budget;
    options.tets.maxTetVolume = 3;  // mm^3: far more tets than a 1000-tet budget predicts from the surface
    BoxExtraction boxes;
    BodyMeshing out;
    meshBody(labels, nullptr, threeJoints(), options, std::ref(boxes), {}, out);
    ASSERT_GT(out.mesh.tets.rows(), 0);
    // The first TetGen line's tet count decides whether the second pass runs.
    const std::size_t at = out.report.find("tetgen: ");
    ASSERT_NE(at, std::string::npos);
    const double firstTets = std::stod(out.report.substr(out.report.find(" nodes, ", at) + 8));
    const bool again = out.report.find("meshing again") != std::string::npos;
    EXPECT_EQ(again, firstTets > 1.1 * budget) << out.report;
    EXPECT_EQ(again, budget == 1000.0) << out.report;  // the small budget overshoots, the large one does not
    EXPECT_EQ(boxes.reductions.size(), again ? 2u : 1u);
    EXPECT_NE(out.report.find("chosen for at most " + std::to_string(static_cast<long long>(budget)) + " tets"),
              std::string::npos)
        << out.report;
  }
}

TEST(BodyMeshing, NoSurfaceIsAnErrorAndTheReportKeepsWhatRan) {
  BodyMeshingOptions options;
  options.mask.meshSpacingMm = 1;
  BodyMeshing out;
  EXPECT_THROW(meshBody(twoBones(), nullptr, threeJoints(), options,
                        [](const MaskVolume&, double, Points&, Triangles&) { return false; }, {}, out),
               std::invalid_argument);
  EXPECT_NE(out.report.find("bone seeds: "), std::string::npos) << out.report;
  EXPECT_EQ(out.report.find("tetgen: "), std::string::npos) << out.report;
}
