#pragma once
// Whether the slices of a DICOM series make one regular 3-D grid, from their geometry alone.
//
// A CT series is a stack of 2-D slices, each with its own position (ImagePositionPatient) and
// orientation (ImageOrientationPatient). It is a grid only when every slice has the same
// orientation, the slices lie along the slice normal (a gantry-tilted acquisition shifts each one
// sideways: the volume is a parallelepiped, not a box) and they are evenly spaced (no slice missing).
// A reader that assumed it anyway would place anatomy millimetres off, silently: these checks turn
// that into an error that says what is wrong.
#include <array>
#include <string>
#include <vector>

namespace repose {

struct DicomSlice {
  std::array<double, 3> position{};     ///< ImagePositionPatient (mm, LPS): the first voxel's centre
  std::array<double, 6> orientation{};  ///< ImageOrientationPatient: row then column direction cosines
};

struct SliceStackGeometry {
  double sliceSpacing = 0.0;          ///< mm between consecutive slices, along the normal
  std::array<double, 3> normal{};     ///< row x column: the direction of increasing slice index
  double gantryTiltDegrees = 0.0;     ///< angle between the stacking direction and the normal
};

/// slices: in stacking order (as sorted by position along the normal), at least one.
/// inPlaneSpacing: the smaller pixel spacing (mm), the scale of the tolerances (1 % of it for the
/// sideways shift, 1 % of the mean gap for uneven gaps).
/// Returns the geometry; throws std::runtime_error with a one-line reason when the slices differ in
/// orientation, are gantry-tilted, coincide, or are unevenly spaced (a missing slice).
SliceStackGeometry checkSliceStack(const std::vector<DicomSlice>& slices, double inPlaneSpacing);

}  // namespace repose
