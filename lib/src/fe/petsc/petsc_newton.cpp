#include "petsc_newton.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iostream>
#include <string>

#include "../../common/seconds_since.hpp"
#include "../newton_load_step.hpp"
#include "softhd/error.hpp"

namespace softhd::fe::petsc_detail {

namespace {

using detail::Clock;
using detail::seconds_since;

NewtonOptions validated(NewtonOptions options) {
  options.validate();
  return options;
}

}  // namespace

DistributedNewton::DistributedNewton(DistributedSystem& system, const NewtonOptions& options)
    : system_(system), options_(validated(options)) {}

bool DistributedNewton::assemble(const Eigen::VectorXd& u, const Eigen::MatrixXd& m, double* energy,
                                 Eigen::VectorXd* residual, bool tangent, NewtonSummary* summary) {
  const auto t0 = Clock::now();
  if (tangent) path_tangent_ = false;
  const bool ok = system_.evaluate(u, m, energy, residual, tangent);
  summary->seconds_assembly += seconds_since(t0);
  ++summary->assemblies;
  return ok;
}

bool DistributedNewton::direction(const Eigen::VectorXd& R, double eta, Eigen::VectorXd* du,
                                  NewtonIteration* rec, NewtonSummary* summary) {
  const LinearSolveReport r = system_.solve(-R, eta, /*allow_shift=*/true, du);
  summary->factorizations += r.attempts;
  summary->krylov_iterations += r.krylov;
  (r.krylov > 0 ? summary->seconds_solve : summary->seconds_factorization) += r.seconds;
  rec->shift = r.ok ? r.shift : 0.0;
  rec->krylov = r.krylov;
  rec->factorized = true;
  return r.ok;
}

// The distributed linear algebra of newton_load_step (../newton_load_step.hpp): owned rows,
// norms and dot products reduced over the ranks, one PETSc matrix (the path tangent until
// the next tangent assembly) and the system's KSP, each direction a fresh solve.
struct DistributedNewton::Algebra {
  DistributedNewton& n;
  NewtonSummary* summary;

  bool has_path_tangent() const { return n.path_tangent_; }
  bool assemble(const Eigen::VectorXd& u, const Eigen::MatrixXd& m, double* energy,
                Eigen::VectorXd* residual, bool tangent) {
    return n.assemble(u, m, energy, residual, tangent, summary);
  }
  double norm(const Eigen::VectorXd& R) const { return n.system_.norm(R); }
  double max_abs(const Eigen::VectorXd& u) const { return n.system_.max_abs(u); }
  double slope(const Eigen::VectorXd& R, const Eigen::VectorXd& du) const {
    return n.system_.dot(R, du);
  }
  bool iterative() const { return n.system_.iterative(); }
  // The matrix is the path tangent exactly when `path` is set (not assembled at u then).
  bool direction(bool /*path*/, const Eigen::VectorXd& R, double /*R_ref*/, double eta,
                 Eigen::VectorXd* du, NewtonIteration* rec) {
    return n.direction(R, eta, du, rec, summary);
  }
  void drop_factorization() {}  // nothing kept: every direction factorises afresh
  void converge(bool tangent_is_current, const Eigen::VectorXd& u, const Eigen::MatrixXd& m) {
    if (!tangent_is_current) n.assemble(u, m, nullptr, nullptr, true, summary);
    n.path_tangent_ = true;
  }
  bool speaks() const { return n.system_.part().rank == 0; }
  const char* name() const { return "newton(petsc)"; }
  bool assemble_path_tangent(const Eigen::VectorXd& u, const Eigen::MatrixXd& m) {
    if (n.assemble(u, m, nullptr, nullptr, true, summary)) n.path_tangent_ = true;
    return n.path_tangent_;
  }
  void load_step_failed() { n.path_tangent_ = false; }  // the failed step overwrote K
};

Eigen::VectorXd DistributedNewton::solve_converged_tangent(const Eigen::VectorXd& b) {
  if (!converged_) throw InvalidArgument("Newton (PETSc): no converged state to solve with");
  if (!path_tangent_) {
    NewtonSummary scratch;
    Algebra{*this, &scratch}.converge(false, last_u_, last_m_);
  }
  Eigen::VectorXd x;
  const LinearSolveReport r =
      system_.solve(b, options_.adjoint_tolerance, /*allow_shift=*/false, &x);
  adjoint_attempts_ = r.attempts;
  if (!r.ok) throw NumericalError("Newton (PETSc): the converged tangent is not positive definite");
  return x;
}

void DistributedNewton::reset() {
  path_tangent_ = false;
  converged_ = false;
  adjoint_attempts_ = 0;
  last_u_.resize(0);
  last_m_.resize(0, 0);
  system_.forget_shift();
}

NewtonSummary DistributedNewton::solve(const Eigen::MatrixXd& m_qp, Eigen::VectorXd* state_u,
                                       Eigen::MatrixXd* state_m) {
  const auto t_start = Clock::now();
  NewtonSummary summary;
  // K is the path tangent of this solve only if it starts where the last one ended.
  const bool same_start = last_u_.size() == state_u->size() && last_u_ == *state_u &&
                          last_m_.rows() == state_m->rows() && last_m_ == *state_m;
  if (system_.min(same_start ? 1.0 : 0.0) == 0.0) path_tangent_ = false;
  converged_ = false;
  const bool has_free = system_.sum(static_cast<double>(state_u->size())) > 0.0;
  Algebra algebra{*this, &summary};
  const double t =
      newton_load_stepping(algebra, options_, m_qp, has_free, state_u, state_m, &summary);
  converged_ = summary.converged();
  last_u_ = *state_u;
  last_m_ = *state_m;
  if (!converged_) path_tangent_ = false;
  summary.final_load = t;
  summary.seconds_total = seconds_since(t_start);
  return summary;
}

}  // namespace softhd::fe::petsc_detail
