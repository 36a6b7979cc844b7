#pragma once
/// \file interpolation.hpp
/// Finite-element interpolation at arbitrary reference points (docs/formulation.md §7): locate
/// each point (fe/locator.hpp), then evaluate the element's shape functions,
///     f(X) = Σ_a N_a(ξ) f_a   in the element containing X, X = Σ_a X_a N_a(ξ).
/// The one place that does it: probes, targets with a known map, grid sequencing and the
/// control fields all go through here. Meshes on the same cells (p-sequencing) transfer
/// element by element instead (transfer_nodal).

#include <Eigen/Core>
#include <vector>

#include "softhd/fe/locator.hpp"
#include "softhd/fe/mesh.hpp"

namespace softhd::fe {

/// The values (P by c) at `points` (P by dim) of a nodal field (num_nodes by c) in the mesh's
/// shape functions. Points outside the mesh get zero rows and their indices (ascending) in
/// *outside; with outside null they throw InvalidArgument naming the first such point.
Eigen::MatrixXd interpolate_nodal(const Mesh& mesh, const PointLocator& locator,
                                  const Eigen::MatrixXd& nodal_field, const Eigen::MatrixXd& points,
                                  std::vector<int>* outside);

/// The same for a vertex field (num_vertices by c) in the P1/Q1 shape functions of the
/// linear cell on the element corners (mesh.element_vertices).
Eigen::MatrixXd interpolate_vertex(const Mesh& mesh, const PointLocator& locator,
                                   const Eigen::MatrixXd& vertex_field,
                                   const Eigen::MatrixXd& points, std::vector<int>* outside);

/// True if `a` and `b` are the same cells on the same vertices, whatever their orders: the
/// same element count, cell family, element corners (element_vertices) and vertex
/// positions. P1 on the vertices of a P2 mesh (linear_mesh) is such a pair.
bool same_cells(const Mesh& a, const Mesh& b);

/// A nodal field of `from` (num_nodes by c) at the nodes of `to`, two meshes on the same
/// cells (same_cells; throws InvalidArgument otherwise), element by element through the
/// reference coordinates: node a of element e of `to` gets f(ξ_a) = Σ_b N_b(ξ_a) f_b over
/// the nodes b of e in `from`. No point search: exact on curved (isoparametric) cells, where
/// a node of the curved mesh may lie outside the straight-sided one.
Eigen::MatrixXd transfer_nodal(const Mesh& from, const Eigen::MatrixXd& nodal_field,
                               const Mesh& to);

/// The element containing each point (P entries, -1 outside).
Eigen::VectorXi locate_points(const PointLocator& locator, const Eigen::MatrixXd& points);

}  // namespace softhd::fe
