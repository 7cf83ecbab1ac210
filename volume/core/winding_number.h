#pragma once
// Generalized winding number of a triangle soup (Jacobson, Kavan and Sorkine-Hornung 2013):
//   w(q) = 1/(4 pi) * sum over triangles of the signed solid angle the triangle subtends at q.
// It is 1 inside a closed outward-facing surface and 0 outside, counts layers where closed pieces
// overlap (2 inside two of them), is -1 inside an inward-facing piece, and varies smoothly across
// holes, where the w = 1/2 level spans the hole as a membrane would. So w >= 1/2 is an inside that
// survives holes, overlapping pieces and nested shells, as surfaces come from atlases and scanners.
// WindingNumberTree evaluates it in about log(#F) time (Barill, Dickson, Schmidt, Levin and Jacobson
// 2018, "Fast Winding Numbers for Soups and Clouds"): a bounding volume hierarchy over the
// triangles; a cluster far from q (farther than beta times its radius) contributes through the
// second-order Taylor expansion of its dipole field, near triangles through their exact solid angle.
#include <Eigen/Core>
#include <cstddef>
#include <vector>

#include "mesh_topology.h"

namespace repose {

/// Signed solid angle (steradians, within [-2 pi, 2 pi]) of triangle (a, b, c) seen from q
/// (Van Oosterom and Strackee 1983): positive when the side the normal (b-a)x(c-a) points to faces
/// away from q. 0 when q lies in the triangle's plane.
double triangleSolidAngle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                          const Eigen::Vector3d& q);

/// w(q) by the direct sum over every triangle of (V #V by 3, F #F by 3): O(#F), the reference the
/// tree is measured against. Throws std::invalid_argument on an index out of range.
double windingNumberExact(const MeshVertices& V, const MeshTriangles& F, const Eigen::Vector3d& q);

struct WindingNumberOptions {
  /// A cluster is summed by its expansion when q lies farther than beta times the cluster's radius
  /// from its centre. Barill et al.'s default 2 keeps the error below about 1e-3 on real meshes;
  /// larger is more accurate and slower.
  double beta = 2.0;
  /// Triangles per leaf of the hierarchy.
  int leafTriangles = 8;
};

/// Fast, hierarchical winding number of one triangle soup. Immutable once built: evaluations are
/// thread-safe and each depends only on q (deterministic whatever the threads).
class WindingNumberTree {
 public:
  /// V #V by 3, F #F by 3 (any units: w is scale-invariant). Degenerate triangles contribute
  /// nothing. Throws std::invalid_argument on an empty soup, an index out of range, a non-finite
  /// vertex or bad options.
  WindingNumberTree(const MeshVertices& V, const MeshTriangles& F, const WindingNumberOptions& options = {});

  /// w(q): exact for q near the surface, within the expansion's error far from it.
  double operator()(const Eigen::Vector3d& q) const;

  std::size_t nodeCount() const { return nodes_.size(); }

 private:
  /// A cluster of triangles and the moments of its dipole field about its centre, reduced to the
  /// coefficients the expansion needs (polynomials in r = centre - q).
  struct Node {
    Eigen::Vector3d centre;      ///< area-weighted centroid of the cluster's triangles
    double farDistance2 = 0;     ///< (beta * radius)^2: beyond it the expansion is used
    Eigen::Vector3d dipole;      ///< sum of vector areas: integral of n dA
    double firstTrace = 0;       ///< trace of C = integral of n (x - centre)^T dA
    double firstQuadratic[6];    ///< r^T C r as coefficients of xx, yy, zz, xy, xz, yz
    Eigen::Vector3d secondLinear;  ///< contraction of the second moment with the identity, against r
    double secondCubic[10];      ///< the second moment against r r r: xxx yyy zzz xxy xxz xyy yyz xzz yzz xyz
    int left = -1, right = -1;   ///< children, -1 for a leaf
    int begin = 0, end = 0;      ///< leaf: triangles [begin, end) of corners_ (in threes)
  };
  int build(std::vector<int>& order, int begin, int end, const MeshVertices& V, const MeshTriangles& F,
            const std::vector<Eigen::Vector3d>& centroids);
  static void reduceMoments(const Eigen::Matrix3d& first, const Eigen::Matrix3d (&second)[3], Node& node);
  static double expansion(const Node& node, const Eigen::Vector3d& q);

  double beta_;
  int leafTriangles_;
  std::vector<Node> nodes_;
  std::vector<Eigen::Vector3d> corners_;  ///< triangle corners in leaf order, three per triangle
};

}  // namespace repose
