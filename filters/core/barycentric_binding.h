#pragma once
// Binding of arbitrary points (surface vertices) to the rest tet mesh, and moving them with it.
#include <Eigen/Core>
#include <vector>

#include "tet_mesh.h"

namespace repose {

using BarycentricCoords = Eigen::Matrix<float, Eigen::Dynamic, 4, Eigen::RowMajor>;  ///< #P by 4

struct Binding {
  std::vector<int> tet;           ///< #P tet index
  BarycentricCoords bary;         ///< #P by 4, sums to 1; negative entries for points outside the mesh
  std::size_t outsideCount = 0;   ///< points not inside any tet (bound to the nearest tet, extrapolated)
};

/// Binds each point to the rest tet containing it, or to the nearest tet (barycentric
/// extrapolation) when it is outside the mesh. Uses a uniform-grid spatial hash; threaded.
Binding bindPoints(const Points& restNodes, const Tets& tets, const Points& points);

/// posedPoints(p) = Σ_a bary(p,a) * posedNodes(tets(tet(p), a)). Threaded. posedPoints is resized.
void applyBinding(const Binding& binding, const Tets& tets, const Points& posedNodes, Points& posedPoints);

}  // namespace repose
