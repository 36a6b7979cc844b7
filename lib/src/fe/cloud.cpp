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
  const Eigen::MatrixXd J =
      volumes == CloudVolumes::kDeformed ? A.jacobians(u) : Eigen::MatrixXd::Ones(E, nq);
  const Eigen::MatrixXd Uv = u.reshaped(dim, mesh.num_nodes()).transpose();  // N by dim
  if (points == CloudPoints::kNodes) {
    Eigen::VectorXd V = Eigen::VectorXd::Zero(mesh.num_nodes());
    for (Eigen::Index e = 0; e < E; ++e)
      for (int q = 0; q < nq; ++q)  // V_i = Σ_e Σ_q N_i(ξ_q) w_q det J0 (J_q)
        for (int a = 0; a < nen; ++a)
          V[mesh.elements(e, a)] += g.shape_values()(q, a) * g.weights()(e, q) * J(e, q);
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
  const Eigen::Index N = points == CloudPoints::kNodes ? mesh.num_nodes() : E * nq;
  const bool deformed = volumes == CloudVolumes::kDeformed;
  if (dJ_dx.rows() != N || dJ_dx.cols() != dim || (deformed && dJ_dV.size() != N)) {
    throw InvalidArgument("cloud_pullback: dJ_dx must be N by dim and dJ_dV of size N, N = " +
                          std::to_string(N));
  }
  Eigen::VectorXd grad = Eigen::VectorXd::Zero(A.dofs().num_dofs);
  for (Eigen::Index e = 0; e < E; ++e)
    for (int q = 0; q < nq; ++q) {
      // Weight of ∂V/∂u at this point: Σ_i dJ/dV_i N_i(ξ_q) (nodes) or dJ/dV_q.
      double c = 0.0;
      if (deformed) {
        if (points == CloudPoints::kNodes) {
          for (int a = 0; a < nen; ++a) c += dJ_dV[mesh.elements(e, a)] * g.shape_values()(q, a);
        } else {
          c = dJ_dV[e * nq + q];
        }
      }
      const Eigen::Matrix3d H =
          deformed ? cofactor(A.deformation_gradient(u, e, q)) : Eigen::Matrix3d::Zero();
      const auto G = g.gradients(e, q);
      for (int a = 0; a < nen; ++a) {
        const Eigen::Index n = mesh.elements(e, a);
        for (int k = 0; k < dim; ++k) {
          double v = 0.0;
          if (deformed)  // ∂(w J)/∂u_ak = w (H ∇N_a)_k
            for (int L = 0; L < dim; ++L) v += c * g.weights()(e, q) * H(k, L) * G(L, a);
          if (points == CloudPoints::kQuadraturePoints)
            v += g.shape_values()(q, a) * dJ_dx(e * nq + q, k);  // ∂x_q/∂u_a = N_a(ξ_q) I
          grad[n * dim + k] += v;
        }
      }
    }
  if (points == CloudPoints::kNodes) {
    for (Eigen::Index n = 0; n < mesh.num_nodes(); ++n)
      for (int k = 0; k < dim; ++k) grad[n * dim + k] += dJ_dx(n, k);  // ∂x_i/∂u_i = I
  }
  return grad;
}

}  // namespace softhd::fe
