#include "softhd/fe/newton.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <sstream>

#include "../common/seconds_since.hpp"
#include "newton_load_step.hpp"
#include "softhd/enum_names.hpp"
#include "softhd/error.hpp"
#include "softhd/parallel.hpp"

namespace softhd::fe {

double residual_floor(double stiffness_scale, double volume, int dim) {
  // 1e-10 × stiffness × |Ω₀|^((d−1)/d): a force (stress × area)
  return 1e-10 * stiffness_scale * std::pow(volume, (dim - 1.0) / dim);
}

using detail::Clock;
using detail::seconds_since;

void NewtonOptions::validate() const {
  auto check = [](bool ok, const std::string& m) {
    if (!ok) throw InvalidArgument("Newton options: " + m);
  };
  check(max_iterations >= 1, "max_iterations must be >= 1");
  check(relative_tolerance >= 0.0, "relative_tolerance must be >= 0");
  check(absolute_tolerance >= 0.0, "absolute_tolerance must be >= 0");
  check(relative_tolerance > 0.0 || absolute_tolerance > 0.0,
        "relative_tolerance and absolute_tolerance cannot both be 0");
  check(armijo > 0.0 && armijo < 0.5, "armijo must be in (0, 0.5)");
  check(backtrack > 0.0 && backtrack < 1.0, "backtrack must be in (0, 1)");
  check(max_line_search_steps >= 1, "max_line_search_steps must be >= 1");
  check(initial_load_increment > 0.0 && initial_load_increment <= 1.0,
        "initial_load_increment must be in (0, 1]");
  check(min_load_increment > 0.0 && min_load_increment <= initial_load_increment,
        "min_load_increment must be in (0, initial_load_increment]");
  check(max_load_steps >= 1, "max_load_steps must be >= 1");
  check(max_total_iterations >= 1, "max_total_iterations must be >= 1");
  check(forcing > 0.0 && forcing < 1.0, "forcing must be in (0, 1)");
  check(displacement_tolerance >= 0.0, "displacement_tolerance must be >= 0");
  check(intermediate_tolerance > 0.0 && intermediate_tolerance < 1.0,
        "intermediate_tolerance must be in (0, 1)");
  check(adjoint_tolerance > 0.0 && adjoint_tolerance < 1.0, "adjoint_tolerance must be in (0, 1)");
  try {
    tangent.validate();  // one set of checks for the tangent solver's options
  } catch (const InvalidArgument& e) {
    check(false, e.what());
  }
}

constexpr auto kNewtonStatusNames = enum_sequence<NewtonStatus::kTooManyIterations>(
    {"converged", "load increment too small", "too many load steps", "too many Newton iterations"});

std::string to_string(NewtonStatus status) { return enum_name(kNewtonStatusNames, status); }

std::string NewtonSummary::BriefReport() const {
  char buf[320];
  std::snprintf(buf, sizeof buf,
                "Newton %s: %d iterations, %d load steps (%d failed), load %.4g, |R| = %.3e "
                "(ref %.3e), energy %.8e, %.3f s (%d assemblies %.3f s, %d factorisations "
                "%.3f s, %d PCG iterations + solves %.3f s)",
                to_string(status).c_str(), newton_iterations, load_steps, failed_load_steps,
                final_load, residual, residual_reference, energy, seconds_total, assemblies,
                seconds_assembly, factorizations, seconds_factorization, krylov_iterations,
                seconds_solve);
  return buf + (message.empty() ? std::string() : "; " + message);
}

std::string NewtonSummary::FullReport() const {
  std::ostringstream os;
  os << BriefReport()
     << "\n  step   load        it  |R|          energy          s        shift  pcg  fact\n";
  char buf[160];
  for (const NewtonIteration& it : iterations) {
    std::snprintf(buf, sizeof buf, "  %4d  %-10.4g %3d  %.3e  %.8e  %-7.3g  %-5.2g  %3d  %d\n",
                  it.load_step, it.load, it.iteration, it.residual, it.energy, it.step, it.shift,
                  it.krylov, it.factorized ? 1 : 0);
    os << buf;
  }
  return os.str();
}

State rest_state(const Assembler& a) {
  return {Eigen::VectorXd::Zero(a.dofs().num_dofs),
          Eigen::MatrixXd::Zero(a.mesh().num_elements(), a.geometry().points_per_element())};
}

namespace {

NewtonOptions validated(NewtonOptions options) {
  options.validate();
  return options;
}

}  // namespace

NewtonSolver::NewtonSolver(const Assembler& assembler, NewtonOptions options)
    : assembler_(assembler),
      options_(validated(options)),
      tangent_(assembler.tangent_pattern(), options_.tangent),
      K_(assembler.tangent_pattern()),
      K_path_(K_) {
  limit_blas_threads();
}

bool NewtonSolver::assemble(const Eigen::VectorXd& u, const Eigen::MatrixXd& m, double* energy,
                            Eigen::VectorXd* residual, SparseMatrix* tangent,
                            NewtonSummary* summary) const {
  const auto t0 = Clock::now();
  const bool ok = assembler_.evaluate(u, m, energy, residual, tangent);
  summary->seconds_assembly += seconds_since(t0);
  ++summary->assemblies;
  return ok;
}

bool NewtonSolver::direction(const SparseMatrix& K, const Eigen::VectorXd& R, double reference,
                             double eta, Eigen::VectorXd* du, NewtonIteration* rec,
                             NewtonSummary* summary) {
  // K du = −R on the free dofs, to ‖K du + R‖ <= η ‖R‖.
  Eigen::VectorXd x;
  // Truncated (Newton–CG) directions escape indefinite regions cheaply, but in a row they
  // can stall on a flat unstable mode (the residual oscillating at constant energy, as on a
  // compressed 3x1x1 plate) and near equilibrium a shifted factorisation converges better:
  // truncate only far from equilibrium and never twice in a row.
  const bool allow_truncation = R.norm() > 1e-3 * reference && !last_truncated_;
  const TangentSolveReport r =
      tangent_.solve(K, -R, eta, /*allow_shift=*/true, &x, allow_truncation);
  last_truncated_ = r.truncated;
  summary->factorizations += r.factorizations;
  summary->krylov_iterations += r.krylov_iterations;
  summary->seconds_factorization += r.seconds_factorization;
  summary->seconds_solve += r.seconds_solve;
  rec->shift = r.shift;
  rec->krylov = r.krylov_iterations;
  rec->factorized = r.factorized;
  rec->truncated = r.truncated;
  if (!r.ok) return false;
  *du = assembler_.dofs().expand(x);
  return true;
}

// The serial linear algebra of newton_load_step (newton_load_step.hpp): whole-mesh
// displacements, free-dof residuals, the tangents K_ (at the iterate) and K_path_ (at the
// last converged state) and the tangent solver (PCG on a kept factorisation).
struct NewtonSolver::Algebra {
  NewtonSolver& s;
  NewtonSummary* summary;

  bool has_path_tangent() const { return s.have_path_tangent_; }
  bool assemble(const Eigen::VectorXd& u, const Eigen::MatrixXd& m, double* energy,
                Eigen::VectorXd* residual, bool tangent) {
    return s.assemble(u, m, energy, residual, tangent ? &s.K_ : nullptr, summary);
  }
  double norm(const Eigen::VectorXd& R) const { return R.norm(); }
  double max_abs(const Eigen::VectorXd& u) const { return u.lpNorm<Eigen::Infinity>(); }
  double slope(const Eigen::VectorXd& R, const Eigen::VectorXd& du) const {
    return R.dot(s.assembler_.dofs().restrict(du));
  }
  bool iterative() const { return false; }
  bool direction(bool path, const Eigen::VectorXd& R, double R_ref, double eta, Eigen::VectorXd* du,
                 NewtonIteration* rec) {
    return s.direction(path ? s.K_path_ : s.K_, R, R_ref, eta, du, rec, summary);
  }
  void drop_factorization() { s.tangent_.drop_factorization(); }
  void converge(bool tangent_is_current, const Eigen::VectorXd& u, const Eigen::MatrixXd& m) {
    if (!tangent_is_current) s.assemble(u, m, nullptr, nullptr, &s.K_, summary);
    std::swap(s.K_path_, s.K_);  // the tangent at the converged state, kept
    s.have_path_tangent_ = true;
  }
  bool speaks() const { return true; }
  const char* name() const { return "newton"; }
  bool assemble_path_tangent(const Eigen::VectorXd& u, const Eigen::MatrixXd& m) {
    s.have_path_tangent_ = s.assemble(u, m, nullptr, nullptr, &s.K_path_, summary);
    return s.have_path_tangent_;
  }
  void load_step_failed() {}  // K_path_ is still the tangent at the last converged state
};

Eigen::VectorXd NewtonSolver::solve_converged_tangent(const Eigen::VectorXd& b) {
  if (!converged_) throw InvalidArgument("Newton: no converged state to solve with");
  if (b.size() != assembler_.dofs().num_free)
    throw InvalidArgument("Newton: the right-hand side must have num_free entries");
  Eigen::VectorXd x;
  last_tangent_solve_ =
      tangent_.solve(K_path_, b, options_.adjoint_tolerance, /*allow_shift=*/false, &x);
  if (!last_tangent_solve_.ok)
    throw NumericalError("Newton: the converged tangent is not positive definite");
  return x;
}

NewtonSummary NewtonSolver::solve(const Eigen::MatrixXd& m_qp, State* state) {
  const auto t_start = Clock::now();
  const Eigen::Index E = assembler_.mesh().num_elements();
  const int nq = assembler_.geometry().points_per_element();
  if (m_qp.rows() != E || m_qp.cols() != nq) {
    throw InvalidArgument("Newton: m_qp must be " + std::to_string(E) + " by " +
                          std::to_string(nq));
  }
  if (state->u.size() != assembler_.dofs().num_dofs || state->m_qp.rows() != E ||
      state->m_qp.cols() != nq) {
    throw InvalidArgument("Newton: the start state has the wrong size (use rest_state())");
  }
  NewtonSummary summary;
  // The tangent kept from the previous solve is the path tangent of this one only if this
  // one starts exactly where that one ended.
  if (!(have_path_tangent_ && last_u_.size() == state->u.size() && last_u_ == state->u &&
        last_m_ == state->m_qp)) {
    have_path_tangent_ = false;
  }
  converged_ = false;
  const bool has_free = assembler_.dofs().num_free > 0;
  Algebra algebra{*this, &summary};
  const double t =
      newton_load_stepping(algebra, options_, m_qp, has_free, &state->u, &state->m_qp, &summary);
  converged_ = summary.converged();
  if (converged_ && !have_path_tangent_ && has_free) {
    // Converged without a Newton iteration on a fresh start: K at the state for the adjoint.
    have_path_tangent_ = assemble(state->u, state->m_qp, nullptr, nullptr, &K_path_, &summary);
  }
  if (have_path_tangent_) {
    last_u_ = state->u;
    last_m_ = state->m_qp;
  }
  summary.final_load = t;
  summary.seconds_total = seconds_since(t_start);
  return summary;
}

}  // namespace softhd::fe
