#include "softhd/fe/geometry.hpp"

#include <Eigen/LU>

#include "softhd/error.hpp"
#include "softhd/fe/shape.hpp"

namespace softhd::fe {

ReferenceGeometry::ReferenceGeometry(const Mesh& mesh) : dim_(mesh.dim) {
  Eigen::VectorXd wq;
  element_quadrature(dim_, mesh.order, &xi_, &wq);
  nq_ = static_cast<int>(wq.size());
  nen_ = mesh.nodes_per_element();
  N_.resize(nq_, nen_);
  std::vector<Eigen::MatrixXd> dN_ref(nq_);
  for (int q = 0; q < nq_; ++q) {
    Eigen::VectorXd N;
    lagrange_shape(dim_, mesh.order, xi_.row(q).transpose(), &N, &dN_ref[q]);
    N_.row(q) = N.transpose();
  }
  const Eigen::Index E = mesh.num_elements();
  dNdX_.resize(dim_, E * nq_ * nen_);
  weights_.resize(E, nq_);
  Eigen::MatrixXd Xe(nen_, dim_);
  for (Eigen::Index e = 0; e < E; ++e) {
    for (int a = 0; a < nen_; ++a) Xe.row(a) = mesh.nodes.row(mesh.elements(e, a));
    for (int q = 0; q < nq_; ++q) {
      // J0 = dX/dxi = Σ_a X_a ⊗ dN_a/dxi;  dN/dX = dN/dxi J0^{-1}
      const Eigen::MatrixXd J0 = Xe.transpose() * dN_ref[q];
      const double det = J0.determinant();
      if (!(det > 0.0)) {
        throw InvalidArgument("mesh: element " + std::to_string(e) +
                              " is inverted or degenerate (det dX/dxi <= 0)");
      }
      dNdX_.middleCols((e * nq_ + q) * nen_, nen_) = (dN_ref[q] * J0.inverse()).transpose();
      weights_(e, q) = wq[q] * det;
    }
  }
}

Eigen::VectorXd lumped_volumes(const Mesh& mesh, const ReferenceGeometry& g) {
  // V_i = ∫ N_i dX = Σ_e Σ_q N_i(ξ_q) w_q det J0
  Eigen::VectorXd V = Eigen::VectorXd::Zero(mesh.num_nodes());
  for (Eigen::Index e = 0; e < mesh.num_elements(); ++e) {
    for (int a = 0; a < g.nodes_per_element(); ++a) {
      V[mesh.elements(e, a)] += g.shape_values().col(a).dot(g.weights().row(e).transpose());
    }
  }
  return V;
}

Eigen::MatrixXd quadrature_points(const Mesh& mesh, const ReferenceGeometry& g) {
  const int nq = g.points_per_element();
  Eigen::MatrixXd P(mesh.num_elements() * nq, mesh.dim);
  for (Eigen::Index e = 0; e < mesh.num_elements(); ++e) {
    for (int q = 0; q < nq; ++q) {
      Eigen::RowVectorXd x = Eigen::RowVectorXd::Zero(mesh.dim);
      for (int a = 0; a < g.nodes_per_element(); ++a) {
        x += g.shape_values()(q, a) * mesh.nodes.row(mesh.elements(e, a));
      }
      P.row(e * nq + q) = x;
    }
  }
  return P;
}

}  // namespace softhd::fe
