#pragma once
/// \file mesh.hpp
/// Lagrange meshes (docs/formulation.md §3.5, §7): one type for every body. A box is a
/// generator of it (structured Q1/Q2 hexahedra or quadrilaterals, faces named x0..z1); a
/// Gmsh file is another (fe/gmsh_mesh.hpp: tetrahedra, hexahedra, triangles, quadrilaterals
/// of any shape, physical groups as regions and named boundary node sets).

#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "softhd/fe/reference_element.hpp"

namespace softhd::fe {

/// Row-major integer matrix: one element (its node ids) per row.
using Connectivity = Eigen::Matrix<int, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// A Lagrange mesh of one cell type. Element nodes are in the internal local order of
/// reference_element(cell) (tensor-product for quadrilaterals and hexahedra).
struct Mesh {
  int dim = 3;                      ///< 2 or 3
  int order = 1;                    ///< 1 or 2: reference_element(cell).order
  CellType cell = CellType::kHex8;  ///< the cell type of every element
  /// N by dim reference coordinates.
  Eigen::MatrixXd nodes;
  /// E by nodes-per-element node ids.
  Connectivity elements;
  /// E by corners-per-element vertex ids (the element corners, in the local order of the
  /// linear cell, numbered among the mesh vertices 0..num_vertices-1): the support of
  /// P1/Q1 controls.
  Connectivity element_vertices;
  /// Node id of each vertex (num_vertices entries).
  Eigen::VectorXi vertex_nodes;
  /// Named boundary node sets: a box's faces ("x0", "x1", "y0", "y1", and in 3D "z0",
  /// "z1"), a Gmsh file's physical groups one dimension below the body's. Sorted node ids.
  std::map<std::string, std::vector<int>> boundary_nodes;
  /// Region index of each element (E entries, into region_names).
  Eigen::VectorXi element_region;
  /// Region names: {"body"} for a box, a Gmsh file's physical volumes (surfaces in 2D).
  std::vector<std::string> region_names{"body"};
  /// The Gmsh element tag of each element (E entries) for a mesh from a file; empty
  /// otherwise. Messages name elements by it (element_name).
  std::vector<std::int64_t> element_tags;
  ///@{
  /// Structured-box data, used to locate points by arithmetic: lower corner, upper
  /// corner, cells. Empty for unstructured meshes (structured() is false).
  Eigen::VectorXd box_lo, box_hi;
  Eigen::VectorXi cells;
  ///@}

  /// True for a structured box mesh (locate by arithmetic, grid halving possible).
  bool structured() const { return cells.size() == dim; }

  /// The number of nodes.
  Eigen::Index num_nodes() const { return nodes.rows(); }
  /// The number of elements.
  Eigen::Index num_elements() const { return elements.rows(); }
  /// The number of vertices (element corners).
  Eigen::Index num_vertices() const { return vertex_nodes.size(); }
  /// Nodes per element, (p+1)^dim.
  int nodes_per_element() const { return static_cast<int>(elements.cols()); }

  /// "element T" with T the Gmsh tag of element e if the mesh has tags, else its index.
  std::string element_name(Eigen::Index e) const;
  /// Node ids of a named boundary set; throws InvalidArgument naming it and listing the
  /// names the mesh has if unknown.
  const std::vector<int>& face(const std::string& name) const;
  /// Index of a named region; throws InvalidArgument listing the names if unknown.
  int region(const std::string& name) const;
};

/// Counts of a structured box mesh in 64 bits (they can exceed 2^31 before anything is
/// allocated), and an estimate of the memory a state solve on it needs.
struct MeshSize {
  ///@{
  /// Counts of the mesh and of the problem on it.
  std::int64_t nodes = 0, elements = 0, dofs = 0, quadrature_points = 0;
  ///@}
  /// Estimated bytes: mesh, quadrature data, the sparse tangent and its factor (taken as
  /// twice the tangent), and a handful of dof vectors. An estimate, not a bound.
  double bytes = 0.0;
};

/// The MeshSize of a mesh in `dim` dimensions with `nodes` nodes and `elements` cells of
/// `nodes_per_element` nodes (`vertices` of them corners) and `quadrature_points` points
/// each, where `pairs` ordered node pairs (a node with itself included) share a cell: the
/// tangent holds a dim x dim block per pair.
MeshSize mesh_size(int dim, double nodes, double elements, int nodes_per_element, int vertices,
                   int quadrature_points, double pairs);

/// The counts of make_box_mesh(lo, hi, cells, order) without building it. `cells` may
/// hold any values >= 1 (computed in floating point where the products could overflow).
MeshSize box_mesh_size(const Eigen::VectorXd& cells, int order);

/// Default memory limit of check_mesh_size: 8 GiB.
constexpr double kDefaultMemoryLimit = 8.0 * (1u << 30);

/// Throws ResourceError naming `what`, the counts, the estimated size and the limit if
/// the estimate exceeds `memory_limit` bytes, or if nodes or dofs exceed the int range
/// the element connectivity is indexed with.
void check_mesh_size(const MeshSize& size, double memory_limit, const std::string& what);

/// Structured mesh of the box [lo, hi] (lo, hi of size 2 or 3) with `cells` elements per
/// axis and Lagrange order 1 or 2. Throws InvalidArgument on bad sizes and ResourceError
/// if the node or dof count exceeds the int range (nothing is allocated then).
Mesh make_box_mesh(const Eigen::VectorXd& lo, const Eigen::VectorXd& hi,
                   const Eigen::VectorXi& cells, int order);

/// The P1/Q1 mesh on the vertices of `mesh` (the coarse level of p-sequencing,
/// docs/formulation.md §3.7): the same cells with only their corners, node k at vertex k,
/// so elements = element_vertices, the same regions and box data, and every boundary set
/// restricted to its vertices. A mesh of order 1 is returned as it is.
Mesh linear_mesh(const Mesh& mesh);

/// Element containing the reference point X of a structured box mesh and the
/// element's reference coordinates xi in [-1, 1]^dim. Returns -1 if X is outside
/// the box (tolerance 1e-10 relative to the box size). Any mesh: fe/locator.hpp.
int locate(const Mesh& mesh, const Eigen::VectorXd& X, Eigen::VectorXd* xi);

}  // namespace softhd::fe
