#include "softhd/fe/geometry.hpp"

#include <Eigen/LU>

#include "softhd/error.hpp"

namespace softhd::fe {

namespace {

// Curved (order-2) elements of a file mesh: det dX/dξ > 0 at the element's vertices too,
// where a fold (a vertex angle of 180° or more) lies outside every quadrature point. dN at
// each vertex: nen by dim. (A box is affine: nothing to check.)
void check_vertices(const Mesh& mesh) {
  const ReferenceElement& ref = reference_element(mesh.cell);
  if (ref.order == 1 || mesh.structured()) return;
  const int nen = ref.nodes, dim = ref.dim, nv = static_cast<int>(ref.vertex_nodes.size());
  std::vector<Eigen::MatrixXd> dN(nv, Eigen::MatrixXd(nen, dim));
  Eigen::VectorXd N(nen);
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> g(nen, dim);
  for (int v = 0; v < nv; ++v) {
    const Eigen::VectorXd xi = ref.node_coordinates.row(ref.vertex_nodes[v]).transpose();
    shape_functions(mesh.cell, xi.data(), N.data(), g.data());
    dN[v] = g;
  }
  Eigen::MatrixXd Xe(nen, dim);
  for (Eigen::Index e = 0; e < mesh.num_elements(); ++e) {
    for (int a = 0; a < nen; ++a) Xe.row(a) = mesh.nodes.row(mesh.elements(e, a));
    for (int v = 0; v < nv; ++v)
      if (!((Xe.transpose() * dN[v]).determinant() > 0.0))  // J = Σ_a X_a ⊗ dN_a/dξ
        throw InvalidArgument("mesh: " + mesh.element_name(e) + " is folded at its local node " +
                              std::to_string(ref.vertex_nodes[v]) +
                              " (det dX/dxi <= 0 there): its curved edges cross");
  }
}

}  // namespace

ReferenceGeometry::ReferenceGeometry(const Mesh& mesh, GradientStorage storage,
                                     int quadrature_degree)
    : dim_(mesh.dim) {
  const ReferenceElement& ref = reference_element(mesh.cell);
  nen_ = mesh.nodes_per_element();
  if (ref.dim != dim_ || ref.nodes != nen_)
    throw InvalidArgument("reference geometry: a " + std::to_string(dim_) + "D mesh with " +
                          std::to_string(nen_) + " nodes per element is not of cell type " +
                          to_string(mesh.cell));
  Eigen::VectorXd wq;
  cell_quadrature(mesh.cell,
                  quadrature_degree > 0 ? quadrature_degree : ref.default_quadrature_degree, &xi_,
                  &wq);
  nq_ = static_cast<int>(wq.size());
  const bool store = storage == GradientStorage::kStored;
  stored_ = store;
  if (!store && nen_ > kMaxNodes)
    throw InvalidArgument("reference geometry: on-demand gradients need at most " +
                          std::to_string(kMaxNodes) + " nodes per element");
  N_.resize(nq_, nen_);
  dN_ref_.resize(nq_);
  Eigen::VectorXd N(nen_);
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> dN(nen_, dim_);
  for (int q = 0; q < nq_; ++q) {
    const Eigen::VectorXd xi = xi_.row(q).transpose();
    shape_functions(mesh.cell, xi.data(), N.data(), dN.data());
    N_.row(q) = N.transpose();
    dN_ref_[q] = dN;
  }
  const Eigen::Index E = mesh.num_elements();
  if (store) dNdX_.resize(dim_, E * nq_ * nen_);
  weights_.resize(E, nq_);
  Eigen::MatrixXd Xe(nen_, dim_);
  for (Eigen::Index e = 0; e < E; ++e) {
    for (int a = 0; a < nen_; ++a) Xe.row(a) = mesh.nodes.row(mesh.elements(e, a));
    for (int q = 0; q < nq_; ++q) {
      // J0 = dX/dxi = Σ_a X_a ⊗ dN_a/dxi;  dN/dX = dN/dxi J0^{-1}
      const Eigen::MatrixXd J0 = Xe.transpose() * dN_ref_[q];
      const double det = J0.determinant();
      if (!(det > 0.0)) {
        throw InvalidArgument("mesh: " + mesh.element_name(e) +
                              " is inverted or degenerate (det dX/dxi <= 0)");
      }
      if (store)
        dNdX_.middleCols((e * nq_ + q) * nen_, nen_) = (dN_ref_[q] * J0.inverse()).transpose();
      weights_(e, q) = wq[q] * det;
    }
  }
  check_vertices(mesh);
}

void ReferenceGeometry::point_gradients(const Mesh& mesh, Eigen::Index e, int q, double* G) const {
  // J0(i, K) = Σ_a X_a,i dN_a/dξ_K (identity beyond dim); dN_a/dX_J = Σ_K dN_a/dξ_K J0⁻¹(K, J)
  const Eigen::MatrixXd& dN = dN_ref_[q];
  Eigen::Matrix3d J0 = Eigen::Matrix3d::Identity();
  for (int i = 0; i < dim_; ++i)
    for (int K = 0; K < dim_; ++K) {
      double s = 0.0;
      for (int a = 0; a < nen_; ++a) s += mesh.nodes(mesh.elements(e, a), i) * dN(a, K);
      J0(i, K) = s;
    }
  const Eigen::Matrix3d Jinv = J0.inverse();
  for (int a = 0; a < nen_; ++a)
    for (int J = 0; J < dim_; ++J) {
      double s = 0.0;
      for (int K = 0; K < dim_; ++K) s += dN(a, K) * Jinv(K, J);
      G[a * dim_ + J] = s;
    }
}

Lumping lumping(CellType type) {
  const ReferenceElement& r = reference_element(type);
  return r.simplex && r.order == 2 ? Lumping::kHRZ : Lumping::kRowSum;
}

void lumped_element_weights(const ReferenceGeometry& g, Lumping lumping, Eigen::Index e,
                            const double* J, double* w, double* dw_dJ) {
  const int nen = g.nodes_per_element(), nq = g.points_per_element();
  const Eigen::MatrixXd& N = g.shape_values();  // nq by nen
  if (lumping == Lumping::kRowSum) {  // w_a = Σ_q N_a c_q, ∂w_a/∂J_q = N_a w_q det J0
    for (int a = 0; a < nen; ++a) w[a] = 0.0;
    for (int q = 0; q < nq; ++q) {
      const double c = g.weights()(e, q) * (J ? J[q] : 1.0);
      for (int a = 0; a < nen; ++a) {
        w[a] += N(q, a) * c;
        if (dw_dJ) dw_dJ[a + nen * q] = N(q, a) * g.weights()(e, q);
      }
    }
    return;
  }
  // HRZ: m_a = Σ_q N_a² c_q, V = Σ_q c_q, S = Σ_a m_a, w_a = V m_a / S;
  // ∂w_a/∂J_q = w_q det J0 (m_a / S + V N_a² / S − V m_a Σ_b N_b² / S²).
  double V = 0.0, S = 0.0;
  for (int a = 0; a < nen; ++a) w[a] = 0.0;  // m_a first
  for (int q = 0; q < nq; ++q) {
    const double c = g.weights()(e, q) * (J ? J[q] : 1.0);
    V += c;
    for (int a = 0; a < nen; ++a) w[a] += N(q, a) * N(q, a) * c;
  }
  for (int a = 0; a < nen; ++a) S += w[a];
  if (dw_dJ) {
    for (int q = 0; q < nq; ++q) {
      const double c0 = g.weights()(e, q);
      const double n2 = N.row(q).squaredNorm();
      for (int a = 0; a < nen; ++a)
        dw_dJ[a + nen * q] = c0 * (w[a] / S + V * N(q, a) * N(q, a) / S - V * w[a] * n2 / (S * S));
    }
  }
  for (int a = 0; a < nen; ++a) w[a] *= V / S;
}

Eigen::VectorXd lumped_volumes(const Mesh& mesh, const ReferenceGeometry& g) {
  Eigen::VectorXd V = Eigen::VectorXd::Zero(mesh.num_nodes());
  const int nen = g.nodes_per_element();
  if (lumping(mesh.cell) == Lumping::kRowSum) {
    // V_i = ∫ N_i dX = Σ_e Σ_q N_i(ξ_q) w_q det J0 (summed as before the table, bitwise)
    for (Eigen::Index e = 0; e < mesh.num_elements(); ++e)
      for (int a = 0; a < nen; ++a)
        V[mesh.elements(e, a)] += g.shape_values().col(a).dot(g.weights().row(e).transpose());
    return V;
  }
  Eigen::VectorXd w(nen);
  for (Eigen::Index e = 0; e < mesh.num_elements(); ++e) {
    lumped_element_weights(g, Lumping::kHRZ, e, nullptr, w.data(), nullptr);
    for (int a = 0; a < nen; ++a) V[mesh.elements(e, a)] += w[a];
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
