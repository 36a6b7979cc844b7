#pragma once
/// \file reference_element.hpp
/// The reference-element table (docs/formulation.md §7): per cell type its shape functions and
/// reference gradients, node coordinates, quadrature rules, VTK cell type and node order,
/// and the map from Gmsh's local node order. Everything that depends on the cell type goes
/// through this table; nothing else branches on it.
///
/// Internal local node orders:
/// - quadrilaterals and hexahedra: tensor-product, a = i + (p+1)(j + (p+1)k), reference
///   coordinates ξ = -1 + 2i/p in [-1, 1]^d (p = order);
/// - triangles and tetrahedra: Gmsh's order, vertices first then edge nodes, on the unit
///   simplex (vertices 0, e_1, e_2[, e_3]); tri6 edges 3:(0,1) 4:(1,2) 5:(2,0), tet10 edges
///   4:(0,1) 5:(1,2) 6:(2,0) 7:(3,0) 8:(3,2) 9:(3,1).

#include <Eigen/Core>
#include <string>
#include <vector>

namespace softhd::fe {

/// The element shapes softhd solves on (2D: plane strain).
enum class CellType {
  kQuad4,  ///< bilinear quadrilateral (Q1)
  kQuad9,  ///< biquadratic quadrilateral (Q2)
  kTri3,   ///< linear triangle (P1)
  kTri6,   ///< quadratic triangle (P2)
  kHex8,   ///< trilinear hexahedron (Q1)
  kHex27,  ///< triquadratic hexahedron (Q2)
  kTet4,   ///< linear tetrahedron (P1)
  kTet10,  ///< quadratic tetrahedron (P2)
};

/// One cell type's constant data. Corner (vertex) nodes are the local nodes in
/// `vertex_nodes`; the P1/Q1 cell on them is `linear`.
struct ReferenceElement {
  CellType type = CellType::kHex8;        ///< the cell type of this entry
  int dim = 3;                            ///< 2 or 3
  int order = 1;                          ///< 1 or 2
  int nodes = 8;                          ///< local nodes
  bool simplex = false;                   ///< triangle or tetrahedron
  CellType linear = CellType::kHex8;      ///< the order-1 cell on the same vertices
  CellType quadratic = CellType::kHex27;  ///< the order-2 cell on the same vertices
  /// Local ids of the corner nodes, in the local order of the `linear` cell.
  std::vector<int> vertex_nodes;
  /// Per local node, the local corner ids (positions in vertex_nodes, sorted) of the
  /// smallest sub-entity (vertex, edge, face, cell) the node lies on: two elements share a
  /// node exactly when its global support vertices agree (order elevation uses it).
  std::vector<std::vector<int>> node_support;
  /// nodes by dim reference coordinates of the local nodes.
  Eigen::MatrixXd node_coordinates;
  /// Reference measure: 2^d for [-1,1]^d, 1/2 (triangle), 1/6 (tetrahedron).
  double reference_measure = 8.0;
  /// The quadrature degree used when the scene gives none (chosen by measurement,
  /// docs/formulation.md §7).
  int default_quadrature_degree = 3;
  /// VTK cell type (VTK_HEXAHEDRON 12, VTK_TRIQUADRATIC_HEXAHEDRON 29, VTK_TETRA 10,
  /// VTK_QUADRATIC_TETRA 24, VTK_TRIANGLE 5, VTK_QUADRATIC_TRIANGLE 22, VTK_QUAD 9,
  /// VTK_BIQUADRATIC_QUAD 28).
  int vtk_type = 12;
  /// VTK local node i is internal local node vtk_order[i].
  std::vector<int> vtk_order;
  /// Internal local node a is Gmsh local node gmsh_order[a] (Gmsh 4.x ordering).
  std::vector<int> gmsh_order;
  /// The Gmsh element type code (io/msh.hpp).
  int gmsh_type = 5;
};

/// The name of a cell type: "quad4", "quad9", "tri3", "tri6", "hex8", "hex27", "tet4", "tet10".
std::string to_string(CellType type);
/// The cell type of such a name; throws InvalidArgument listing the names for any other.
CellType parse_cell_type(const std::string& name);

/// The table entry of a cell type.
const ReferenceElement& reference_element(CellType type);

/// The cell type of dimension `dim`, order 1 or 2, simplex or not. Throws InvalidArgument.
CellType cell_type(int dim, int order, bool simplex);

/// Shape values N (nodes) and reference gradients dN (nodes by dim, row-major:
/// dN[a dim + k] = ∂N_a/∂ξ_k) at the reference point xi (dim entries). No allocation.
void shape_functions(CellType type, const double* xi, double* N, double* dN);

/// A quadrature rule exact for polynomials of total degree `degree` (tensor degree for
/// quadrilaterals and hexahedra) on the reference cell, with positive weights summing to
/// reference_measure: nq by dim points and nq weights. Throws InvalidArgument if `degree`
/// is outside 1..the highest degree the table has (documented in the implementation).
void cell_quadrature(CellType type, int degree, Eigen::MatrixXd* points, Eigen::VectorXd* weights);

/// The spurious zero-energy modes of cell_quadrature(type, degree): the dimension of the
/// kernel of Σ_q B_qᵀ B_q (B_q the symmetric gradient of the element's displacements at
/// point q) less the rigid motions (6 in 3D, 3 in 2D), the most over the reference cell, a
/// stretched and a sheared affine image of it. 0 means the linearised stiffness of a free
/// element vanishes only on the rigid motions (docs/formulation.md §7.2).
int spurious_zero_modes(CellType type, int degree);

/// The smallest degree whose rule has no spurious zero-energy modes.
int smallest_stable_degree(CellType type);

/// Throws InvalidArgument naming the degree, the cell type and smallest_stable_degree(type)
/// if cell_quadrature(type, degree) has spurious zero-energy modes (or is out of range).
void check_quadrature_degree(CellType type, int degree);

/// Whether the reference point xi lies in the reference cell, within `tol`.
bool inside_reference_cell(CellType type, const double* xi, double tol);

}  // namespace softhd::fe
