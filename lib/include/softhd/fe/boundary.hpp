#pragma once
/// \file boundary.hpp
/// The boundary surface of a 3D mesh (docs/formulation.md §8.6): its facets — the element faces
/// that belong to exactly one element — cut into flat triangles over the boundary nodes, and
/// their lumped areas, the volumes of the boundary moving cloud (fe/cloud.hpp).
///
/// Each facet is cut through its nodes: a P1 triangle stays one triangle, a P2 triangle gives
/// four (the corner triangles and the midside one), a Q1 quadrilateral two (the diagonal from
/// its first corner), a Q2 quadrilateral eight (each quarter cut by its diagonal through the
/// centre node). Orientation: outward, taken from the reference cell (det dX/dξ > 0 holds,
/// fe/geometry.hpp).

#include <Eigen/Core>
#include <vector>

#include "softhd/fe/mesh.hpp"
#include "softhd/triangle_surface.hpp"

namespace softhd::fe {

/// The boundary's topology, built once per mesh: surface point k is mesh node nodes[k].
struct BoundaryFacets {
  std::vector<int> nodes;                           ///< boundary node ids, ascending
  Eigen::Matrix<int, Eigen::Dynamic, 3> triangles;  ///< T by 3 surface point ids, outward
};

/// The boundary of `mesh` (3D; InvalidArgument for a 2D mesh).
BoundaryFacets boundary_facets(const Mesh& mesh);

/// The boundary in the configuration x = X + u (u: mesh.num_nodes() * 3 entries, node-major).
TriangleSurface boundary_surface(const Mesh& mesh, const BoundaryFacets& facets,
                                 const Eigen::VectorXd& u);
/// As above, building the facets first.
TriangleSurface boundary_surface(const Mesh& mesh, const Eigen::VectorXd& u);

/// The lumped areas of the surface's points: V_k = Σ_{t ∋ k} |T_t| / 3, |T| = ½|(b−a)×(c−a)|
/// (exactly ∫ N_k dA for flat P1 facets; for the other facets the sub-triangle lumping, whose
/// weights are positive where ∫ N_k dA of a P2 corner is zero).
Eigen::VectorXd lumped_areas(const TriangleSurface& surface);

/// Σ_k w_k ∂V_k/∂x_j for every surface point j (N by 3), V_k = lumped_areas:
/// ∂|T|/∂a = ½ (b − c) × n̂ for T = (a, b, c) with unit normal n̂, cyclically.
Eigen::MatrixXd lumped_areas_pullback(const TriangleSurface& surface, const Eigen::VectorXd& w);

}  // namespace softhd::fe
