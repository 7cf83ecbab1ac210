// DICOM slice stacks: a regular grid is accepted with its spacing; tilt, gaps and mixed orientations
// are refused with a reason.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>

#include "dicom_slice_stack.h"

using repose::checkSliceStack;
using repose::DicomSlice;

namespace {

// n axial slices (rows along x, columns along y) from z0 every dz, each shifted by dy per slice.
std::vector<DicomSlice> axialStack(int n, double z0, double dz, double dy = 0.0) {
  std::vector<DicomSlice> s(static_cast<std::size_t>(n));
  for (int k = 0; k < n; ++k) {
    s[std::size_t(k)].orientation = {1, 0, 0, 0, 1, 0};
    s[std::size_t(k)].position = {-100.0, -80.0 + dy * k, z0 + dz * k};
  }
  return s;
}

std::string refusal(const std::vector<DicomSlice>& s) {
  try {
    checkSliceStack(s, 0.7);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(DicomSliceStack, ARegularStackGivesItsSpacingAndNormal) {
  const auto g = checkSliceStack(axialStack(40, -300.0, 2.5), 0.7);
  EXPECT_NEAR(g.sliceSpacing, 2.5, 1e-12);
  EXPECT_NEAR(g.normal[2], 1.0, 1e-12);
  EXPECT_NEAR(g.gantryTiltDegrees, 0.0, 1e-9);
  // Stacked head to feet (decreasing z): the same spacing.
  EXPECT_NEAR(checkSliceStack(axialStack(10, 0.0, -1.25), 0.7).sliceSpacing, 1.25, 1e-12);
}

TEST(DicomSliceStack, AnObliqueButOrthogonalStackIsAGrid) {
  // Rows and columns rotated 30 degrees about x; slices stacked along their normal.
  const double c = std::cos(M_PI / 6), s = std::sin(M_PI / 6);
  std::vector<DicomSlice> st(12);
  for (int k = 0; k < 12; ++k) {
    st[std::size_t(k)].orientation = {1, 0, 0, 0, c, s};
    st[std::size_t(k)].position = {0.0, -s * 3.0 * k, c * 3.0 * k};  // normal = row x column = (0, -s, c)
  }
  const auto g = checkSliceStack(st, 0.7);
  EXPECT_NEAR(g.sliceSpacing, 3.0, 1e-9);
  EXPECT_NEAR(g.normal[1], -s, 1e-12);
}

TEST(DicomSliceStack, GantryTiltIsRefusedWithItsAngle) {
  // Each slice 0.35 mm further along y for a 2 mm step: atan(0.35 / 2) = 9.9 degrees.
  const std::string why = refusal(axialStack(20, 0.0, 2.0, 0.35));
  EXPECT_NE(why.find("gantry-tilted (9.93 degrees"), std::string::npos) << why;
  // A shift well below the tolerance (1 % of the pixel) is rounding in the header, not tilt.
  EXPECT_EQ(refusal(axialStack(20, 0.0, 2.0, 1e-5)), "");
}

TEST(DicomSliceStack, AMissingSliceOrMixedOrientationIsRefused) {
  auto gap = axialStack(20, 0.0, 2.0);
  gap.erase(gap.begin() + 7);
  EXPECT_NE(refusal(gap).find("a missing slice"), std::string::npos) << refusal(gap);
  auto mixed = axialStack(20, 0.0, 2.0);
  mixed[3].orientation = {0, 1, 0, 0, 0, -1};  // a sagittal localizer among axial slices
  EXPECT_NE(refusal(mixed).find("differ in orientation"), std::string::npos) << refusal(mixed);
  auto same = axialStack(5, 0.0, 0.0);
  EXPECT_NE(refusal(same).find("same place"), std::string::npos) << refusal(same);
  EXPECT_NE(refusal({}).find("no slices"), std::string::npos);
}
