#include "softhd/fe/state_solver.hpp"

#include "softhd/error.hpp"
#include "softhd/fe/second_order.hpp"
#if defined(SOFTHD_WITH_MPI) && SOFTHD_WITH_MPI
#include "softhd/fe/petsc_state.hpp"
#endif

namespace softhd::fe {

StateEquation::~StateEquation() = default;

StateSolver::StateSolver(Assembler assembler, ControlKind control, NewtonOptions options,
                         std::vector<int> control_regions)
    : own_assembler_(std::make_unique<const Assembler>(std::move(assembler))),
      assembler_(own_assembler_.get()),
      own_control_(std::make_unique<const ControlSpace>(assembler_->mesh(), assembler_->geometry(),
                                                        control, std::move(control_regions))),
      control_(own_control_.get()),
      options_(options),
      newton_(std::in_place, *assembler_, options),
      state_(rest_state(*assembler_)) {}

StateSolver::StateSolver(const Body& body, NewtonOptions options)
    : StateSolver(body.make_assembler(), body.control_kind, options, body.control_regions) {}

StateSolver::StateSolver(const Assembler& assembler, const ControlSpace& control,
                         NewtonOptions options)
    : assembler_(&assembler),
      control_(&control),
      options_(options),
      newton_(std::in_place, assembler, options),
      state_(rest_state(assembler)) {}

NewtonSummary StateSolver::solve(const Eigen::VectorXd& m) {
  if (m.size() != control_->size())
    throw InvalidArgument("state solver: the control has " + std::to_string(m.size()) +
                          " values, expected " + std::to_string(control_->size()));
  have_adjoint_ = false;  // λ belongs to the previous state
  const NewtonSummary summary = newton_->solve(control_->to_quadrature(m), &state_);
  converged_ = summary.converged();
  return summary;
}

void StateSolver::set_state(const State& state) {
  if (state.u.size() != state_.u.size() || state.m_qp.rows() != state_.m_qp.rows() ||
      state.m_qp.cols() != state_.m_qp.cols())
    throw InvalidArgument("state solver: set_state with a state of another problem");
  state_ = state;
  converged_ = false;  // the kept tangent is not this state's
  have_adjoint_ = false;
}

GridSequencingReport StateSolver::grid_sequenced_start(const Body& body, const Eigen::VectorXd& m,
                                                       const GridSequencingOptions& options) {
  GridSequencingReport report;
  state_ = fe::grid_sequenced_start(body, *assembler_, m, options_, options, &report);
  converged_ = false;
  have_adjoint_ = false;
  return report;
}

void StateSolver::reset() {
  newton_.emplace(*assembler_, options_);
  converged_ = false;
  have_adjoint_ = false;
}

Eigen::VectorXd StateSolver::gradient(const Eigen::VectorXd& g) {
  if (!converged_) throw InvalidArgument("state solver: gradient() needs a converged solve");
  lambda_ = solve_adjoint(*assembler_, *newton_, g);
  have_adjoint_ = true;
  return control_gradient(*assembler_, *control_, state_.u, lambda_);
}

int StateSolver::adjoint_factorizations() const {
  return newton_->last_tangent_solve().factorizations;
}

void StateSolver::require_adjoint(const char* what) const {
  if (!converged_ || !have_adjoint_)
    throw InvalidArgument(std::string("state solver: ") + what +
                          " needs a converged solve followed by gradient()");
}

Eigen::VectorXd StateSolver::solve_tangent(const Eigen::VectorXd& b) {
  const DofMap& dofs = assembler_->dofs();
  if (dofs.num_free == 0) return Eigen::VectorXd::Zero(dofs.num_dofs);
  return dofs.expand(newton_->solve_converged_tangent(dofs.restrict(b)));
}

Eigen::VectorXd StateSolver::sensitivity(const Eigen::VectorXd& v) {
  require_adjoint("sensitivity()");
  if (v.size() != control_->size())
    throw InvalidArgument("state solver: sensitivity() needs " + std::to_string(control_->size()) +
                          " control values, got " + std::to_string(v.size()));
  // K w = −(∂R/∂m) v
  return solve_tangent(-control_force(*assembler_, *control_, state_.u, v));
}

Eigen::VectorXd StateSolver::hessian_product(const Eigen::VectorXd& v, const Eigen::VectorXd& w,
                                             const Eigen::VectorXd& q, HessianPart part) {
  require_adjoint("hessian_product()");
  const DofMap& dofs = assembler_->dofs();
  if (v.size() != control_->size() || w.size() != dofs.num_dofs || q.size() != dofs.num_dofs)
    throw InvalidArgument("state solver: hessian_product() needs v with " +
                          std::to_string(control_->size()) + " values and w, q with " +
                          std::to_string(dofs.num_dofs));
  const Assembler& A = *assembler_;
  const Eigen::VectorXd w_free = dofs.expand(dofs.restrict(w));  // fixed entries ignored
  // K μ = q − [∂²(λᵀR)/∂u² w + ∂²(λᵀR)/∂u∂m v]   (Gauss–Newton: K μ = q)
  Eigen::VectorXd rhs = q;
  if (part == HessianPart::full)
    rhs -= adjoint_curvature(A, state_.u, w_free, lambda_) +
           adjoint_mixed_um(A, *control_, lambda_, v);
  const Eigen::VectorXd mu = solve_tangent(rhs);
  // s = −(∂R/∂m)ᵀ μ − ∂²(λᵀR)/∂m∂u w, −(∂R/∂m)ᵀ μ = ∫ M_k (F a₀)·(∇μ a₀) dX (the gradient's map)
  Eigen::VectorXd s = control_gradient(A, *control_, state_.u, mu);
  if (part == HessianPart::full) s -= adjoint_mixed_mu(A, *control_, lambda_, w_free);
  return s;
}

double StateSolver::energy() const {
  double e = 0.0;
  assembler_->evaluate(state_.u, state_.m_qp, &e, nullptr, nullptr);
  return e;
}

double StateSolver::deformed_volume() const { return assembler_->deformed_volume(state_.u); }

double StateSolver::min_jacobian() const { return jacobians().minCoeff(); }

Eigen::MatrixXd StateSolver::jacobians() const { return assembler_->jacobians(state_.u); }

void StateSolverOptions::validate() const {
  newton.validate();
  if (max_krylov_iterations < 1)
    throw InvalidArgument("state solver options: max_krylov_iterations must be >= 1");
}

std::unique_ptr<StateEquation> make_state_solver(const Body& body,
                                                 const StateSolverOptions& options,
                                                 const Assembler* assembler,
                                                 const ControlSpace* control) {
  options.validate();
  NewtonOptions newton = options.newton;
  if (newton.absolute_tolerance == 0.0) newton.absolute_tolerance = body.residual_floor();
  if (options.backend == StateBackend::kCholmod) {
    if (assembler && control) return std::make_unique<StateSolver>(*assembler, *control, newton);
    return std::make_unique<StateSolver>(body, newton);
  }
#if defined(SOFTHD_WITH_MPI) && SOFTHD_WITH_MPI
  PetscStateOptions petsc;
  petsc.newton = newton;
  petsc.backend = options.backend;
  petsc.max_krylov_iterations = options.max_krylov_iterations;
  return std::make_unique<PetscStateSolver>(body, petsc);
#else
  throw InvalidArgument("state backend " + to_string(options.backend) +
                        " needs softhd built with -DSOFTHD_WITH_MPI=ON");
#endif
}

StateSolverFactory state_solver_factory(const Body& body, StateBackend backend,
                                        const Assembler* assembler, const ControlSpace* control) {
  return [&body, backend, assembler, control](const NewtonOptions& newton) {
    StateSolverOptions options;
    options.backend = backend;
    options.newton = newton;
    return make_state_solver(body, options, assembler, control);
  };
}

}  // namespace softhd::fe
