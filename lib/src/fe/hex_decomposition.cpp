#include "hex_decomposition.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <map>
#include <utility>
#include <vector>

#include "softhd/error.hpp"
#include "softhd/fe/reference_element.hpp"

namespace softhd::fe {

namespace {

// One cell type's split: the sub-hexahedra's corners as reference points, each with its
// support (the local corner ids of the smallest vertex, edge, face or cell it lies on, which
// key it among neighbours), and the sub-hexahedra as 8 indices into them.
struct Pattern {
  std::vector<Eigen::Vector3d> xi;
  std::vector<std::vector<int>> support;
  std::vector<std::array<int, 8>> hexes;
};

Eigen::Vector3d corner_xi(const ReferenceElement& r, int c) {
  return r.node_coordinates.row(r.vertex_nodes[c]).transpose();
}

// A hexahedron's k³ sub-cells (k = 1 or 2) on the grid ξ_d = −1 + 2i/k. A grid point lies on
// the corners that agree with it in every axis where |ξ_d| = 1.
Pattern hex_pattern(const ReferenceElement& r, int k) {
  Pattern p;
  const auto id = [k](int i, int j, int l) { return i + (k + 1) * (j + (k + 1) * l); };
  for (int l = 0; l <= k; ++l)
    for (int j = 0; j <= k; ++j)
      for (int i = 0; i <= k; ++i) {
        const Eigen::Vector3d xi(-1.0 + 2.0 * i / k, -1.0 + 2.0 * j / k, -1.0 + 2.0 * l / k);
        std::vector<int> support;
        for (int c = 0; c < 8; ++c) {
          const Eigen::Vector3d x = corner_xi(r, c);
          bool on = true;
          for (int d = 0; d < 3; ++d)
            if (std::abs(xi[d]) == 1.0 && x[d] != xi[d]) on = false;
          if (on) support.push_back(c);
        }
        p.xi.push_back(xi);
        p.support.push_back(support);
      }
  for (int l = 0; l < k; ++l)
    for (int j = 0; j < k; ++j)
      for (int i = 0; i < k; ++i)
        p.hexes.push_back({id(i, j, l), id(i + 1, j, l), id(i + 1, j + 1, l), id(i, j + 1, l),
                           id(i, j, l + 1), id(i + 1, j, l + 1), id(i + 1, j + 1, l + 1),
                           id(i, j + 1, l + 1)});
  return p;
}

// The trilinear map's Jacobian determinant at the centre of a hexahedron with corners x (Gmsh
// order): ∂x/∂s_d = (Σ of the + face's corners − Σ of the − face's)/4.
double centre_determinant(const std::array<Eigen::Vector3d, 8>& x) {
  const Eigen::Vector3d d0 = (x[1] + x[2] + x[5] + x[6] - x[0] - x[3] - x[4] - x[7]) / 4.0;
  const Eigen::Vector3d d1 = (x[2] + x[3] + x[6] + x[7] - x[0] - x[1] - x[4] - x[5]) / 4.0;
  const Eigen::Vector3d d2 = (x[4] + x[5] + x[6] + x[7] - x[0] - x[1] - x[2] - x[3]) / 4.0;
  return (Eigen::Matrix3d() << d0, d1, d2).finished().determinant();
}

// A tetrahedron's 4 hexahedra. The points are the barycentres of the 15 non-empty corner
// subsets (index: the subset's bit mask − 1); vertex v's hexahedron, the others j < k < l,
// has the bottom face (v, vj, vjk, vk) and the top face (vl, vjl, vjkl, vkl), mirrored where
// that would be negatively oriented.
Pattern tet_pattern(const ReferenceElement& r) {
  Pattern p;
  for (int mask = 1; mask < 16; ++mask) {
    Eigen::Vector3d xi = Eigen::Vector3d::Zero();
    std::vector<int> support;
    for (int c = 0; c < 4; ++c)
      if (mask & (1 << c)) {
        xi += corner_xi(r, c);
        support.push_back(c);
      }
    p.xi.push_back(xi / static_cast<double>(support.size()));
    p.support.push_back(support);
  }
  for (int v = 0; v < 4; ++v) {
    std::array<int, 3> o{};
    for (int c = 0, n = 0; c < 4; ++c)
      if (c != v) o[n++] = 1 << c;
    const int b = 1 << v, j = o[0], k = o[1], l = o[2];
    std::array<int, 8> h = {b, b | j, b | j | k, b | k, b | l, b | j | l, b | j | k | l, b | k | l};
    for (int& m : h) --m;
    std::array<Eigen::Vector3d, 8> x;
    for (int a = 0; a < 8; ++a) x[a] = p.xi[h[a]];
    if (centre_determinant(x) < 0) {
      std::swap(h[1], h[3]);
      std::swap(h[5], h[7]);
    }
    p.hexes.push_back(h);
  }
  return p;
}

Pattern pattern_of(CellType type) {
  const ReferenceElement& r = reference_element(type);
  switch (type) {
    case CellType::kHex8:
      return hex_pattern(r, 1);
    case CellType::kHex27:
      return hex_pattern(r, 2);
    case CellType::kTet4:
    case CellType::kTet10:
      return tet_pattern(r);
    default:
      throw InvalidArgument(
          "the cell form of a body needs a 3D mesh (hex8, hex27, tet4, tet10), not " +
          to_string(type));
  }
}

}  // namespace

HexDecomposition hex_decomposition(const Mesh& mesh) {
  const Pattern p = pattern_of(mesh.cell);
  const ReferenceElement& r = reference_element(mesh.cell);
  // Shape values of the element at every pattern point (the same for every element).
  Eigen::MatrixXd shape(p.xi.size(), r.nodes);
  std::vector<double> dN(static_cast<std::size_t>(r.nodes) * 3);
  for (std::size_t q = 0; q < p.xi.size(); ++q) {
    Eigen::RowVectorXd N(r.nodes);
    shape_functions(mesh.cell, p.xi[q].data(), N.data(), dN.data());
    shape.row(static_cast<Eigen::Index>(q)) = N;
  }
  const Eigen::Index E = mesh.num_elements();
  HexDecomposition out;
  out.cells.resize(E * static_cast<Eigen::Index>(p.hexes.size()), 8);
  out.parent.resize(out.cells.rows());
  std::map<std::vector<int>, int> point_of;  // sorted global vertex ids of the support
  std::vector<Eigen::Triplet<double>> entries;
  std::vector<int> local(p.xi.size());
  for (Eigen::Index e = 0; e < E; ++e) {
    for (std::size_t q = 0; q < p.xi.size(); ++q) {
      std::vector<int> key;
      for (int c : p.support[q]) key.push_back(mesh.element_vertices(e, c));
      std::sort(key.begin(), key.end());
      const auto [it, fresh] = point_of.emplace(key, static_cast<int>(point_of.size()));
      local[q] = it->second;
      if (!fresh) continue;
      // x_p = Σ_a N_a(ξ_p) x_a over the element's nodes (exact zeros of the Lagrange basis
      // at other nodes dropped).
      for (int a = 0; a < r.nodes; ++a) {
        const double n = shape(static_cast<Eigen::Index>(q), a);
        if (std::abs(n) > 1e-13) entries.emplace_back(it->second, mesh.elements(e, a), n);
      }
    }
    for (std::size_t h = 0; h < p.hexes.size(); ++h) {
      const Eigen::Index row =
          e * static_cast<Eigen::Index>(p.hexes.size()) + static_cast<Eigen::Index>(h);
      for (int a = 0; a < 8; ++a) out.cells(row, a) = local[p.hexes[h][a]];
      out.parent[row] = static_cast<int>(e);
    }
  }
  out.map.resize(static_cast<Eigen::Index>(point_of.size()), mesh.num_nodes());
  out.map.setFromTriplets(entries.begin(), entries.end());
  return out;
}

}  // namespace softhd::fe
