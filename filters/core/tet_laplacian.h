#pragma once
// Linear-FEM stiffness (cotangent) matrix of a tetrahedral mesh.
#include <Eigen/Sparse>

#include "tet_mesh.h"

namespace repose {

/// K (#V by #V, symmetric positive semi-definite): K_ij = -1/6 Σ_edges-opposite l_k cot θ_k over
/// tets sharing edge ij, i.e. ∫ ∇φ_i·∇φ_j with barycentric shape functions. Rows sum to zero.
/// Throws std::invalid_argument for out-of-range indices or degenerate (zero-volume) tets.
Eigen::SparseMatrix<double> tetStiffnessMatrix(const Points& nodes, const Tets& tets);

}  // namespace repose
