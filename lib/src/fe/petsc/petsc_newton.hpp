#pragma once
// Newton–Raphson of fe/newton.hpp on a DistributedSystem (internal to the PETSc backend):
// the same load stepping, path predictor, forcing terms, convergence test and energy line
// search (EnergyLineSearch on the owned entries), with reductions over the ranks. Linear
// solves by the system's KSP with the shift search instead of PCG with a kept factor.

#include <Eigen/Core>

#include "petsc_system.hpp"
#include "softhd/fe/newton.hpp"

namespace softhd::fe::petsc_detail {

class DistributedNewton {
 public:
  DistributedNewton(DistributedSystem& system, const NewtonOptions& options);

  /// Moves (*u, *m_state) (owned rows; the part's control at its quadrature points) to
  /// equilibrium with m_qp, ramping from *m_state. On failure they stay at the last
  /// converged load step.
  NewtonSummary solve(const Eigen::MatrixXd& m_qp, Eigen::VectorXd* u, Eigen::MatrixXd* m_state);
  bool converged() const { return converged_; }
  /// x with K x = b (owned rows) for the tangent at the last converged state, to the
  /// relative residual adjoint_tolerance. Throws NumericalError if K is not positive
  /// definite or the solve fails.
  Eigen::VectorXd solve_converged_tangent(const Eigen::VectorXd& b);
  /// Factorisations (MUMPS) or preconditioner set-ups (GAMG) of the last
  /// solve_converged_tangent.
  int adjoint_attempts() const { return adjoint_attempts_; }
  /// Forgets the path tangent, the last shift and the last converged state, as a new
  /// solver on the same system.
  void reset();

 private:
  /// The linear algebra of the shared Newton loop (../newton_load_step.hpp).
  struct Algebra;
  bool direction(const Eigen::VectorXd& R, double eta, Eigen::VectorXd* du, NewtonIteration* rec,
                 NewtonSummary* summary);
  bool assemble(const Eigen::VectorXd& u, const Eigen::MatrixXd& m, double* energy,
                Eigen::VectorXd* residual, bool tangent, NewtonSummary* summary);

  DistributedSystem& system_;
  NewtonOptions options_;
  bool path_tangent_ = false;  ///< the system's K is the tangent at (last_u_, last_m_)
  bool converged_ = false;
  int adjoint_attempts_ = 0;
  Eigen::VectorXd last_u_;
  Eigen::MatrixXd last_m_;
};

}  // namespace softhd::fe::petsc_detail
