#pragma once
// Untangling of inverted tets by moving their free nodes: the last resort after an elastic solve,
// whose energy stays finite through det F = 0 and so may settle with a few tets turned inside out.
#include <vector>

#include "tet_mesh.h"

namespace repose {

struct UntangleOptions {
  /// A tet counts as repaired when its signed volume is at least this fraction of its rest volume.
  double minVolumeRatio = 0.05;
  /// Sweeps over the nodes of the tets still below minVolumeRatio.
  int maxSweeps = 50;
  /// Newton steps of each node's local problem (active-set changes; a few suffice).
  int maxLocalSteps = 30;
};

struct UntangleReport {
  int invertedBefore = 0;         ///< tets with signed volume <= 0 on input
  int invertedAfter = 0;          ///< ... on output
  int invertedRigid = 0;          ///< of which every node is fixed: nothing can move them
  int nodesMoved = 0;             ///< node moves accepted (a node may move in several sweeps)
  int sweeps = 0;
  double maxMove = 0.0;           ///< largest single node move (mm)
};

/// Moves free nodes of inverted tets, each by the smallest step that brings every tet around it to
/// at least minVolumeRatio of its rest volume (the projection of the node onto the polyhedron of
/// positions where those tets are positive: each tet's volume is affine in one node, so this is a
/// small convex problem; when the half-spaces have no common point, the least-squares compromise
/// between them, which a neighbour's later move may turn feasible; the target is lowered when the
/// full one is out of reach). A move is kept only if it turns no positive tet and lowers the number
/// of inverted tets around the node, or keeps it and lowers their volume deficit: the set of inverted
/// tets only shrinks, so a relaxation never leaves a tet inverted that its input had positive (a
/// move that freed two tets by turning a third let 4 tets of the Visible Human's hip pose, positive
/// when skinned, end inverted). Gauss-Seidel sweeps repeat while tets are still inverted and moves
/// still help.
///
/// rest       #V by 3 rest positions (rest volumes, the scale of minVolumeRatio)
/// tets       #T by 4, positive at rest
/// fixedBone  #V: >= 0 nodes never move
/// posed      #V by 3, in and out
UntangleReport untangleTets(const Points& rest, const Tets& tets, const std::vector<int>& fixedBone, Points& posed,
                            const UntangleOptions& options = {});

}  // namespace repose
