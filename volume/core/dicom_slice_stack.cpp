#include "dicom_slice_stack.h"

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace repose {
namespace {

std::string number(double x) {
  std::ostringstream text;
  text.precision(3);
  text << x;
  return text.str();
}

}  // namespace

SliceStackGeometry checkSliceStack(const std::vector<DicomSlice>& slices, double inPlaneSpacing) {
  if (slices.empty()) throw std::runtime_error("DICOM series has no slices");
  if (!(inPlaneSpacing > 0.0)) throw std::runtime_error("DICOM series has no valid pixel spacing");
  const auto& o = slices.front().orientation;
  const Eigen::Vector3d row(o[0], o[1], o[2]), column(o[3], o[4], o[5]);
  if (!(std::abs(row.norm() - 1.0) < 1e-3 && std::abs(column.norm() - 1.0) < 1e-3 && std::abs(row.dot(column)) < 1e-3))
    throw std::runtime_error("DICOM ImageOrientationPatient is not a pair of orthogonal unit vectors");
  SliceStackGeometry g;
  const Eigen::Vector3d normal = row.cross(column).normalized();
  for (int c = 0; c < 3; ++c) g.normal[std::size_t(c)] = normal[c];
  for (std::size_t k = 1; k < slices.size(); ++k)
    for (int c = 0; c < 6; ++c)
      if (std::abs(slices[k].orientation[std::size_t(c)] - o[std::size_t(c)]) > 1e-3)
        throw std::runtime_error("DICOM slices " + std::to_string(k) + " and 0 differ in orientation (a localizer "
                                 "or a second series in the folder?)");
  if (slices.size() == 1) return g;

  auto at = [&](std::size_t k) {
    const auto& p = slices[k].position;
    return Eigen::Vector3d(p[0], p[1], p[2]);
  };
  const Eigen::Vector3d span = at(slices.size() - 1) - at(0);
  const double along = span.dot(normal);
  if (!(std::abs(along) > 1e-6 * inPlaneSpacing))
    throw std::runtime_error("DICOM slices all lie at the same place (a multi-phase or repeated series?)");
  g.gantryTiltDegrees = std::acos(std::min(1.0, std::abs(along) / span.norm())) * 180.0 / M_PI;
  const double sign = along > 0 ? 1.0 : -1.0;
  const double gap = std::abs(along) / double(slices.size() - 1);
  for (std::size_t k = 1; k < slices.size(); ++k) {
    const Eigen::Vector3d d = at(k) - at(0);
    const double sideways = (d - d.dot(normal) * normal).norm();
    if (sideways > 0.01 * inPlaneSpacing)
      throw std::runtime_error("DICOM series is gantry-tilted (" + number(g.gantryTiltDegrees) +
                               " degrees: slice " + std::to_string(k) + " lies " + number(sideways) +
                               " mm off the slice normal); resample it to an orthogonal grid first");
    const double step = sign * (at(k) - at(k - 1)).dot(normal);
    if (std::abs(step - gap) > 0.01 * gap)
      throw std::runtime_error("DICOM slices " + std::to_string(k - 1) + " and " + std::to_string(k) + " are " +
                               number(step) + " mm apart where the series averages " + number(gap) +
                               " mm (a missing slice, or uneven spacing)");
  }
  g.sliceSpacing = gap;
  return g;
}

}  // namespace repose
