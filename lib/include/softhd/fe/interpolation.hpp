#pragma once
/// \file interpolation.hpp
/// Finite-element interpolation at arbitrary reference points (docs/formulation.md §7): locate
/// each point (fe/locator.hpp), then evaluate the element's shape functions,
///     f(X) = Σ_a N_a(ξ) f_a   in the element containing X, X = Σ_a X_a N_a(ξ).
/// The one place that does it: probes, targets with a known map, grid sequencing and the
/// control fields all go through here.

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

/// The element containing each point (P entries, -1 outside).
Eigen::VectorXi locate_points(const PointLocator& locator, const Eigen::MatrixXd& points);

}  // namespace softhd::fe
