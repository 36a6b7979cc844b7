#include "softhd/fe/newton.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <sstream>

#include "softhd/error.hpp"

namespace softhd::fe {

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

}  // namespace

bool NewtonOptions::IsValid(std::string* error) const {
  auto fail = [&](const std::string& m) {
    if (error) *error = "Newton options: " + m;
    return false;
  };
  if (max_iterations < 1) return fail("max_iterations must be >= 1");
  if (!(relative_tolerance >= 0.0) || !(absolute_tolerance >= 0.0))
    return fail("tolerances must be >= 0");
  if (relative_tolerance == 0.0 && absolute_tolerance == 0.0)
    return fail("relative_tolerance and absolute_tolerance cannot both be 0");
  if (!(armijo > 0.0 && armijo < 0.5)) return fail("armijo must be in (0, 0.5)");
  if (!(backtrack > 0.0 && backtrack < 1.0)) return fail("backtrack must be in (0, 1)");
  if (max_line_search_steps < 1) return fail("max_line_search_steps must be >= 1");
  if (!(initial_load_increment > 0.0 && initial_load_increment <= 1.0))
    return fail("initial_load_increment must be in (0, 1]");
  if (!(min_load_increment > 0.0 && min_load_increment <= initial_load_increment))
    return fail("min_load_increment must be in (0, initial_load_increment]");
  if (max_load_steps < 1) return fail("max_load_steps must be >= 1");
  if (max_total_iterations < 1) return fail("max_total_iterations must be >= 1");
  return true;
}

std::string to_string(NewtonStatus status) {
  switch (status) {
    case NewtonStatus::kConverged:
      return "converged";
    case NewtonStatus::kLoadIncrementTooSmall:
      return "load increment too small";
    case NewtonStatus::kTooManyLoadSteps:
      return "too many load steps";
    case NewtonStatus::kTooManyIterations:
      return "too many Newton iterations";
  }
  return "unknown";
}

std::string NewtonSummary::BriefReport() const {
  char buf[320];
  std::snprintf(buf, sizeof buf,
                "Newton %s: %d iterations, %d load steps (%d failed), load %.4g, |R| = %.3e "
                "(ref %.3e), energy %.8e, %.3f s (assembly %.3f, factorisation %.3f, solve %.3f)",
                to_string(status).c_str(), newton_iterations, load_steps, failed_load_steps,
                final_load, residual, residual_reference, energy, seconds_total, seconds_assembly,
                seconds_factorization, seconds_solve);
  return buf + (message.empty() ? std::string() : "; " + message);
}

std::string NewtonSummary::FullReport() const {
  std::ostringstream os;
  os << BriefReport() << "\n  step   load        it  |R|          energy          s        shift\n";
  char buf[160];
  for (const NewtonIteration& it : iterations) {
    std::snprintf(buf, sizeof buf, "  %4d  %-10.4g %3d  %.3e  %.8e  %-7.3g  %.2g\n", it.load_step,
                  it.load, it.iteration, it.residual, it.energy, it.step, it.shift);
    os << buf;
  }
  return os.str();
}

State rest_state(const Assembler& a) {
  return {Eigen::VectorXd::Zero(a.dofs().num_dofs),
          Eigen::MatrixXd::Zero(a.mesh().num_elements(), a.geometry().points_per_element())};
}

NewtonSolver::NewtonSolver(const Assembler& assembler, NewtonOptions options)
    : assembler_(assembler), options_(options) {
  std::string error;
  if (!options_.IsValid(&error)) throw InvalidArgument(error);
  K_ = assembler_.tangent_pattern();
  shifted_ = K_;
  for (int j = 0; j < K_.outerSize(); ++j) {
    const int* begin = K_.innerIndexPtr() + K_.outerIndexPtr()[j];
    const int* end = K_.innerIndexPtr() + K_.outerIndexPtr()[j + 1];
    diagonal_.push_back(static_cast<int>(std::lower_bound(begin, end, j) - K_.innerIndexPtr()));
  }
  solver_ = make_linear_solver(options_.linear_solver);
  if (K_.rows() > 0) solver_->analyze(K_);  // symbolic analysis once per pattern
}

double NewtonSolver::factorize_with_fallback(NewtonSummary* summary) {
  const auto t0 = Clock::now();
  double shift = 0.0;
  bool ok = solver_->factorize(K_);
  ++summary->factorizations;
  if (!ok) {
    // Not positive definite: factorise K + μ I with μ growing from 1e-8 max|K_ii|.
    double dmax = 0.0;
    for (int idx : diagonal_) dmax = std::max(dmax, std::abs(K_.valuePtr()[idx]));
    shift = 1e-8 * dmax;
    for (int attempt = 0; attempt < 20 && !ok; ++attempt, shift *= 10.0) {
      std::copy(K_.valuePtr(), K_.valuePtr() + K_.nonZeros(), shifted_.valuePtr());
      for (int idx : diagonal_) shifted_.valuePtr()[idx] += shift;
      ok = solver_->factorize(shifted_);
      ++summary->factorizations;
      if (ok) break;
    }
    if (!ok) shift = std::numeric_limits<double>::infinity();
  }
  summary->seconds_factorization += seconds_since(t0);
  return shift;
}

double NewtonSolver::backtrack(const Eigen::MatrixXd& m, const Eigen::VectorXd& u0, double Pi0,
                               double slope, const Eigen::VectorXd& du, double s, double rnorm,
                               Eigen::VectorXd* u, NewtonSummary* summary) const {
  // Π(u0 + s du) <= Π(u0) + c s slope, s halving; +inf energy (det F <= 0) never accepted.
  for (int ls = 0; ls < options_.max_line_search_steps; ++ls, s *= options_.backtrack) {
    const Eigen::VectorXd trial = u0 + s * du;
    double Pi_trial;
    const auto t0 = Clock::now();
    const bool admissible = assembler_.evaluate(trial, m, &Pi_trial, nullptr, nullptr);
    summary->seconds_assembly += seconds_since(t0);
    if (!admissible) continue;
    bool accept = Pi_trial <= Pi0 + options_.armijo * s * slope;
    if (!accept && std::abs(Pi_trial - Pi0) <= 1e-13 * std::abs(Pi0)) {
      // Energy differences at round-off: accept if the residual decreases.
      Eigen::VectorXd R_trial;
      assembler_.evaluate(trial, m, nullptr, &R_trial, nullptr);
      accept = R_trial.norm() < rnorm;
    }
    if (accept) {
      *u = trial;
      return s;
    }
  }
  return 0.0;
}

bool NewtonSolver::solve_load_step(const Eigen::MatrixXd& m, int load_step, double load,
                                   Eigen::VectorXd* u, NewtonSummary* summary) {
  const DofMap& dofs = assembler_.dofs();
  Eigen::VectorXd R, R0;
  double Pi = 0.0;
  auto t0 = Clock::now();
  assembler_.evaluate(Eigen::VectorXd::Zero(dofs.num_dofs), m, nullptr, &R0, nullptr);
  summary->seconds_assembly += seconds_since(t0);
  double R_ref = R0.norm();
  // Watchdog (nonmonotone) line search: a full step that raises the energy but keeps
  // det F > 0 is taken tentatively; if the next full step does not bring the energy below
  // the Armijo line of the saved point, both are undone and the saved step backtracks.
  // Thin bodies need it: the full Newton step bends them correctly but leaves second-order
  // membrane strains whose energy the next iteration removes.
  struct Watch {
    bool active = false;
    Eigen::VectorXd u, du;
    double Pi = 0.0, slope = 0.0, rnorm = 0.0;
  } watch;
  for (int it = 0; it <= options_.max_iterations; ++it) {
    t0 = Clock::now();
    const bool admissible = assembler_.evaluate(*u, m, &Pi, &R, &K_);
    summary->seconds_assembly += seconds_since(t0);
    if (!admissible) {
      summary->message = "start state of the load step has det F <= 0";
      return false;
    }
    const double rnorm = R.norm();
    if (R_ref == 0.0) R_ref = rnorm;
    summary->residual = rnorm;
    summary->residual_reference = R_ref;
    summary->energy = Pi;
    NewtonIteration rec{load_step, load, it, rnorm, Pi, 0.0, 0.0};
    if (rnorm <= options_.relative_tolerance * R_ref + options_.absolute_tolerance ||
        rnorm == 0.0) {
      summary->iterations.push_back(rec);
      if ((options_.factorize_converged_tangent || options_.path_predictor) && dofs.num_free > 0) {
        const double shift = factorize_with_fallback(summary);
        factorization_valid_ = shift == 0.0;
        have_path_tangent_ = std::isfinite(shift);
      }
      return true;
    }
    if (it == options_.max_iterations) {
      summary->iterations.push_back(rec);
      summary->message = "no convergence in " + std::to_string(it) + " iterations";
      return false;
    }
    ++summary->newton_iterations;
    if (it == 0 && have_path_tangent_) {
      rec.shift = 0.0;  // predictor: reuse the previous converged tangent's factorisation
    } else {
      rec.shift = factorize_with_fallback(summary);
    }
    have_path_tangent_ = false;
    factorization_valid_ = false;
    if (!std::isfinite(rec.shift)) {
      summary->iterations.push_back(rec);
      summary->message = "tangent could not be factorised";
      return false;
    }
    t0 = Clock::now();
    const Eigen::VectorXd du = dofs.expand(-solver_->solve(R));
    summary->seconds_solve += seconds_since(t0);
    const double slope = R.dot(dofs.restrict(du));  // dΠ/ds at s = 0, < 0 for descent
    if (watch.active) {
      watch.active = false;
      double Pi_full;
      const Eigen::VectorXd full = *u + du;
      if (assembler_.evaluate(full, m, &Pi_full, nullptr, nullptr) &&
          Pi_full <= watch.Pi + options_.armijo * watch.slope) {
        *u = full;
        rec.step = 1.0;
      } else {
        rec.step = backtrack(m, watch.u, watch.Pi, watch.slope, watch.du, options_.backtrack,
                             watch.rnorm, u, summary);
        if (rec.step == 0.0) *u = watch.u;
      }
    } else {
      double Pi_full;
      const Eigen::VectorXd full = *u + du;
      const bool ok = assembler_.evaluate(full, m, &Pi_full, nullptr, nullptr);
      if (ok && Pi_full <= Pi + options_.armijo * slope) {
        *u = full;
        rec.step = 1.0;
      } else if (ok && options_.watchdog) {
        watch = {true, *u, du, Pi, slope, rnorm};
        *u = full;
        rec.step = 1.0;
      } else {
        rec.step = backtrack(m, *u, Pi, slope, du, 1.0, rnorm, u, summary);
      }
    }
    summary->iterations.push_back(rec);
    if (options_.verbose) {
      std::cerr << "newton: step " << load_step << " load " << load << " it " << it << " |R| "
                << rnorm << " energy " << Pi << " s " << rec.step << " shift " << rec.shift
                << (watch.active ? " (tentative)" : "") << "\n";
    }
    if (rec.step == 0.0) {
      summary->message = "line search failed at iteration " + std::to_string(it);
      return false;
    }
  }
  return false;
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
  // The factorisation left by the previous solve is the path tangent of this one only if
  // this one starts exactly where that one ended.
  if (!(have_path_tangent_ && last_u_.size() == state->u.size() && last_u_ == state->u &&
        last_m_ == state->m_qp)) {
    have_path_tangent_ = false;
  }
  factorization_valid_ = false;
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
    if (options_.path_predictor && !have_path_tangent_ && assembler_.dofs().num_free > 0) {
      // Tangent at the last converged state (u, m_t): its first step is the Euler
      // predictor along the equilibrium path (K depends on m through the fiber term).
      const auto t0 = Clock::now();
      assembler_.evaluate(state->u, state->m_qp, nullptr, nullptr, &K_);
      summary.seconds_assembly += seconds_since(t0);
      have_path_tangent_ = std::isfinite(factorize_with_fallback(&summary));
    }
    const int before = summary.newton_iterations;
    const bool ok = solve_load_step(m, summary.load_steps, t_try, &u, &summary);
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
      u = state->u;  // back to the last converged state
      have_path_tangent_ = false;
      inc *= 0.5;
      if (inc < options_.min_load_increment) {
        summary.status = NewtonStatus::kLoadIncrementTooSmall;
        summary.message = "at load " + std::to_string(t) + ": " + summary.message;
        break;
      }
    }
  }
  if (!summary.converged()) factorization_valid_ = false;
  if (have_path_tangent_) {
    last_u_ = state->u;
    last_m_ = state->m_qp;
  }
  summary.final_load = t;
  summary.seconds_total = seconds_since(t_start);
  return summary;
}

}  // namespace softhd::fe
