#include "softhd/fe/cloud.hpp"

#include <Eigen/LU>

#include "softhd/error.hpp"

namespace softhd::fe {

PointCloud deformed_cloud(const Assembler& A, const Eigen::VectorXd& u, CloudPoints points,
                          CloudVolumes volumes) {
  const Mesh& mesh = A.mesh();
  const ReferenceGeometry& g = A.geometry();
  const int dim = mesh.dim, nq = g.points_per_element(), nen = mesh.nodes_per_element();
  const Eigen::Index E = mesh.num_elements();
  if (u.size() != A.dofs().num_dofs) throw InvalidArgument("deformed_cloud: u has the wrong size");
  if (points == CloudPoints::kBoundaryNodes)
    return boundary_cloud(mesh, boundary_facets(mesh), u, volumes);
  const Eigen::MatrixXd J =
      volumes == CloudVolumes::kDeformed ? A.jacobians(u) : Eigen::MatrixXd::Ones(E, nq);
  const Eigen::MatrixXd Uv = u.reshaped(dim, mesh.num_nodes()).transpose();  // N by dim
  if (points == CloudPoints::kNodes) {
    Eigen::VectorXd V = Eigen::VectorXd::Zero(mesh.num_nodes());
    if (lumping(mesh.cell) == Lumping::kRowSum) {
      for (Eigen::Index e = 0; e < E; ++e)
        for (int q = 0; q < nq; ++q)  // V_i = Σ_e Σ_q N_i(ξ_q) w_q det J0 (J_q)
          for (int a = 0; a < nen; ++a)
            V[mesh.elements(e, a)] += g.shape_values()(q, a) * g.weights()(e, q) * J(e, q);
    } else {  // HRZ on P2 simplices (geometry.hpp)
      Eigen::VectorXd Je(nq), w(nen);
      for (Eigen::Index e = 0; e < E; ++e) {
        Je = J.row(e).transpose();
        lumped_element_weights(g, Lumping::kHRZ, e, Je.data(), w.data(), nullptr);
        for (int a = 0; a < nen; ++a) V[mesh.elements(e, a)] += w[a];
      }
    }
    return PointCloud(mesh.nodes + Uv, V);
  }
  Eigen::MatrixXd X(E * nq, dim);
  Eigen::VectorXd V(E * nq);
  for (Eigen::Index e = 0; e < E; ++e)
    for (int q = 0; q < nq; ++q) {
      Eigen::RowVectorXd x = Eigen::RowVectorXd::Zero(dim);
      for (int a = 0; a < nen; ++a) {
        const int n = mesh.elements(e, a);
        x += g.shape_values()(q, a) * (mesh.nodes.row(n) + Uv.row(n));
      }
      X.row(e * nq + q) = x;
      V[e * nq + q] = g.weights()(e, q) * J(e, q);
    }
  return PointCloud(X, V);
}

Eigen::VectorXd cloud_pullback(const Assembler& A, const Eigen::VectorXd& u, CloudPoints points,
                               CloudVolumes volumes, const Eigen::MatrixXd& dJ_dx,
                               const Eigen::VectorXd& dJ_dV) {
  const Mesh& mesh = A.mesh();
  const ReferenceGeometry& g = A.geometry();
  const int dim = mesh.dim, nq = g.points_per_element(), nen = mesh.nodes_per_element();
  const Eigen::Index E = mesh.num_elements();
  if (points == CloudPoints::kBoundaryNodes)
    return boundary_cloud_pullback(mesh, boundary_facets(mesh), u, volumes, dJ_dx, dJ_dV);
  const Eigen::Index N = points == CloudPoints::kNodes ? mesh.num_nodes() : E * nq;
  const bool deformed = volumes == CloudVolumes::kDeformed;
  if (dJ_dx.rows() != N || dJ_dx.cols() != dim || (deformed && dJ_dV.size() != N)) {
    throw InvalidArgument("cloud_pullback: dJ_dx must be N by dim and dJ_dV of size N, N = " +
                          std::to_string(N));
  }
  Eigen::VectorXd grad = Eigen::VectorXd::Zero(A.dofs().num_dofs);
  // HRZ nodal volumes (P2 simplices): ∂V_i/∂J_q from lumped_element_weights.
  const bool hrz = deformed && points == CloudPoints::kNodes && lumping(mesh.cell) == Lumping::kHRZ;
  const Eigen::MatrixXd J = hrz ? A.jacobians(u) : Eigen::MatrixXd();
  Eigen::VectorXd Je(nq), w(nen), dw_dJ(hrz ? nen * nq : 0);
  for (Eigen::Index e = 0; e < E; ++e) {
    if (hrz) {
      Je = J.row(e).transpose();
      lumped_element_weights(g, Lumping::kHRZ, e, Je.data(), w.data(), dw_dJ.data());
    }
    for (int q = 0; q < nq; ++q) {
      // cw = Σ_i dJ/dV_i ∂V_i/∂J_q: Σ_i dJ/dV_i N_i(ξ_q) w_q det J0 (row sum), Σ_a dJ/dV_a
      // ∂w_a/∂J_q (HRZ), or dJ/dV_q w_q det J0 (quadrature points).
      double c = 0.0, cw = 0.0;
      if (deformed) {
        if (hrz) {
          for (int a = 0; a < nen; ++a) cw += dJ_dV[mesh.elements(e, a)] * dw_dJ[a + nen * q];
        } else {
          if (points == CloudPoints::kNodes) {
            for (int a = 0; a < nen; ++a) c += dJ_dV[mesh.elements(e, a)] * g.shape_values()(q, a);
          } else {
            c = dJ_dV[e * nq + q];
          }
          cw = c * g.weights()(e, q);
        }
      }
      const Eigen::Matrix3d H =
          deformed ? cofactor(A.deformation_gradient(u, e, q)) : Eigen::Matrix3d::Zero();
      const auto G = g.gradients(e, q);
      for (int a = 0; a < nen; ++a) {
        const Eigen::Index n = mesh.elements(e, a);
        for (int k = 0; k < dim; ++k) {
          double v = 0.0;
          if (deformed)  // ∂J_q/∂u_ak = (H ∇N_a)_k
            for (int L = 0; L < dim; ++L) v += cw * H(k, L) * G(L, a);
          if (points == CloudPoints::kQuadraturePoints)
            v += g.shape_values()(q, a) * dJ_dx(e * nq + q, k);  // ∂x_q/∂u_a = N_a(ξ_q) I
          grad[n * dim + k] += v;
        }
      }
    }
  }
  if (points == CloudPoints::kNodes) {
    for (Eigen::Index n = 0; n < mesh.num_nodes(); ++n)
      for (int k = 0; k < dim; ++k) grad[n * dim + k] += dJ_dx(n, k);  // ∂x_i/∂u_i = I
  }
  return grad;
}

PointCloud boundary_cloud(const Mesh& mesh, const BoundaryFacets& facets, const Eigen::VectorXd& u,
                          CloudVolumes volumes) {
  const TriangleSurface s = boundary_surface(mesh, facets, u);
  const Eigen::VectorXd V =
      lumped_areas(volumes == CloudVolumes::kDeformed
                       ? s
                       : boundary_surface(mesh, facets, Eigen::VectorXd::Zero(u.size())));
  return PointCloud(s.points, V);
}

Eigen::VectorXd boundary_cloud_pullback(const Mesh& mesh, const BoundaryFacets& facets,
                                        const Eigen::VectorXd& u, CloudVolumes volumes,
                                        const Eigen::MatrixXd& dJ_dx,
                                        const Eigen::VectorXd& dJ_dV) {
  const Eigen::Index N = static_cast<Eigen::Index>(facets.nodes.size());
  const bool deformed = volumes == CloudVolumes::kDeformed;
  if (dJ_dx.rows() != N || dJ_dx.cols() != 3 || (deformed && dJ_dV.size() != N)) {
    throw InvalidArgument(
        "boundary_cloud_pullback: dJ_dx must be N by 3 and dJ_dV of size N, N = " +
        std::to_string(N));
  }
  Eigen::MatrixXd g = dJ_dx;  // ∂x_k/∂u_k = I
  if (deformed) g += lumped_areas_pullback(boundary_surface(mesh, facets, u), dJ_dV);
  Eigen::VectorXd grad = Eigen::VectorXd::Zero(mesh.num_nodes() * 3);
  for (Eigen::Index k = 0; k < N; ++k) grad.segment<3>(3 * facets.nodes[k]) = g.row(k).transpose();
  return grad;
}

}  // namespace softhd::fe
