#pragma once
/// \file state_solver.hpp
/// The state equation as the optimiser sees it (docs/formulation.md §4): a control vector m in, the
/// equilibrium displacement out, warm-started from the previous solve, and the adjoint
/// gradient dJ/dm for any ∂J/∂u at the last converged state, solved with its tangent.

#include <Eigen/Core>

#include "softhd/fe/adjoint.hpp"
#include "softhd/fe/newton.hpp"
#include "softhd/fe/scene.hpp"

namespace softhd::fe {

/// The state equation m ↦ u(m) with warm starts and the adjoint gradient, for one body.
class StateSolver {
 public:
  /// A solver for `assembler`'s body with controls of kind `control`.
  StateSolver(Assembler assembler, ControlKind control, NewtonOptions options = {});
  /// The scene's body, material, clamp and control space.
  explicit StateSolver(const Scene& scene, NewtonOptions options = {});
  StateSolver(const StateSolver&) = delete;  // the Newton solver refers to the assembler
  StateSolver& operator=(const StateSolver&) = delete;

  /// The body's assembler.
  const Assembler& assembler() const { return assembler_; }
  /// The control space.
  const ControlSpace& control() const { return control_; }

  /// Equilibrium for the control m (control().size() values), starting from the last
  /// converged state. On failure the state stays at the last converged load step (a valid
  /// equilibrium for an intermediate control) and the summary says why.
  NewtonSummary solve(const Eigen::VectorXd& m);

  /// Displacement of the current state (num_dofs entries).
  const Eigen::VectorXd& displacement() const { return state_.u; }
  /// True if the last solve converged (gradient() is then available).
  bool converged() const { return converged_; }

  /// State part of dJ/dm_k = ∫ M_k (F a₀)·(∇λ a₀) dX with K λ = g, g = ∂J/∂u (num_dofs).
  /// Throws InvalidArgument if the last solve did not converge.
  Eigen::VectorXd gradient(const Eigen::VectorXd& g);

 private:
  Assembler assembler_;
  ControlSpace control_;
  NewtonSolver newton_;
  State state_;
  bool converged_ = false;
};

}  // namespace softhd::fe
