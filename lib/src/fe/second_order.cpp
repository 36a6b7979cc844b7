#include "softhd/fe/second_order.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <string>
#include <vector>

#include "softhd/error.hpp"
#include "softhd/parallel.hpp"

namespace softhd::fe {

namespace {

// Elements per pass of an assembled vector: their element vectors are buffered, then added
// serially in element order (bounded memory, deterministic for any thread count).
constexpr Eigen::Index kPassElements = 4096;

// Per-thread scratch of the element kernels.
struct Scratch {
  Eigen::MatrixXd Gq;          // dim by nen: ∇N_a at X_q when the geometry does not store it
  Eigen::MatrixXd Z1, Z2, Z3;  // dim by nen: element values of up to three dof fields
  Scratch(int dim, int nen) : Gq(dim, nen), Z1(dim, nen), Z2(dim, nen), Z3(dim, nen) {}
};

void check_dof_vector(const Assembler& A, const Eigen::VectorXd& x, const char* name) {
  if (x.size() != A.dofs().num_dofs)
    throw InvalidArgument(std::string("second-order state terms: ") + name + " must have " +
                          std::to_string(A.dofs().num_dofs) + " entries, got " +
                          std::to_string(x.size()));
}

// Z(i, a) = x[node(e, a) dim + i]: the element's values of a dof field.
void gather(const Assembler& A, const Eigen::VectorXd& x, Eigen::Index e, Eigen::MatrixXd* Z) {
  const int dim = A.mesh().dim;
  for (int a = 0; a < A.mesh().nodes_per_element(); ++a)
    for (int i = 0; i < dim; ++i) (*Z)(i, a) = x[A.mesh().elements(e, a) * dim + i];
}

// ∇N_a at X_q (dim by nen), stored or recomputed into s.Gq.
Eigen::Ref<const Eigen::MatrixXd> point_gradients(const Assembler& A, Eigen::Index e, int q,
                                                  Scratch& s) {
  if (A.geometry().stores_gradients()) return A.geometry().gradients(e, q);
  A.geometry().point_gradients(A.mesh(), e, q, s.Gq.data());
  return s.Gq;
}

// ∇z = Σ_a z_a ⊗ ∇N_a as a 3 by 3 (zero third row and column in 2D).
Eigen::Matrix3d field_gradient(const Eigen::MatrixXd& Z,
                               const Eigen::Ref<const Eigen::MatrixXd>& G) {
  const int dim = static_cast<int>(Z.rows());
  Eigen::Matrix3d D = Eigen::Matrix3d::Zero();
  D.topLeftCorner(dim, dim).noalias() = Z * G.transpose();
  return D;
}

// Σ_e r_e: kernel(e, scratch, re) writes element e's vector re (nd, local dof a dim + i);
// elements in parallel passes, added in element order; fixed dofs left zero.
template <class Kernel>
Eigen::VectorXd assemble_vector(const Assembler& A, Kernel&& kernel) {
  const Mesh& mesh = A.mesh();
  const int dim = mesh.dim, nen = mesh.nodes_per_element(), nd = nen * dim;
  const Eigen::Index E = mesh.num_elements();
  const Eigen::Index chunk = std::max<Eigen::Index>(1, std::min(kPassElements, E));
  std::vector<double> buffer(static_cast<size_t>(chunk) * nd);
  std::vector<Scratch> scratch(softhd::max_threads(), Scratch(dim, nen));
  Eigen::VectorXd out = Eigen::VectorXd::Zero(A.dofs().num_dofs);
  for (Eigen::Index start = 0; start < E; start += chunk) {
    const Eigen::Index n = std::min(chunk, E - start);
#pragma omp parallel for schedule(dynamic, 8) \
    num_threads(static_cast <int>(scratch.size())) if (n >= 8)
    for (Eigen::Index i = 0; i < n; ++i)
      kernel(start + i, scratch[thread_id()], &buffer[static_cast<size_t>(i) * nd]);
    for (Eigen::Index i = 0; i < n; ++i)  // serial, in element order
      for (int a = 0; a < nen; ++a)
        for (int k = 0; k < dim; ++k) {
          const Eigen::Index dof = mesh.elements(start + i, a) * dim + k;
          if (A.dofs().free_index[dof] >= 0) out[dof] += buffer[i * nd + a * dim + k];
        }
  }
  return out;
}

// δ ↦ −∫ m_v (T a₀)·(∇δ a₀) dX with T = I + ∇z (with_identity: F of the displacement z)
// or T = ∇z: r_e(i, a) = −Σ_q w_q m_v (T a₀)_i (∇N_a · a₀).
Eigen::VectorXd fiber_load(const Assembler& A, const Eigen::VectorXd& z, bool with_identity,
                           const Eigen::MatrixXd& m_v) {
  const int dim = A.mesh().dim, nq = A.geometry().points_per_element();
  return assemble_vector(A, [&](Eigen::Index e, Scratch& s, double* re) {
    Eigen::Map<Eigen::MatrixXd> r(re, dim, A.mesh().nodes_per_element());
    r.setZero();
    if ((m_v.row(e).array() == 0.0).all()) return;  // outside the control's regions
    gather(A, z, e, &s.Z1);
    for (int q = 0; q < nq; ++q) {
      const Eigen::Ref<const Eigen::MatrixXd> G = point_gradients(A, e, q, s);
      Eigen::Matrix3d T = field_gradient(s.Z1, G);
      if (with_identity) T += Eigen::Matrix3d::Identity();
      const Eigen::Vector3d a0 = A.fiber(e, q);
      const double c = -A.geometry().weights()(e, q) * m_v(e, q);
      r.noalias() += (c * (T * a0).head(dim)) * (a0.head(dim).transpose() * G);
    }
  });
}

// vec-wise action of a 9 by 9 fourth-order tensor on a second-order one.
Eigen::Matrix3d apply(const Matrix9d& C, const Eigen::Matrix3d& X) {
  Eigen::Matrix3d Y;
  Eigen::Map<Vector9d>(Y.data()) = C * Eigen::Map<const Vector9d>(X.data());
  return Y;
}

}  // namespace

Eigen::VectorXd control_force(const Assembler& assembler, const ControlSpace& control,
                              const Eigen::VectorXd& u, const Eigen::VectorXd& v) {
  // δ · (∂R/∂m) v = −∫ m_v (F a₀)·(∇δ a₀) dX
  check_dof_vector(assembler, u, "u");
  return fiber_load(assembler, u, /*with_identity=*/true, control.to_quadrature(v));
}

Eigen::VectorXd adjoint_mixed_um(const Assembler& assembler, const ControlSpace& control,
                                 const Eigen::VectorXd& lambda, const Eigen::VectorXd& v) {
  // ∂/∂m [δ·K λ] v = −∫ m_v (∇δ a₀)·(∇λ a₀) dX
  check_dof_vector(assembler, lambda, "lambda");
  return fiber_load(assembler, lambda, /*with_identity=*/false, control.to_quadrature(v));
}

Eigen::VectorXd adjoint_mixed_mu(const Assembler& assembler, const ControlSpace& control,
                                 const Eigen::VectorXd& lambda, const Eigen::VectorXd& w) {
  // k ↦ −∫ M_k (∇w a₀)·(∇λ a₀) dX: the pairing at the quadrature points, then Σ_q M_k(X_q)
  check_dof_vector(assembler, lambda, "lambda");
  check_dof_vector(assembler, w, "w");
  const Assembler& A = assembler;
  const int dim = A.mesh().dim, nen = A.mesh().nodes_per_element();
  const int nq = A.geometry().points_per_element();
  Eigen::MatrixXd p(A.mesh().num_elements(), nq);
  std::vector<Scratch> scratch(softhd::max_threads(), Scratch(dim, nen));
#pragma omp parallel for schedule(static) num_threads(static_cast <int>(scratch.size()))
  for (Eigen::Index e = 0; e < A.mesh().num_elements(); ++e) {
    Scratch& s = scratch[thread_id()];
    gather(A, w, e, &s.Z1);
    gather(A, lambda, e, &s.Z2);
    for (int q = 0; q < nq; ++q) {
      const Eigen::Ref<const Eigen::MatrixXd> G = point_gradients(A, e, q, s);
      const Eigen::Vector3d a0 = A.fiber(e, q);
      p(e, q) = -A.geometry().weights()(e, q) *
                (field_gradient(s.Z1, G) * a0).dot(field_gradient(s.Z2, G) * a0);
    }
  }
  return control.from_quadrature(p);
}

Eigen::Matrix3d tangent_derivative(const EnergyDerivatives& d, double W_JJJ,
                                   const Eigen::Matrix3d& F, const Eigen::Matrix3d& H,
                                   const Eigen::Matrix3d& D, const Eigen::Matrix3d& L) {
  // d/dε of δF:C:L along F + ε D, term by term (dH = F ⨯ D, dJ = H : D, W_FF and W_HH
  // constant, A : (B ⨯ C) symmetric in A, B, C):
  //   (F⨯δF):W_HH:(F⨯L)   → δF : [D ⨯ (W_HH:(F⨯L)) + F ⨯ (W_HH:(D⨯L))]
  //   W_H : (δF ⨯ L)       → δF : [L ⨯ (W_HH:(F⨯D))]
  //   W_JJ (H:δF)(H:L)     → δF : [W_JJJ (H:D)(H:L) H + W_JJ ((H:L)(F⨯D) + ((F⨯D):L) H)]
  //   W_J F : (δF ⨯ L)     → δF : [W_JJ (H:D)(F⨯L) + W_J (D⨯L)]
  const Eigen::Matrix3d FxD = cross(F, D), FxL = cross(F, L), DxL = cross(D, L);
  const double hD = (H.array() * D.array()).sum(), hL = (H.array() * L.array()).sum();
  const double fdL = (FxD.array() * L.array()).sum();
  Eigen::Matrix3d S =
      cross(D, apply(d.W_HH, FxL)) + cross(F, apply(d.W_HH, DxL)) + cross(L, apply(d.W_HH, FxD));
  S += (W_JJJ * hD * hL + d.W_JJ * fdL) * H + d.W_JJ * (hL * FxD + hD * FxL) + d.W_J * DxL;
  return S;
}

Eigen::VectorXd adjoint_curvature(const Assembler& assembler, const Eigen::VectorXd& u,
                                  const Eigen::VectorXd& w, const Eigen::VectorXd& lambda) {
  // δ ↦ ∫ ∇δ : S(F, ∇w, ∇λ) dX: r_e(i, a) = Σ_q w_q Σ_J S_iJ ∂N_a/∂X_J
  check_dof_vector(assembler, u, "u");
  check_dof_vector(assembler, w, "w");
  check_dof_vector(assembler, lambda, "lambda");
  const Assembler& A = assembler;
  const int dim = A.mesh().dim, nq = A.geometry().points_per_element();
  return assemble_vector(A, [&](Eigen::Index e, Scratch& s, double* re) {
    Eigen::Map<Eigen::MatrixXd> r(re, dim, A.mesh().nodes_per_element());
    r.setZero();
    gather(A, u, e, &s.Z1);
    gather(A, w, e, &s.Z2);
    gather(A, lambda, e, &s.Z3);
    const Material& material = A.material(A.mesh().element_region[e]);
    for (int q = 0; q < nq; ++q) {
      const Eigen::Ref<const Eigen::MatrixXd> G = point_gradients(A, e, q, s);
      const Eigen::Matrix3d F = Eigen::Matrix3d::Identity() + field_gradient(s.Z1, G);
      const Eigen::Matrix3d H = cofactor(F);
      const double J = F.determinant();
      const EnergyDerivatives d = material.evaluate(F, H, J, /*second=*/true);
      const Eigen::Matrix3d S = tangent_derivative(
          d, material.W_JJJ(J), F, H, field_gradient(s.Z2, G), field_gradient(s.Z3, G));
      r.noalias() += (A.geometry().weights()(e, q) * S.topLeftCorner(dim, dim)) * G;
    }
  });
}

}  // namespace softhd::fe
