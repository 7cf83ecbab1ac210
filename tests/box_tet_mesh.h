#pragma once
// The unit tests' common mesh: the box [lo, hi] as n cubes per axis, each cube cut into the 6 Kuhn
// tets around its main diagonal (conforming faces, dihedral angles <= 90 degrees), every tet
// positively oriented. Node (i, j, k) has index (k * (n[1] + 1) + j) * (n[0] + 1) + i. With jitter > 0,
// interior nodes move by up to jitter of a cell per axis (seeded); below about 0.2 no tet inverts.
#include <array>
#include <random>

#include <Eigen/Core>

#include "tet_mesh.h"

inline void kuhnBoxMesh(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, const std::array<int, 3>& n,
                        repose::Points& V, repose::Tets& T, double jitter = 0.0, unsigned seed = 1) {
  const int sx = n[0] + 1, sy = n[1] + 1, sz = n[2] + 1;
  V.resize(Eigen::Index(sx) * sy * sz, 3);
  auto id = [&](int i, int j, int k) { return (k * sy + j) * sx + i; };
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-jitter, jitter);
  for (int k = 0; k < sz; ++k)
    for (int j = 0; j < sy; ++j)
      for (int i = 0; i < sx; ++i) {
        Eigen::Vector3d f(double(i) / n[0], double(j) / n[1], double(k) / n[2]);
        if (jitter > 0 && i > 0 && j > 0 && k > 0 && i < n[0] && j < n[1] && k < n[2])
          for (int a = 0; a < 3; ++a) f(a) += u(rng) / n[std::size_t(a)];
        V.row(id(i, j, k)) = (lo + (hi - lo).cwiseProduct(f)).transpose();
      }
  const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  T.resize(Eigen::Index(n[0]) * n[1] * n[2] * 6, 4);
  int t = 0;
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i)
        for (const auto& p : perms) {
          int c[3] = {i, j, k}, row[4];
          row[0] = id(c[0], c[1], c[2]);
          for (int s = 0; s < 3; ++s) {
            ++c[p[s]];
            row[s + 1] = id(c[0], c[1], c[2]);
          }
          if (repose::tetVolume(V.row(row[0]).transpose(), V.row(row[1]).transpose(), V.row(row[2]).transpose(),
                                V.row(row[3]).transpose()) < 0)
            std::swap(row[2], row[3]);
          T.row(t++) << row[0], row[1], row[2], row[3];
        }
}
