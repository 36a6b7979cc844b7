#pragma once
/// \file mesh.hpp
/// Structured Lagrange meshes of a box (docs/formulation.md §3.5): 8-node (Q1) and 27-node (Q2)
/// hexahedra in 3D, 4-node and 9-node quadrilaterals in 2D (plane strain).

#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace softhd::fe {

/// Row-major integer matrix: one element (its node ids) per row.
using Connectivity = Eigen::Matrix<int, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// A Lagrange mesh. Element nodes are numbered in tensor-product order: local node
/// a = i + (p+1) (j + (p+1) k), i, j, k in 0..p, with reference coordinate
/// xi = -1 + 2 i / p along each axis (p = order).
struct Mesh {
  int dim = 3;    ///< 2 or 3
  int order = 1;  ///< 1 (Q1) or 2 (Q2)
  /// N by dim reference coordinates.
  Eigen::MatrixXd nodes;
  /// E by (p+1)^dim node ids.
  Connectivity elements;
  /// E by 2^dim vertex ids (the element corners, in tensor-product order, numbered
  /// among the mesh vertices 0..num_vertices-1): the support of Q1 controls.
  Connectivity element_vertices;
  /// Node id of each vertex (num_vertices entries).
  Eigen::VectorXi vertex_nodes;
  /// Named boundary faces ("x0", "x1", "y0", "y1", and in 3D "z0", "z1"): sorted node ids.
  std::map<std::string, std::vector<int>> boundary_nodes;
  ///@{
  /// Structured-box data, used to locate points: lower corner, upper corner, cells.
  Eigen::VectorXd box_lo, box_hi;
  Eigen::VectorXi cells;
  ///@}

  /// The number of nodes.
  Eigen::Index num_nodes() const { return nodes.rows(); }
  /// The number of elements.
  Eigen::Index num_elements() const { return elements.rows(); }
  /// The number of vertices (element corners).
  Eigen::Index num_vertices() const { return vertex_nodes.size(); }
  /// Nodes per element, (p+1)^dim.
  int nodes_per_element() const { return static_cast<int>(elements.cols()); }

  /// Node ids of a named face; throws InvalidArgument naming the face if unknown.
  const std::vector<int>& face(const std::string& name) const;
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

/// Element containing the reference point X of a structured box mesh and the
/// element's reference coordinates xi in [-1, 1]^dim. Returns -1 if X is outside
/// the box (tolerance 1e-10 relative to the box size).
int locate(const Mesh& mesh, const Eigen::VectorXd& X, Eigen::VectorXd* xi);

}  // namespace softhd::fe
