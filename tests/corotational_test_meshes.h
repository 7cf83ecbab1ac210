#pragma once
// The corotational FEM tests' meshes and settings: boxes of Kuhn tets, a block indented by a stamp, a
// bar folded at a hinge, and the fixed-corotated solve to a tight tolerance.
#include <Eigen/Geometry>
#include <algorithm>
#include <vector>

#include "box_tet_mesh.h"
#include "corotational_fem.h"
#include "tet_mesh.h"

struct Box {
  repose::Points nodes;
  repose::Tets tets;
  int nx, ny, nz;  // nodes per axis
  int id(int i, int j, int k) const { return (k * ny + j) * nx + i; }
};

/// cx by cy by cz cubes of edge h from the origin, each split into the 6 Kuhn tets.
inline Box makeBox(int cx, int cy, int cz, double h) {
  Box b;
  b.nx = cx + 1;
  b.ny = cy + 1;
  b.nz = cz + 1;
  kuhnBoxMesh(Eigen::Vector3d::Zero(), h * Eigen::Vector3d(cx, cy, cz), {cx, cy, cz}, b.nodes, b.tets);
  return b;
}

/// fixedBone of a box whose boundary nodes are held (bone 0) and interior free.
inline std::vector<int> boundaryFixed(const Box& b) {
  std::vector<int> fixed(std::size_t(b.nodes.rows()), -1);
  for (int k = 0; k < b.nz; ++k)
    for (int j = 0; j < b.ny; ++j)
      for (int i = 0; i < b.nx; ++i)
        if (i == 0 || j == 0 || k == 0 || i == b.nx - 1 || j == b.ny - 1 || k == b.nz - 1) fixed[b.id(i, j, k)] = 0;
  return fixed;
}

/// A block of cx by cy by cz unit cubes, its bottom fixed (bone 0) and a stamp (bone 1) pressed depth
/// into its top over the node columns from <= i <= to.
struct StampedBlock {
  Box b;
  std::vector<int> fixed;
  repose::Points stamped;
};
inline StampedBlock stampedBlock(int cx, int cy, int cz, int from, int to, double depth) {
  StampedBlock s{makeBox(cx, cy, cz, 1.0), {}, {}};
  const Box& b = s.b;
  s.fixed.assign(std::size_t(b.nodes.rows()), -1);
  s.stamped = b.nodes;
  for (int j = 0; j < b.ny; ++j)
    for (int i = 0; i < b.nx; ++i) {
      s.fixed[std::size_t(b.id(i, j, 0))] = 0;
      if (i >= from && i <= to) {
        s.fixed[std::size_t(b.id(i, j, b.nz - 1))] = 1;
        s.stamped(b.id(i, j, b.nz - 1), 2) -= depth;
      }
    }
  return s;
}

inline repose::Points transform(const repose::Points& P, const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
  repose::Points Q(P.rows(), 3);
  for (Eigen::Index i = 0; i < P.rows(); ++i) Q.row(i) = (R * P.row(i).transpose() + t).transpose();
  return Q;
}

inline Eigen::Matrix3d someRotation() {
  return Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
}

/// The fixed-corotated model solved to a tight tolerance (tests compare minima).
inline repose::CorotationalOptions fixedCorotated(
    repose::CorotationalOptions::Preconditioner pre = repose::CorotationalOptions::Jacobi) {
  repose::CorotationalOptions opt;
  opt.model = repose::CorotationalOptions::FixedCorotated;
  opt.preconditioner = pre;
  opt.tolerance = 1e-10;
  opt.stepTolerance = 1e-8;
  opt.maxNewtonIterations = 200;
  opt.energyTolerance = 0;
  opt.maxCgIterations = 20000;
  return opt;
}

// A bar bent by 86 degrees about a hinge on its inner face (bones 0: x <= 4 and 1: x >= 8, bone 1 the
// child), warm-started from a fold: the free nodes collapsed onto a curve. Newton and the untangling settle
// in a local minimum with a tet turned inside out; the continuation from the rest shape gets no fold
// on the way and ends in the minimum that a good warm start (the linear blend) reaches directly.
struct FoldedBar {
  Box b = makeBox(12, 4, 4, 1.0);
  std::vector<int> fixed;
  repose::Points blended, folded;
};
inline FoldedBar foldedBar() {
  FoldedBar f;
  const Box& b = f.b;
  f.fixed.assign(std::size_t(b.nodes.rows()), -1);
  f.blended = f.folded = b.nodes;
  const Eigen::Vector3d hinge(6, 2, 0);
  const Eigen::Matrix3d Rend = Eigen::AngleAxisd(1.5, Eigen::Vector3d::UnitY()).toRotationMatrix();
  for (Eigen::Index i = 0; i < b.nodes.rows(); ++i) {
    const double w = std::clamp((b.nodes(i, 0) - 4.0) / 4.0, 0.0, 1.0);
    const Eigen::Vector3d p = b.nodes.row(i).transpose();
    f.blended.row(i) = ((1 - w) * p + w * (Rend * (p - hinge) + hinge)).transpose();
    f.fixed[std::size_t(i)] = w == 0.0 ? 0 : w == 1.0 ? 1 : -1;
    const Eigen::Vector3d c(6, 2, 2);  // all free rest nodes here, then blended
    const Eigen::Vector3d collapsed = (1 - w) * c + w * (Rend * (c - hinge) + hinge);
    f.folded.row(i) =
        f.fixed[std::size_t(i)] < 0 ? Eigen::RowVector3d(collapsed.transpose()) : Eigen::RowVector3d(f.blended.row(i));
  }
  return f;
}
