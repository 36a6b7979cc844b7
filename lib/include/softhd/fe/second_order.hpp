#pragma once
/// \file second_order.hpp
/// The state's terms of the reduced Hessian-vector product of J(m) = F(u(m), m) with
/// R(u; m) = ∂Π/∂u = 0 (docs/formulation.md §4.4.1): the control's force (∂R/∂m) v and the
/// second derivatives of the λ-weighted residual λᵀR. R is affine in m (∂²R/∂m² = 0) and
/// F = I + ∇u is linear in u.
///
/// Dof vectors have num_dofs entries (node · dim + component) with the fixed ones zero;
/// displacement-like inputs (u, w, λ) are read on all their entries, as the assembler reads
/// u. Control vectors have one value per control of the ControlSpace. Element loops are
/// parallel (OpenMP) into per-element buffers added serially in element order, so every
/// result is bitwise the same for any number of threads.

#include <Eigen/Core>

#include "softhd/fe/assembly.hpp"
#include "softhd/fe/control.hpp"

namespace softhd::fe {

/// (∂R/∂m) v at the displacement u for the control direction v (a dof vector):
/// δ · (∂R/∂m) v = −∫ m_v (F a₀)·(∇δ a₀) dX, m_v = Σ_k M_k v_k.
Eigen::VectorXd control_force(const Assembler& assembler, const ControlSpace& control,
                              const Eigen::VectorXd& u, const Eigen::VectorXd& v);

/// ∂²(λᵀR)/∂u∂m v for the control direction v (a dof vector):
/// δ ↦ −∫ m_v (∇δ a₀)·(∇λ a₀) dX (independent of u).
Eigen::VectorXd adjoint_mixed_um(const Assembler& assembler, const ControlSpace& control,
                                 const Eigen::VectorXd& lambda, const Eigen::VectorXd& v);

/// ∂²(λᵀR)/∂m∂u w for the displacement direction w (a control vector), the transpose of
/// adjoint_mixed_um: k ↦ −∫ M_k (∇w a₀)·(∇λ a₀) dX.
Eigen::VectorXd adjoint_mixed_mu(const Assembler& assembler, const ControlSpace& control,
                                 const Eigen::VectorXd& lambda, const Eigen::VectorXd& w);

/// ∂²(λᵀR)/∂u² w = d/dε [K(u + ε w) λ] at ε = 0, exactly (a dof vector):
/// δ ↦ ∫ d/dε [∇δ : C(F + ε ∇w) : ∇λ] dX, the third derivative of W(F) applied to
/// (∇δ, ∇w, ∇λ), symmetric in the three (the fibre term's C does not depend on u).
/// Needs W_FF, W_HH constant (Material::W_JJJ). Throws InvalidArgument for the wrong sizes.
Eigen::VectorXd adjoint_curvature(const Assembler& assembler, const Eigen::VectorXd& u,
                                  const Eigen::VectorXd& w, const Eigen::VectorXd& lambda);

/// The trilinear form at one point: S with ∇δ : S = d/dε [∇δ : C(F + ε D) : L], D = ∇w,
/// L = ∇λ (3 by 3; plane strain in 2D), for the material derivatives `d` (with the second
/// ones) at F, H = cof F, and W_JJJ:
///   S = D ⨯ (W_HH:(F ⨯ L)) + F ⨯ (W_HH:(D ⨯ L)) + L ⨯ (W_HH:(F ⨯ D))
///       + W_JJJ (H:D)(H:L) H + W_JJ [(H:L)(F ⨯ D) + ((F ⨯ D):L) H + (H:D)(F ⨯ L)] + W_J D ⨯ L.
Eigen::Matrix3d tangent_derivative(const EnergyDerivatives& d, double W_JJJ,
                                   const Eigen::Matrix3d& F, const Eigen::Matrix3d& H,
                                   const Eigen::Matrix3d& D, const Eigen::Matrix3d& L);

}  // namespace softhd::fe
