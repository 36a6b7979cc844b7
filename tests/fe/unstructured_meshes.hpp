#pragma once
// Unstructured test meshes built in code (no file I/O): a box split into Kuhn tetrahedra
// (P1 or P2), and any mesh moved by a smooth non-affine map (curved P2/Q2 elements).

#include <Eigen/Core>
#include <Eigen/LU>
#include <array>
#include <cmath>
#include <map>
#include <utility>
#include <vector>

#include "softhd/fe/mesh.hpp"

namespace fe_test {

// [0, len] with n cells per axis, each cube split into the 6 tetrahedra around its diagonal
// (0,0,0)-(1,1,1) (Kuhn: conforming across cube faces); order 2 adds the edge midpoints.
// Unstructured: no box data, so locating goes through the tree.
inline softhd::fe::Mesh tet_box(int order, const std::array<int, 3>& n,
                                const std::array<double, 3>& len) {
  using softhd::fe::CellType;
  softhd::fe::Mesh m;
  m.dim = 3;
  m.order = order;
  m.cell = order == 1 ? CellType::kTet4 : CellType::kTet10;
  const int nx = n[0] + 1, ny = n[1] + 1, nz = n[2] + 1, nv = nx * ny * nz;
  std::vector<Eigen::Vector3d> X(nv);
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        X[i + nx * (j + ny * k)] =
            Eigen::Vector3d(len[0] * i / n[0], len[1] * j / n[1], len[2] * k / n[2]);
  std::vector<std::array<int, 4>> tets;
  const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i)
        for (const auto& p : perms) {
          std::array<int, 3> c = {i, j, k};
          std::array<int, 4> t;
          t[0] = c[0] + nx * (c[1] + ny * c[2]);
          for (int s = 0; s < 3; ++s) {
            ++c[p[s]];
            t[s + 1] = c[0] + nx * (c[1] + ny * c[2]);
          }
          const Eigen::Matrix3d D =
              (Eigen::Matrix3d() << X[t[1]] - X[t[0]], X[t[2]] - X[t[0]], X[t[3]] - X[t[0]])
                  .finished();
          if (D.determinant() < 0) std::swap(t[1], t[2]);
          tets.push_back(t);
        }
  const int E = static_cast<int>(tets.size());
  const int edges[6][2] = {{0, 1}, {1, 2}, {2, 0}, {3, 0}, {3, 2}, {3, 1}};  // internal order
  std::map<std::pair<int, int>, int> mid;
  std::vector<Eigen::Vector3d> nodes = X;
  m.elements.resize(E, order == 1 ? 4 : 10);
  m.element_vertices.resize(E, 4);
  for (int e = 0; e < E; ++e) {
    for (int a = 0; a < 4; ++a) m.elements(e, a) = m.element_vertices(e, a) = tets[e][a];
    if (order == 1) continue;
    for (int s = 0; s < 6; ++s) {
      const int a = tets[e][edges[s][0]], b = tets[e][edges[s][1]];
      const auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it == mid.end()) {
        it = mid.emplace(key, static_cast<int>(nodes.size())).first;
        nodes.push_back(0.5 * (X[a] + X[b]));
      }
      m.elements(e, 4 + s) = it->second;
    }
  }
  m.nodes.resize(static_cast<Eigen::Index>(nodes.size()), 3);
  for (size_t i = 0; i < nodes.size(); ++i)
    m.nodes.row(static_cast<Eigen::Index>(i)) = nodes[i].transpose();
  m.vertex_nodes = Eigen::VectorXi::LinSpaced(nv, 0, nv - 1);
  m.element_region = Eigen::VectorXi::Zero(E);
  return m;
}

// X -> X + a (sin(X_1 + 0.3 X_2), sin(X_2 + 0.5 X_0), sin(X_0 + 0.7 X_1)): smooth and, for
// small a, orientation preserving; applied to every node, so P2/Q2 edges become curved.
// Drops the box data (the mesh is no longer a box).
inline void warp(softhd::fe::Mesh* m, double a) {
  for (Eigen::Index i = 0; i < m->num_nodes(); ++i) {
    const Eigen::RowVectorXd X = m->nodes.row(i);
    const double y = X.size() > 2 ? X[2] : 0.0;
    m->nodes(i, 0) += a * std::sin(X[1] + 0.3 * y);
    m->nodes(i, 1) += a * std::sin(y + 0.5 * X[0]);
    if (X.size() > 2) m->nodes(i, 2) += a * std::sin(X[0] + 0.7 * X[1]);
  }
  m->cells.resize(0);
  m->box_lo.resize(0);
  m->box_hi.resize(0);
}

}  // namespace fe_test
