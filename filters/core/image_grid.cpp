#include "image_grid.h"

#include <cmath>

namespace repose {

bool ImageGrid::sameGridAs(const ImageGrid& o, double tol) const {
  if (dims != o.dims) return false;
  const double scale = spacing.cwiseAbs().maxCoeff();
  if (!((spacing - o.spacing).cwiseAbs().maxCoeff() <= tol * scale)) return false;
  if (!((origin - o.origin).cwiseAbs().maxCoeff() <= tol * std::max(1.0, scale))) return false;
  return (direction - o.direction).cwiseAbs().maxCoeff() <= tol;
}

}  // namespace repose
