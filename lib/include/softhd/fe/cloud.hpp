#pragma once
/// \file cloud.hpp
/// The moving point cloud of the deformed body (docs/formulation.md §1.2, §4.3) and the chain rule
/// back to the displacement: the particles are the mesh nodes (x_i = X_i + u_i), the quadrature
/// points (x_q = Σ_a N_a(X_q) x_a) or the boundary nodes (3D, §8.6); the volumes are the reference
/// ones (V_i = ∫ N_i dX, or w_q det J0) or the deformed ones (V_i = ∫ N_i J dX, or w_q det J0 J_q);
/// for boundary nodes they are the lumped facet areas (fe/boundary.hpp) at u = 0 or at u.

#include <Eigen/Core>

#include "softhd/fe/assembly.hpp"
#include "softhd/fe/boundary.hpp"
#include "softhd/point_cloud.hpp"

namespace softhd::fe {

/// The particles of the moving cloud: mesh nodes, quadrature points, or the boundary nodes
/// (BoundaryFacets::nodes, in that order; 3D meshes only) with their facet areas. For the
/// boundary, deformed_cloud and cloud_pullback find the facets at every call; a caller that
/// evaluates often keeps them and calls boundary_cloud and boundary_cloud_pullback.
enum class CloudPoints { kNodes, kQuadraturePoints, kBoundaryNodes };
/// The particles' volumes: reference ones, or deformed ones (times J).
enum class CloudVolumes { kReference, kDeformed };

/// The deformed cloud for displacement u.
PointCloud deformed_cloud(const Assembler& assembler, const Eigen::VectorXd& u, CloudPoints points,
                          CloudVolumes volumes);

/// g = ∂J/∂u (num_dofs entries) from dJ/dx (N by dim) and dJ/dV (N entries; ignored for
/// reference volumes) of the cloud deformed_cloud(assembler, u, points, volumes):
///   g_a = Σ_i (∂x_i/∂u_a)ᵀ dJ/dx_i + Σ_i dJ/dV_i ∂V_i/∂u_a,  ∂V_i/∂u_a = ∫ N_i H ∇N_a dX
/// (∂J/∂F = H = cof F). Entries of fixed dofs are included; solve_adjoint ignores them.
Eigen::VectorXd cloud_pullback(const Assembler& assembler, const Eigen::VectorXd& u,
                               CloudPoints points, CloudVolumes volumes,
                               const Eigen::MatrixXd& dJ_dx, const Eigen::VectorXd& dJ_dV);

/// The boundary cloud of `facets` (boundary_facets(mesh)) for displacement u: the boundary
/// nodes x_k = X_k + u_k with the lumped areas V_k = Σ_{t ∋ k} |T_t|/3 of the configuration u
/// (kDeformed) or of the reference one (kReference).
PointCloud boundary_cloud(const Mesh& mesh, const BoundaryFacets& facets, const Eigen::VectorXd& u,
                          CloudVolumes volumes);

/// ∂J/∂u (mesh.num_nodes() * 3 entries) of J(boundary_cloud(mesh, facets, u, volumes)) from
/// dJ/dx (boundary nodes by 3) and dJ/dV (boundary nodes; ignored for reference areas):
///   g_k = dJ/dx_k + Σ_t (Σ_{j ∈ t} dJ/dV_j / 3) ∂|T_t|/∂x_k   (lumped_areas_pullback).
Eigen::VectorXd boundary_cloud_pullback(const Mesh& mesh, const BoundaryFacets& facets,
                                        const Eigen::VectorXd& u, CloudVolumes volumes,
                                        const Eigen::MatrixXd& dJ_dx, const Eigen::VectorXd& dJ_dV);

}  // namespace softhd::fe
