#pragma once
// Free nodes pinched between bones: folds that no relaxation can remove.
#include <vector>

#include "tet_mesh.h"

namespace repose {

/// A free node that no position can unfold. Each tet around it whose other three nodes are all bone
/// nodes (held at their rigid positions) wants it on the positive side of that bone face; where those
/// half-spaces have no common point, one of the tets stays inverted wherever the node goes. Bones
/// pressed into each other do this (the shoulder girdle and the upper arm of an arm abducted further
/// than the scan's shoulder was carved for): neither Newton nor a fold-free continuation can help.
struct PinchedNode {
  int node = -1;
  /// How far the node's best position still lies on the wrong side of its worst bone face (length units).
  double shortfall = 0.0;
};

/// The pinched nodes of `posed`. Only the free node of an inverted tet whose other three nodes are fixed
/// can be pinched (a pinched node's bone-face tets cannot all be positive), so only those are examined:
/// a few per fold, each a small linear programme. Sorted by node.
std::vector<PinchedNode> findPinchedNodes(const Points& posed, const Tets& tets, const std::vector<int>& fixedBone);

/// The largest s (at most `cap`) for which some x has normals[i].x >= offsets[i] + s for every i
/// (normals of unit length): the margin by which the half-spaces' intersection clears its tightest
/// plane, negative where it is empty. Exact: the optimum of this linear programme lies at a vertex,
/// and every vertex is tried (so keep the planes few: a node has tens of tets). Directions no normal
/// spans are left free. +infinity with more than `maxPlanes` planes (not examined: taken as room).
double largestHalfSpaceMargin(const std::vector<Eigen::Vector3d>& normals, const std::vector<double>& offsets,
                              double cap, std::size_t maxPlanes = 48);

}  // namespace repose
