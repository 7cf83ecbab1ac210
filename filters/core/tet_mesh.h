#pragma once
// The volumetric mesh of the body and its per-node / per-tet attributes.
#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace repose {

using Points = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;      ///< #V by 3
using Tets = Eigen::Matrix<int, Eigen::Dynamic, 4, Eigen::RowMajor>;           ///< #T by 4 node indices
using Triangles = Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor>;      ///< #F by 3 node indices

struct TetMesh {
  Points nodes;                      ///< #V by 3 rest positions (mm)
  Tets tets;                         ///< #T by 4, positively oriented (det > 0)
  std::vector<int> fixedBone;        ///< #V: bone (joint) index the node is fixed to, -1 if free
  std::vector<std::int32_t> tetLabel;  ///< #T: label value at the tet's centroid
};

/// Signed volume of tet (a,b,c,d): det[b-a, c-a, d-a] / 6.
double tetVolume(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                 const Eigen::Vector3d& d);
/// Sum of signed tet volumes for the given node positions.
double meshVolume(const Points& nodes, const Tets& tets);

}  // namespace repose
