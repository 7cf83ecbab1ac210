#include "winding_number.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

namespace repose {
namespace {

constexpr double kFourPi = 4.0 * M_PI;

Eigen::Vector3d corner(const MeshVertices& V, const MeshTriangles& F, Eigen::Index t, int c) {
  return V.row(F(t, c)).transpose();
}

}  // namespace

double triangleSolidAngle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                          const Eigen::Vector3d& q) {
  const Eigen::Vector3d x = a - q, y = b - q, z = c - q;
  const double lx = x.norm(), ly = y.norm(), lz = z.norm();
  const double numerator = x.dot(y.cross(z));
  const double denominator = lx * ly * lz + x.dot(y) * lz + y.dot(z) * lx + z.dot(x) * ly;
  return 2.0 * std::atan2(numerator, denominator);
}

double windingNumberExact(const MeshVertices& V, const MeshTriangles& F, const Eigen::Vector3d& q) {
  checkTriangleIndices(V, F);
  double sum = 0;
  for (Eigen::Index t = 0; t < F.rows(); ++t)
    sum += triangleSolidAngle(corner(V, F, t, 0), corner(V, F, t, 1), corner(V, F, t, 2), q);
  return sum / kFourPi;
}

WindingNumberTree::WindingNumberTree(const MeshVertices& V, const MeshTriangles& F, const WindingNumberOptions& options)
    : beta_(options.beta), leafTriangles_(options.leafTriangles) {
  if (V.rows() == 0 || F.rows() == 0) throw std::invalid_argument("the surface has no triangles");
  if (!V.allFinite()) throw std::invalid_argument("the surface has a vertex that is not a finite number");
  if (!(beta_ > 1.0) || !std::isfinite(beta_)) throw std::invalid_argument("the winding number's beta must be above 1");
  if (leafTriangles_ < 1) throw std::invalid_argument("a leaf needs at least one triangle");
  checkTriangleIndices(V, F);
  std::vector<Eigen::Vector3d> centroids(std::size_t(F.rows()));
  for (Eigen::Index t = 0; t < F.rows(); ++t)
    centroids[std::size_t(t)] = (corner(V, F, t, 0) + corner(V, F, t, 1) + corner(V, F, t, 2)) / 3.0;
  std::vector<int> order(std::size_t(F.rows()));
  std::iota(order.begin(), order.end(), 0);
  nodes_.reserve(2 * std::size_t(F.rows()) / std::size_t(leafTriangles_) + 2);
  corners_.reserve(3 * std::size_t(F.rows()));
  build(order, 0, int(F.rows()), V, F, centroids);
}

/// Builds the node over triangles order[begin, end): a leaf when few enough, else split at the
/// median centroid along the longest axis of the centroids' box. Returns the node's index.
int WindingNumberTree::build(std::vector<int>& order, int begin, int end, const MeshVertices& V,
                             const MeshTriangles& F, const std::vector<Eigen::Vector3d>& centroids) {
  const int index = int(nodes_.size());
  nodes_.emplace_back();
  // Moments about the area-weighted centroid.
  Eigen::Vector3d centre = Eigen::Vector3d::Zero(), dipole = Eigen::Vector3d::Zero();
  double area = 0;
  for (int n = begin; n < end; ++n) {
    const Eigen::Index t = order[std::size_t(n)];
    const Eigen::Vector3d vectorArea =
        0.5 * (corner(V, F, t, 1) - corner(V, F, t, 0)).cross(corner(V, F, t, 2) - corner(V, F, t, 0));
    const double a = vectorArea.norm();
    centre += a * centroids[std::size_t(t)];
    area += a;
    dipole += vectorArea;
  }
  centre = area > 0 ? Eigen::Vector3d(centre / area) : centroids[std::size_t(order[std::size_t(begin)])];
  Node node;
  node.centre = centre;
  node.dipole = dipole;
  // C = integral of n d^T dA and S_i = integral of n_i d d^T dA, with d = x - centre.
  Eigen::Matrix3d first = Eigen::Matrix3d::Zero(), second[3] = {first, first, first};
  double radius2 = 0;
  for (int n = begin; n < end; ++n) {
    const Eigen::Index t = order[std::size_t(n)];
    const Eigen::Vector3d a = corner(V, F, t, 0), b = corner(V, F, t, 1), c = corner(V, F, t, 2);
    const Eigen::Vector3d vectorArea = 0.5 * (b - a).cross(c - a);
    const Eigen::Vector3d da = a - centre, db = b - centre, dc = c - centre, sum = da + db + dc;
    first += vectorArea * (sum / 3.0).transpose();
    // Exact second moment of a triangle: integral of d d^T dA = area/12 (sum d_v d_v^T + s s^T).
    const Eigen::Matrix3d moment =
        (da * da.transpose() + db * db.transpose() + dc * dc.transpose() + sum * sum.transpose()) / 12.0;
    for (int i = 0; i < 3; ++i) second[i] += vectorArea[i] * moment;
    radius2 = std::max({radius2, da.squaredNorm(), db.squaredNorm(), dc.squaredNorm()});
  }
  node.farDistance2 = beta_ * beta_ * radius2;
  reduceMoments(first, second, node);

  if (end - begin <= leafTriangles_) {
    node.begin = int(corners_.size() / 3);
    for (int n = begin; n < end; ++n)
      for (int c = 0; c < 3; ++c) corners_.push_back(corner(V, F, order[std::size_t(n)], c));
    node.end = int(corners_.size() / 3);
    nodes_[std::size_t(index)] = node;
    return index;
  }
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
  for (int n = begin; n < end; ++n) {
    lo = lo.cwiseMin(centroids[std::size_t(order[std::size_t(n)])]);
    hi = hi.cwiseMax(centroids[std::size_t(order[std::size_t(n)])]);
  }
  int axis = 0;
  (hi - lo).maxCoeff(&axis);
  const int middle = begin + (end - begin) / 2;
  // Ties broken by triangle index: the same tree whatever the standard library's nth_element does.
  std::nth_element(order.begin() + begin, order.begin() + middle, order.begin() + end, [&](int x, int y) {
    const double cx = centroids[std::size_t(x)][axis], cy = centroids[std::size_t(y)][axis];
    return cx < cy || (cx == cy && x < y);
  });
  node.left = build(order, begin, middle, V, F, centroids);
  node.right = build(order, middle, end, V, F, centroids);
  nodes_[std::size_t(index)] = node;
  return index;
}

/// The expansion's coefficients from the moments C and S_i (see expansion()).
void WindingNumberTree::reduceMoments(const Eigen::Matrix3d& first, const Eigen::Matrix3d (&second)[3], Node& node) {
  node.firstTrace = first.trace();
  const Eigen::Matrix3d c = first + first.transpose();
  const double quadratic[6] = {first(0, 0), first(1, 1), first(2, 2), c(0, 1), c(0, 2), c(1, 2)};
  std::copy(quadratic, quadratic + 6, node.firstQuadratic);
  for (int k = 0; k < 3; ++k)
    node.secondLinear[k] = 2.0 * (second[0](0, k) + second[1](1, k) + second[2](2, k)) + second[k].trace();
  // The monomial r_i r_j r_k of each index triple, in the order of secondCubic.
  auto monomial = [](int i, int j, int k) {
    int n[3] = {0, 0, 0};
    ++n[i], ++n[j], ++n[k];
    if (n[0] == 3) return 0;
    if (n[1] == 3) return 1;
    if (n[2] == 3) return 2;
    if (n[0] == 2) return n[1] == 1 ? 3 : 4;
    if (n[1] == 2) return n[0] == 1 ? 5 : 6;
    if (n[2] == 2) return n[0] == 1 ? 7 : 8;
    return 9;
  };
  std::fill(node.secondCubic, node.secondCubic + 10, 0.0);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) node.secondCubic[monomial(i, j, k)] += second[i](j, k);
}

/// Solid angle of a far cluster: integral of n . g(x - q) dA with g(r) = r / |r|^3, expanded about
/// r = centre - q to second order in x - centre:
///   order 0: N . r / |r|^3
///   order 1: sum C_ij dg_i/dr_j = tr(C) / |r|^3 - 3 r^T C r / |r|^5
///   order 2: 1/2 sum S_ijk d2g_i/dr_j dr_k, with
///            d2g_i/dr_j dr_k = -3 (delta_ij r_k + delta_ik r_j + delta_jk r_i) / |r|^5 + 15 r_i r_j r_k / |r|^7
double WindingNumberTree::expansion(const Node& node, const Eigen::Vector3d& q) {
  const Eigen::Vector3d r = node.centre - q;
  const double x = r.x(), y = r.y(), z = r.z();
  const double r2 = r.squaredNorm();
  const double inv = 1.0 / std::sqrt(r2);
  const double inv3 = inv / r2, inv5 = inv3 / r2, inv7 = inv5 / r2;
  const double* c = node.firstQuadratic;
  const double quadratic = c[0] * x * x + c[1] * y * y + c[2] * z * z + c[3] * x * y + c[4] * x * z + c[5] * y * z;
  const double* s = node.secondCubic;
  const double cubic = x * (x * (s[0] * x + s[3] * y + s[4] * z) + y * (s[5] * y + s[9] * z) + s[7] * z * z) +
                       y * y * (s[1] * y + s[6] * z) + z * z * (s[2] * z + s[8] * y);
  const double order0 = node.dipole.dot(r) * inv3;
  const double order1 = node.firstTrace * inv3 - 3.0 * quadratic * inv5;
  const double order2 = 0.5 * (-3.0 * node.secondLinear.dot(r) * inv5 + 15.0 * cubic * inv7);
  return order0 + order1 + order2;
}

double WindingNumberTree::operator()(const Eigen::Vector3d& q) const {
  double sum = 0;
  int stack[128];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& node = nodes_[std::size_t(stack[--top])];
    if ((node.centre - q).squaredNorm() > node.farDistance2) {
      sum += expansion(node, q);
    } else if (node.left < 0) {
      for (int t = node.begin; t < node.end; ++t)
        sum += triangleSolidAngle(corners_[3 * std::size_t(t)], corners_[3 * std::size_t(t) + 1],
                                  corners_[3 * std::size_t(t) + 2], q);
    } else {
      stack[top++] = node.right;
      stack[top++] = node.left;
    }
  }
  return sum / kFourPi;
}

}  // namespace repose
