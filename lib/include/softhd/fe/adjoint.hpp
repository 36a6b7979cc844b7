#pragma once
/// \file adjoint.hpp
/// The adjoint gradient of a functional J(u(m), m) w.r.t. the control (docs/formulation.md §4.4):
/// solve K λ = g = ∂J/∂u on the free dofs with the converged tangent, then dJ/dm_k = ∂J/∂m_k + ∫
/// M_k (F a₀)·(∇λ a₀) dX, ∇λ = Σ_a λ_a ⊗ ∇N_a. (Sign: R(u; m) = ∂Π/∂u = 0 and ∂R/∂m_k · v = −∫ M_k
/// (F a₀)·(∇v a₀) dX, so dJ/dm_k = −λ·∂R/∂m_k; checked by the Taylor test in
/// tests/fe/test_adjoint.cpp.)

#include <Eigen/Core>

#include "softhd/fe/assembly.hpp"
#include "softhd/fe/control.hpp"
#include "softhd/fe/newton.hpp"

namespace softhd::fe {

/// λ (all num_dofs entries, fixed ones zero) from K λ = g on the free dofs, K the tangent
/// at the state of `newton`'s last solve (NewtonSolver::solve_converged_tangent: PCG with
/// the kept factorisation to NewtonOptions::adjoint_tolerance, or a factorisation); `g`
/// has num_dofs entries (those of fixed dofs are ignored). Throws InvalidArgument if the
/// last solve did not converge.
Eigen::VectorXd solve_adjoint(const Assembler& assembler, NewtonSolver& newton,
                              const Eigen::VectorXd& g);

/// The state part of the control gradient: ∫ M_k (F a₀)·(∇λ a₀) dX for every control k,
/// at the converged displacement u.
Eigen::VectorXd control_gradient(const Assembler& assembler, const ControlSpace& control,
                                 const Eigen::VectorXd& u, const Eigen::VectorXd& lambda);

}  // namespace softhd::fe
