#pragma once
/// \file state_solver.hpp
/// The serial implementation of the state equation (fe/state_equation.hpp): the Newton of
/// fe/newton.hpp with CHOLMOD factorisations, on the whole mesh, warm-started from the
/// previous solve, and the adjoint gradient dJ/dm for any ∂J/∂u at the last converged
/// state, solved with its tangent (docs/formulation.md §4).

#include <Eigen/Core>
#include <memory>
#include <optional>

#include "softhd/fe/adjoint.hpp"
#include "softhd/fe/body.hpp"
#include "softhd/fe/newton.hpp"
#include "softhd/fe/state_equation.hpp"

namespace softhd::fe {

/// The state equation m ↦ u(m) with warm starts and the adjoint gradient, for one body,
/// by the serial Newton (StateBackend::kCholmod).
class StateSolver final : public StateEquation {
 public:
  /// A solver for `assembler`'s body with controls of kind `control` acting on
  /// `control_regions` (empty: the whole body); the assembler and control space are kept.
  StateSolver(Assembler assembler, ControlKind control, NewtonOptions options = {},
              std::vector<int> control_regions = {});
  /// The body's body, material, clamp and control space.
  explicit StateSolver(const Body& body, NewtonOptions options = {});
  /// A solver on an assembler and control space the caller keeps; both must outlive it.
  StateSolver(const Assembler& assembler, const ControlSpace& control, NewtonOptions options);

  /// The body's assembler.
  const Assembler& assembler() const { return *assembler_; }
  /// The control space.
  const ControlSpace& control() const { return *control_; }

  /// StateBackend::kCholmod.
  StateBackend backend() const override { return StateBackend::kCholmod; }
  /// Free dofs of the mesh.
  Eigen::Index free_dofs() const override { return assembler_->dofs().num_free; }
  /// Equilibrium for the control m (control().size() values), starting from the current
  /// state. On failure the state stays at the last converged load step (a valid
  /// equilibrium for an intermediate control) and the summary says why.
  NewtonSummary solve(const Eigen::VectorXd& m) override;
  /// True if the last solve converged (gradient() is then available).
  bool converged() const override { return converged_; }
  /// Displacement of the current state (num_dofs entries).
  Eigen::VectorXd displacement() const override { return state_.u; }
  /// The current state.
  State state() const override { return state_; }
  /// The current state, without a copy.
  const State& current_state() const { return state_; }
  /// Makes `state` the start of the next solve (shapes checked).
  void set_state(const State& state) override;
  /// grid_sequenced_start of fe/grid_sequencing.hpp on this solver's assembler.
  GridSequencingReport grid_sequenced_start(const Body& body, const Eigen::VectorXd& m,
                                            const GridSequencingOptions& options) override;
  /// A new Newton solver (no kept factorisation or path tangent); the state is kept.
  void reset() override;

  /// State part of dJ/dm_k = ∫ M_k (F a₀)·(∇λ a₀) dX with K λ = g, g = ∂J/∂u (num_dofs).
  /// Keeps λ for sensitivity() and hessian_product() at this state (until the next solve,
  /// set_state, grid_sequenced_start or reset). Throws InvalidArgument if the last solve did
  /// not converge.
  Eigen::VectorXd gradient(const Eigen::VectorXd& g) override;
  /// Factorisations of the last tangent solve (the adjoint's after gradient()).
  int adjoint_factorizations() const override;
  /// w = (du/dm) v (StateEquation::sensitivity): K w = −(∂R/∂m) v with the converged tangent,
  /// solved as the adjoint is (PCG with the kept factorisation).
  Eigen::VectorXd sensitivity(const Eigen::VectorXd& v) override;
  /// The state's side of the reduced Hessian-vector product (StateEquation::hessian_product):
  /// K μ = q − [∂²(λᵀR)/∂u² w + ∂²(λᵀR)/∂u∂m v], s = −(∂R/∂m)ᵀ μ − ∂²(λᵀR)/∂m∂u w
  /// (fe/second_order.hpp; the brackets dropped by HessianPart::gauss_newton). Entries of w
  /// and q at fixed dofs are ignored.
  Eigen::VectorXd hessian_product(const Eigen::VectorXd& v, const Eigen::VectorXd& w,
                                  const Eigen::VectorXd& q, HessianPart part) override;

  ///@{
  /// Π(u; m), ∫ J dX and min J at the current state.
  double energy() const override;
  double deformed_volume() const override;
  double min_jacobian() const override;
  ///@}
  /// det F at the quadrature points of the current state.
  Eigen::MatrixXd jacobians() const override;

 private:
  std::unique_ptr<const Assembler> own_assembler_;  // null if the caller keeps it
  const Assembler* assembler_;
  std::unique_ptr<const ControlSpace> own_control_;  // null if the caller keeps it
  const ControlSpace* control_;
  NewtonOptions options_;
  std::optional<NewtonSolver> newton_;  // optional: reset() makes a new one
  State state_;
  bool converged_ = false;
  /// The adjoint of the last gradient() at the converged state_ (valid if have_adjoint_).
  Eigen::VectorXd lambda_;
  bool have_adjoint_ = false;
  /// Throws InvalidArgument unless a gradient() followed the last (converged) solve.
  void require_adjoint(const char* what) const;
  /// x (num_dofs, fixed entries zero) with K x = b on the free dofs, b = the free entries of
  /// `b`, K the converged tangent (NewtonSolver::solve_converged_tangent).
  Eigen::VectorXd solve_tangent(const Eigen::VectorXd& b);
};

}  // namespace softhd::fe
