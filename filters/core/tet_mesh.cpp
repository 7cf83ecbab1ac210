#include "tet_mesh.h"

#include <Eigen/Dense>

namespace repose {

double tetVolume(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                 const Eigen::Vector3d& d) {
  return (b - a).dot((c - a).cross(d - a)) / 6.0;
}

double meshVolume(const Points& nodes, const Tets& tets) {
  double v = 0;
  for (Eigen::Index t = 0; t < tets.rows(); ++t)
    v += tetVolume(nodes.row(tets(t, 0)), nodes.row(tets(t, 1)), nodes.row(tets(t, 2)),
                   nodes.row(tets(t, 3)));
  return v;
}

}  // namespace repose
