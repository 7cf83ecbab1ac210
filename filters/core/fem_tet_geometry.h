#pragma once
// The corotational FEM's per-tet geometry (internal to corotational_fem): rest shapes and their
// shape-function gradients, element rotations, and the counts of inverted tets the solves guard.
#include <Eigen/Core>
#include <vector>

#include "corotational_fem.h"
#include "tet_mesh.h"

namespace repose {
namespace fem {

using Mat3 = Eigen::Matrix3d;
using Vec3 = Eigen::Vector3d;

/// Row i of P as a column vector.
inline Vec3 node(const Points& P, int i) { return P.row(i).transpose(); }

/// Per-tet rest data. Row k of DmInv is the gradient of shape function N_{k+1}; N_0's is minus
/// their sum (gradients are recomputed rather than stored: memory is the limit on large meshes).
struct RestTet {
  Mat3 DmInv;
  double volume;  ///< rest volume (mm^3)
};

/// The rest data of every tet of (rest, tets), #T entries.
/// Throws std::invalid_argument naming the first tet found degenerate or inverted at rest.
std::vector<RestTet> restTetsOf(const Points& rest, const Tets& tets);

/// Shape-function gradients of a tet (1/mm): row a is grad N_a.
inline Eigen::Matrix<double, 4, 3> gradients(const RestTet& rt) {
  Eigen::Matrix<double, 4, 3> g;
  g.bottomRows<3>() = rt.DmInv;
  g.row(0) = -rt.DmInv.colwise().sum();
  return g;
}

/// Rotation of F's polar decomposition, det = +1 even for inverted or degenerate F: the sign goes
/// to the smallest singular value (Irving et al. 2004), so an inverted tet is pushed back, not flipped.
Mat3 robustRotation(const Mat3& F);

/// Whether tet t has a free node (one no bone holds, fixedBone < 0).
inline bool hasFreeNode(const Tets& tets, const std::vector<int>& fixedBone, std::size_t t) {
  for (int a = 0; a < 4; ++a)
    if (fixedBone[std::size_t(tets(Eigen::Index(t), a))] < 0) return true;
  return false;
}

/// Tets of P (#V by 3) with signed volume <= 0; with `only` (#T flags), among the tets it flags.
int countInverted(const Points& P, const Tets& tets, const std::vector<char>* only = nullptr);

/// Whether some tet positive in `from` is flat or inverted in `to` (both #V by 3).
bool turnsAPositiveTet(const Points& from, const Points& to, const Tets& tets);

/// The report's counts after relaxing P: inverted tets, those no free node can repair (all nodes
/// fixed), and the free nodes pinched between bones (pinched_nodes.h) when some fold has a free node.
void countInvertedAfter(const Points& P, const Tets& tets, const std::vector<int>& fixedBone, CorotationalReport& rep);

}  // namespace fem
}  // namespace repose
