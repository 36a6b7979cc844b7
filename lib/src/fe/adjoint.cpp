#include "softhd/fe/adjoint.hpp"

#include "softhd/error.hpp"

namespace softhd::fe {

Eigen::VectorXd solve_adjoint(const Assembler& assembler, NewtonSolver& newton,
                              const Eigen::VectorXd& g) {
  const DofMap& dofs = assembler.dofs();
  if (g.size() != dofs.num_dofs) {
    throw InvalidArgument("adjoint: g must have " + std::to_string(dofs.num_dofs) + " entries");
  }
  if (dofs.num_free == 0) return Eigen::VectorXd::Zero(dofs.num_dofs);
  if (!newton.converged()) {
    throw InvalidArgument("adjoint: the last state solve did not converge");
  }
  // K λ = g on the free dofs (K symmetric), K the tangent at the converged state.
  return dofs.expand(newton.solve_converged_tangent(dofs.restrict(g)));
}

Eigen::VectorXd control_gradient(const Assembler& assembler, const ControlSpace& control,
                                 const Eigen::VectorXd& u, const Eigen::VectorXd& lambda) {
  // dJ/dm_k = Σ_e Σ_q M_k(X_q) w_q det J0 (F a₀)·(∇λ a₀)
  return control.from_quadrature(assembler.fiber_sensitivity(u, lambda));
}

}  // namespace softhd::fe
