#include "softhd/fe/newton.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <sstream>

#include "line_search.hpp"
#include "softhd/enum_names.hpp"
#include "softhd/error.hpp"
#include "softhd/parallel.hpp"

namespace softhd::fe {

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

}  // namespace

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

namespace {
constexpr EnumNames<NewtonStatus, 4> kNewtonStatusNames{
    {{NewtonStatus::kConverged, "converged"},
     {NewtonStatus::kLoadIncrementTooSmall, "load increment too small"},
     {NewtonStatus::kTooManyLoadSteps, "too many load steps"},
     {NewtonStatus::kTooManyIterations, "too many Newton iterations"}}};
}  // namespace

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

bool NewtonSolver::solve_load_step(const Eigen::MatrixXd& m, int load_step, double load,
                                   bool predictor, Eigen::VectorXd* u, NewtonSummary* summary) {
  const DofMap& dofs = assembler_.dofs();
  Eigen::VectorXd R, R0;
  double Pi = 0.0;
  assemble(Eigen::VectorXd::Zero(dofs.num_dofs), m, nullptr, &R0, nullptr, summary);
  double R_ref = R0.norm();
  EnergyLineSearch line_search(
      options_,
      [&](const Eigen::VectorXd& v, double* e) {
        return assemble(v, m, e, nullptr, nullptr, summary);
      },
      [&](const Eigen::VectorXd& v) {
        Eigen::VectorXd Rv;
        assemble(v, m, nullptr, &Rv, nullptr, summary);
        return Rv.norm();
      });
  double last_step = 0.0;  // |Δu|_∞ of the last iteration
  const bool final = load >= 1.0;
  const double tolerance_factor =
      final ? options_.relative_tolerance
            : std::max(options_.relative_tolerance, options_.intermediate_tolerance);
  for (int it = 0; it <= options_.max_iterations; ++it) {
    // The predictor's first direction uses K_path_: K at u is not needed then.
    const bool use_path = predictor && it == 0 && have_path_tangent_;
    if (!assemble(*u, m, &Pi, &R, use_path ? nullptr : &K_, summary)) {
      summary->message = "start state of the load step has det F <= 0";
      return false;
    }
    const double rnorm = R.norm();
    if (R_ref == 0.0) R_ref = rnorm;
    summary->residual = rnorm;
    summary->residual_reference = R_ref;
    summary->energy = Pi;
    NewtonIteration rec{load_step, load, it, rnorm, Pi, 0.0, 0.0, 0, false, false};
    const bool small_step =
        options_.displacement_tolerance == 0.0 || it == 0 ||
        last_step <= options_.displacement_tolerance * u->lpNorm<Eigen::Infinity>();
    const bool residual_ok = rnorm <= tolerance_factor * R_ref + options_.absolute_tolerance;
    const auto converge = [&] {
      if (use_path) assemble(*u, m, nullptr, nullptr, &K_, summary);
      std::swap(K_path_, K_);  // the tangent at the converged state, kept
      have_path_tangent_ = true;
      return true;
    };
    if ((residual_ok && (small_step || !final)) || rnorm == 0.0) {
      summary->iterations.push_back(rec);
      return converge();
    }
    if (it == options_.max_iterations) {
      summary->iterations.push_back(rec);
      summary->message = "no convergence in " + std::to_string(it) + " iterations";
      return false;
    }
    ++summary->newton_iterations;
    // Forcing term η = min(forcing, |R|/R_ref, 1e-3 tol/|R|): falls like the residual
    // (quadratic convergence), and the last direction is solved to 1e-3 of the tolerance so
    // that the converged state is as accurate as after an exact Newton step.
    const double tol = tolerance_factor * R_ref + options_.absolute_tolerance;
    const double eta =
        std::max(1e-14, std::min({options_.forcing, rnorm / R_ref, 1e-3 * tol / rnorm}));
    Eigen::VectorXd du;
    const SparseMatrix& K = use_path ? K_path_ : K_;
    const bool direction_ok = direction(K, R, R_ref, eta, &du, &rec, summary);
    if (residual_ok && (!direction_ok || rec.shift != 0.0 || rec.truncated)) {
      // Only the step test is pending, and K is not positive definite here (an unstable
      // equilibrium, e.g. a compressed plate before it buckles): a Newton step would leave
      // it along a descent direction instead of confirming it. Converged at the residual.
      --summary->newton_iterations;
      rec.shift = 0.0;
      summary->iterations.push_back(rec);
      return converge();
    }
    if (!direction_ok) {
      summary->iterations.push_back(rec);
      summary->message = "tangent could not be factorised";
      return false;
    }
    const Eigen::VectorXd u_before = *u;
    rec.step = line_search.step(du, Pi, R.dot(dofs.restrict(du)), rnorm, u);
    if (rec.step == 0.0 && !rec.factorized) {
      // The direction came from PCG with a kept factorisation: retry with K factorised.
      tangent_.drop_factorization();
      *u = u_before;
      if (direction(K, R, R_ref, eta, &du, &rec, summary))
        rec.step = line_search.step(du, Pi, R.dot(dofs.restrict(du)), rnorm, u);
    }
    last_step = (*u - u_before).lpNorm<Eigen::Infinity>();
    summary->iterations.push_back(rec);
    if (options_.verbose) {
      std::cerr << "newton: step " << load_step << " load " << load << " it " << it << " |R| "
                << rnorm << " energy " << Pi << " s " << rec.step << " shift " << rec.shift
                << " pcg " << rec.krylov << (rec.factorized ? " factorised" : "")
                << (rec.truncated ? " truncated" : "")
                << (line_search.tentative() ? " (tentative)" : "") << "\n";
    }
    if (rec.step == 0.0) {
      summary->message = "line search failed at iteration " + std::to_string(it);
      return false;
    }
  }
  return false;
}

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
  const Eigen::MatrixXd m0 = state->m_qp;
  double t = 0.0, inc = options_.initial_load_increment;
  Eigen::VectorXd u = state->u;
  while (true) {
    if (summary.load_steps >= options_.max_load_steps) {
      summary.status = NewtonStatus::kTooManyLoadSteps;
      break;
    }
    if (summary.newton_iterations >= options_.max_total_iterations) {
      summary.status = NewtonStatus::kTooManyIterations;
      break;
    }
    const double t_try = std::min(1.0, t + inc);
    const Eigen::MatrixXd m = m0 + t_try * (m_qp - m0);
    if (options_.path_predictor && !have_path_tangent_ && has_free) {
      // Tangent at the last converged state (u, m_t) for the Euler predictor.
      have_path_tangent_ = assemble(state->u, state->m_qp, nullptr, nullptr, &K_path_, &summary);
    }
    const int before = summary.newton_iterations;
    const bool ok = solve_load_step(m, summary.load_steps, t_try,
                                    options_.path_predictor && has_free, &u, &summary);
    ++summary.load_steps;
    if (ok) {
      t = t_try;
      state->u = u;
      state->m_qp = m;
      summary.message.clear();
      if (t >= 1.0) {
        summary.status = NewtonStatus::kConverged;
        break;
      }
      if (summary.newton_iterations - before < options_.max_iterations / 2)
        inc = std::min(1.0, 2.0 * inc);
    } else {
      ++summary.failed_load_steps;
      u = state->u;  // back to the last converged state, whose tangent K_path_ still is
      inc *= 0.5;
      if (inc < options_.min_load_increment) {
        summary.status = NewtonStatus::kLoadIncrementTooSmall;
        summary.message = "at load " + std::to_string(t) + ": " + summary.message;
        break;
      }
    }
  }
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
