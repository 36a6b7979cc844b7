#include "softhd/fe/reference_element.hpp"

#include <array>
#include <utility>

#include "softhd/enum_names.hpp"
#include "softhd/error.hpp"

namespace softhd::fe {

namespace {

// ---------------------------------------------------------------------------------------------
// Shape functions.

// 1-D Lagrange basis of order p at equispaced nodes -1 + 2i/p: values and derivatives.
// Q1: (1 ∓ x)/2;  Q2: x(x − 1)/2, 1 − x², x(x + 1)/2.
void lagrange_1d(int p, double x, double* l, double* dl) {
  if (p == 1) {
    l[0] = 0.5 * (1.0 - x);
    l[1] = 0.5 * (1.0 + x);
    dl[0] = -0.5;
    dl[1] = 0.5;
  } else {
    l[0] = 0.5 * x * (x - 1.0);
    l[1] = 1.0 - x * x;
    l[2] = 0.5 * x * (x + 1.0);
    dl[0] = x - 0.5;
    dl[1] = -2.0 * x;
    dl[2] = x + 0.5;
  }
}

// Tensor products N_a(ξ) = Π_d l_{i_d}(ξ_d), a = i + (p+1)(j + (p+1)k). The products are
// formed in the order of the former lagrange_shape (so box results stay bitwise equal).
void tensor_shape(int dim, int p, const double* xi, double* N, double* dN) {
  const int n1 = p + 1;
  double l[3][3], dl[3][3];
  for (int d = 0; d < dim; ++d) lagrange_1d(p, xi[d], l[d], dl[d]);
  const int nen = dim == 2 ? n1 * n1 : n1 * n1 * n1;
  for (int a = 0; a < nen; ++a) {
    const int idx[3] = {a % n1, (a / n1) % n1, a / (n1 * n1)};
    double v = 1.0;
    for (int d = 0; d < dim; ++d) v *= l[d][idx[d]];
    N[a] = v;
    for (int g = 0; g < dim; ++g) {
      double w = 1.0;
      for (int d = 0; d < dim; ++d) w *= (d == g) ? dl[d][idx[d]] : l[d][idx[d]];
      dN[a * dim + g] = w;
    }
  }
}

// Edges of the quadratic simplices, in the internal (Gmsh) order.
constexpr int kTriEdges[3][2] = {{0, 1}, {1, 2}, {2, 0}};
constexpr int kTetEdges[6][2] = {{0, 1}, {1, 2}, {2, 0}, {3, 0}, {3, 2}, {3, 1}};

// Simplices in barycentric form: L_0 = 1 − Σ ξ_k, L_k = ξ_k (∂L_0/∂ξ_k = −1, ∂L_j/∂ξ_k = δ_jk).
// P1: N_i = L_i. P2: vertex N_i = L_i (2 L_i − 1), edge (i, j) N = 4 L_i L_j.
void simplex_shape(int dim, int p, const double* xi, double* N, double* dN) {
  const int nv = dim + 1;
  double L[4], dL[4][3];
  L[0] = 1.0;
  for (int k = 0; k < dim; ++k) {
    L[0] -= xi[k];
    L[k + 1] = xi[k];
    dL[0][k] = -1.0;
    for (int j = 1; j < nv; ++j) dL[j][k] = j == k + 1 ? 1.0 : 0.0;
  }
  if (p == 1) {
    for (int i = 0; i < nv; ++i) {
      N[i] = L[i];
      for (int k = 0; k < dim; ++k) dN[i * dim + k] = dL[i][k];
    }
    return;
  }
  for (int i = 0; i < nv; ++i) {
    N[i] = L[i] * (2.0 * L[i] - 1.0);
    for (int k = 0; k < dim; ++k) dN[i * dim + k] = (4.0 * L[i] - 1.0) * dL[i][k];
  }
  const int ne = dim == 2 ? 3 : 6;
  for (int e = 0; e < ne; ++e) {
    const int i = dim == 2 ? kTriEdges[e][0] : kTetEdges[e][0];
    const int j = dim == 2 ? kTriEdges[e][1] : kTetEdges[e][1];
    const int a = nv + e;
    N[a] = 4.0 * L[i] * L[j];
    for (int k = 0; k < dim; ++k) dN[a * dim + k] = 4.0 * (dL[i][k] * L[j] + L[i] * dL[j][k]);
  }
}

// ---------------------------------------------------------------------------------------------
// The table.

// Quadrilaterals and hexahedra: tensor-product nodes ξ = −1 + 2i/p; corners are the nodes with
// every index in {0, p}; a node's support is the corners agreeing with it on every axis where
// its index is 0 or p.
void fill_tensor(ReferenceElement* r) {
  const int dim = r->dim, p = r->order, n1 = p + 1;
  r->node_coordinates.resize(r->nodes, dim);
  std::vector<std::array<int, 3>> corner_idx;
  for (int a = 0; a < r->nodes; ++a) {
    const int idx[3] = {a % n1, (a / n1) % n1, a / (n1 * n1)};
    bool corner = true;
    for (int d = 0; d < dim; ++d) {
      r->node_coordinates(a, d) = -1.0 + 2.0 * idx[d] / p;
      corner = corner && (idx[d] == 0 || idx[d] == p);
    }
    if (corner) {
      r->vertex_nodes.push_back(a);
      corner_idx.push_back({idx[0], idx[1], dim == 3 ? idx[2] : 0});
    }
  }
  for (int a = 0; a < r->nodes; ++a) {
    const int idx[3] = {a % n1, (a / n1) % n1, a / (n1 * n1)};
    std::vector<int> support;
    for (int c = 0; c < static_cast<int>(corner_idx.size()); ++c) {
      bool match = true;
      for (int d = 0; d < dim; ++d)
        if ((idx[d] == 0 || idx[d] == p) && corner_idx[c][d] != idx[d]) match = false;
      if (match) support.push_back(c);
    }
    r->node_support.push_back(support);
  }
  r->reference_measure = dim == 2 ? 4.0 : 8.0;
  // Today's full Gauss rule, (p+1)^d points: degree 2p + 1 per axis.
  r->default_quadrature_degree = 2 * p + 1;
}

// Triangles and tetrahedra: vertices 0, e_1, e_2[, e_3], then the edge midpoints.
void fill_simplex(ReferenceElement* r) {
  const int dim = r->dim, nv = dim + 1;
  r->node_coordinates = Eigen::MatrixXd::Zero(r->nodes, dim);
  for (int i = 0; i < nv; ++i) {
    if (i > 0) r->node_coordinates(i, i - 1) = 1.0;
    r->vertex_nodes.push_back(i);
    r->node_support.push_back({i});
  }
  for (int e = 0; e + nv < r->nodes; ++e) {
    const int i = dim == 2 ? kTriEdges[e][0] : kTetEdges[e][0];
    const int j = dim == 2 ? kTriEdges[e][1] : kTetEdges[e][1];
    r->node_coordinates.row(nv + e) =
        0.5 * (r->node_coordinates.row(i) + r->node_coordinates.row(j));
    r->node_support.push_back({std::min(i, j), std::max(i, j)});
  }
  r->reference_measure = dim == 2 ? 0.5 : 1.0 / 6.0;
  // Measured (docs/formulation.md §7.2, studies/bench_quadrature.py): P1 states are the same at
  // every degree (F constant), 2 keeps the mass matrix and ∫ m² exact; P2 at 4 is within
  // 1e-10 of degree 8 (degree 2: 5e-6 on tetrahedra, and twice the Newton iterations).
  r->default_quadrature_degree = r->order == 1 ? 2 : 4;
}

ReferenceElement make(CellType type, int dim, int order, bool simplex, int nodes, int vtk_type,
                      int gmsh_type, std::vector<int> vtk_order, std::vector<int> gmsh_order) {
  ReferenceElement r;
  r.type = type;
  r.dim = dim;
  r.order = order;
  r.nodes = nodes;
  r.simplex = simplex;
  r.linear = cell_type(dim, 1, simplex);
  r.quadratic = cell_type(dim, 2, simplex);
  if (simplex)
    fill_simplex(&r);
  else
    fill_tensor(&r);
  r.vtk_type = vtk_type;
  r.vtk_order = std::move(vtk_order);
  r.gmsh_type = gmsh_type;
  r.gmsh_order = std::move(gmsh_order);
  return r;
}

// VTK and Gmsh orders (tests/fe/test_reference_element.cpp checks each against the other
// program's own node coordinates). vtk_order[i]: the internal node at VTK node i;
// gmsh_order[a]: the Gmsh node at internal node a.
//  - VTK_QUAD 9 / VTK_HEXAHEDRON 12: corners counter-clockwise, bottom then top.
//  - VTK_BIQUADRATIC_QUAD 28: corners, edges (0,1) (1,2) (2,3) (3,0), centre.
//  - VTK_TRIQUADRATIC_HEXAHEDRON 29: corners; edges (0,1) (1,2) (3,2) (0,3) of the bottom,
//    the same on top, then the verticals (0,4) (1,5) (2,6) (3,7); faces x−, x+, y−, y+, z−,
//    z+ (vtkTriQuadraticHexahedron's parametric coordinates, not its header's face list);
//    centre.
//  - VTK_QUADRATIC_TETRA 24: edges (0,1) (1,2) (2,0) (0,3) (1,3) (2,3) (internal 8 and 9
//    swap); VTK_QUADRATIC_TRIANGLE 22 and VTK_TRIANGLE 5, VTK_TETRA 10: the internal order.
//  - Gmsh quadrangles and hexahedra: corners counter-clockwise (bottom, top), then edges
//    (0,1) (0,3) (0,4) (1,2) (1,5) (2,3) (2,6) (3,7) (4,5) (4,7) (5,6) (6,7) of the hexahedron
//    ((0,1) (1,2) (2,3) (3,0) of the quadrangle), faces z−, y−, x−, x+, y+, z+, centre.
std::array<ReferenceElement, 8> make_table() {
  using C = CellType;
  return {
      make(C::kQuad4, 2, 1, false, 4, 9, 3, {0, 1, 3, 2}, {0, 1, 3, 2}),
      make(C::kQuad9, 2, 2, false, 9, 28, 10, {0, 2, 8, 6, 1, 5, 7, 3, 4},
           {0, 4, 1, 7, 8, 5, 3, 6, 2}),
      make(C::kTri3, 2, 1, true, 3, 5, 2, {0, 1, 2}, {0, 1, 2}),
      make(C::kTri6, 2, 2, true, 6, 22, 9, {0, 1, 2, 3, 4, 5}, {0, 1, 2, 3, 4, 5}),
      make(C::kHex8, 3, 1, false, 8, 12, 5, {0, 1, 3, 2, 4, 5, 7, 6}, {0, 1, 3, 2, 4, 5, 7, 6}),
      make(C::kHex27, 3, 2, false, 27, 29, 12,
           {0,  2,  8, 6,  18, 20, 26, 24, 1,  5,  7, 3,  19, 23,
            25, 21, 9, 11, 17, 15, 12, 14, 10, 16, 4, 22, 13},
           {0,  8,  1,  9,  20, 11, 3, 13, 2,  10, 21, 12, 22, 26,
            23, 15, 24, 14, 4,  16, 5, 17, 25, 18, 7,  19, 6}),
      make(C::kTet4, 3, 1, true, 4, 10, 4, {0, 1, 2, 3}, {0, 1, 2, 3}),
      make(C::kTet10, 3, 2, true, 10, 24, 11, {0, 1, 2, 3, 4, 5, 6, 7, 9, 8},
           {0, 1, 2, 3, 4, 5, 6, 7, 8, 9}),
  };
}

constexpr auto kCellTypeNames = enum_sequence<CellType::kTet10>(
    {"quad4", "quad9", "tri3", "tri6", "hex8", "hex27", "tet4", "tet10"});

}  // namespace

std::string to_string(CellType type) { return enum_name(kCellTypeNames, type); }

CellType parse_cell_type(const std::string& name) {
  return enum_from_name(kCellTypeNames, name, "cell type");
}

CellType cell_type(int dim, int order, bool simplex) {
  if ((dim != 2 && dim != 3) || (order != 1 && order != 2))
    throw InvalidArgument("cell type: need dimension 2 or 3 and order 1 or 2, got dimension " +
                          std::to_string(dim) + " and order " + std::to_string(order));
  if (dim == 2) {
    if (simplex) return order == 1 ? CellType::kTri3 : CellType::kTri6;
    return order == 1 ? CellType::kQuad4 : CellType::kQuad9;
  }
  if (simplex) return order == 1 ? CellType::kTet4 : CellType::kTet10;
  return order == 1 ? CellType::kHex8 : CellType::kHex27;
}

const ReferenceElement& reference_element(CellType type) {
  static const std::array<ReferenceElement, 8> table = make_table();
  return table[static_cast<int>(type)];
}

void shape_functions(CellType type, const double* xi, double* N, double* dN) {
  switch (type) {
    case CellType::kQuad4:
      return tensor_shape(2, 1, xi, N, dN);
    case CellType::kQuad9:
      return tensor_shape(2, 2, xi, N, dN);
    case CellType::kHex8:
      return tensor_shape(3, 1, xi, N, dN);
    case CellType::kHex27:
      return tensor_shape(3, 2, xi, N, dN);
    case CellType::kTri3:
      return simplex_shape(2, 1, xi, N, dN);
    case CellType::kTri6:
      return simplex_shape(2, 2, xi, N, dN);
    case CellType::kTet4:
      return simplex_shape(3, 1, xi, N, dN);
    case CellType::kTet10:
      return simplex_shape(3, 2, xi, N, dN);
  }
}

bool inside_reference_cell(CellType type, const double* xi, double tol) {
  const ReferenceElement& r = reference_element(type);
  if (!r.simplex) {  // [-1, 1]^d
    for (int k = 0; k < r.dim; ++k)
      if (!(xi[k] >= -1.0 - tol && xi[k] <= 1.0 + tol)) return false;
    return true;
  }
  double s = 0.0;  // ξ_k >= 0, Σ ξ_k <= 1
  for (int k = 0; k < r.dim; ++k) {
    if (!(xi[k] >= -tol)) return false;
    s += xi[k];
  }
  return s <= 1.0 + tol;
}

}  // namespace softhd::fe
