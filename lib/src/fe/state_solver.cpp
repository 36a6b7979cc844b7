#include "softhd/fe/state_solver.hpp"

#include "softhd/error.hpp"

namespace softhd::fe {

StateSolver::StateSolver(Assembler assembler, ControlKind control, NewtonOptions options)
    : assembler_(std::move(assembler)),
      control_(assembler_.mesh(), assembler_.geometry(), control),
      newton_(assembler_, options),
      state_(rest_state(assembler_)) {}

StateSolver::StateSolver(const Scene& scene, NewtonOptions options)
    : StateSolver(scene.make_assembler(), scene.control_kind, options) {}

NewtonSummary StateSolver::solve(const Eigen::VectorXd& m) {
  const NewtonSummary summary = newton_.solve(control_.to_quadrature(m), &state_);
  converged_ = summary.converged();
  return summary;
}

Eigen::VectorXd StateSolver::gradient(const Eigen::VectorXd& g) {
  if (!converged_) throw InvalidArgument("state solver: gradient() needs a converged solve");
  const Eigen::VectorXd lambda = solve_adjoint(assembler_, newton_, g);
  return control_gradient(assembler_, control_, state_.u, lambda);
}

}  // namespace softhd::fe
