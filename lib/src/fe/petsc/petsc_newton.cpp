#include "petsc_newton.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iostream>
#include <string>

#include "../line_search.hpp"
#include "softhd/error.hpp"

namespace softhd::fe::petsc_detail {

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

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

bool DistributedNewton::converge(bool tangent_is_current, const Eigen::VectorXd& u,
                                 const Eigen::MatrixXd& m, NewtonSummary* summary) {
  if (!tangent_is_current) assemble(u, m, nullptr, nullptr, true, summary);
  path_tangent_ = true;
  return true;
}

bool DistributedNewton::solve_load_step(const Eigen::MatrixXd& m, int load_step, double load,
                                        bool predictor, Eigen::VectorXd* u,
                                        NewtonSummary* summary) {
  Eigen::VectorXd R, R0;
  double Pi = 0.0;
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(u->size());
  assemble(zero, m, nullptr, &R0, false, summary);
  double R_ref = system_.norm(R0);
  EnergyLineSearch line_search(
      options_,
      [&](const Eigen::VectorXd& v, double* e) {
        return assemble(v, m, e, nullptr, false, summary);
      },
      [&](const Eigen::VectorXd& v) {
        Eigen::VectorXd Rv;
        assemble(v, m, nullptr, &Rv, false, summary);
        return system_.norm(Rv);
      });
  double last_step = 0.0;  // |Δu|_∞ of the last iteration
  const bool final = load >= 1.0;
  const double tolerance_factor =
      final ? options_.relative_tolerance
            : std::max(options_.relative_tolerance, options_.intermediate_tolerance);
  for (int it = 0; it <= options_.max_iterations; ++it) {
    const bool use_path = predictor && it == 0 && path_tangent_;
    if (!assemble(*u, m, &Pi, &R, !use_path, summary)) {
      summary->message = "start state of the load step has det F <= 0";
      return false;
    }
    const double rnorm = system_.norm(R);
    if (R_ref == 0.0) R_ref = rnorm;
    summary->residual = rnorm;
    summary->residual_reference = R_ref;
    summary->energy = Pi;
    NewtonIteration rec{load_step, load, it, rnorm, Pi, 0.0, 0.0, 0, false, false};
    const bool small_step = options_.displacement_tolerance == 0.0 || it == 0 ||
                            last_step <= options_.displacement_tolerance * system_.max_abs(*u);
    const bool residual_ok = rnorm <= tolerance_factor * R_ref + options_.absolute_tolerance;
    if ((residual_ok && (small_step || !final)) || rnorm == 0.0) {
      summary->iterations.push_back(rec);
      return converge(!use_path, *u, m, summary);
    }
    if (it == options_.max_iterations) {
      summary->iterations.push_back(rec);
      summary->message = "no convergence in " + std::to_string(it) + " iterations";
      return false;
    }
    ++summary->newton_iterations;
    const double tol = tolerance_factor * R_ref + options_.absolute_tolerance;
    // The serial forcing term; with CG + GAMG without its last factor (1e-3 tol/|R|, which
    // asks every direction for 1e-3 of the final tolerance: cheap for PCG with a Cholesky
    // preconditioner, about 1000 CG iterations with GAMG): η = min(forcing, |R|/R_ref)
    // still converges quadratically, and the convergence test is unchanged.
    const double eta =
        std::max(1e-14, system_.iterative()
                            ? std::min(options_.forcing, rnorm / R_ref)
                            : std::min({options_.forcing, rnorm / R_ref, 1e-3 * tol / rnorm}));
    Eigen::VectorXd du;
    const bool direction_ok = direction(R, eta, &du, &rec, summary);
    if (residual_ok && (!direction_ok || rec.shift != 0.0)) {
      // Only the step test is pending at an unstable equilibrium (as in the serial Newton).
      --summary->newton_iterations;
      rec.shift = 0.0;
      summary->iterations.push_back(rec);
      return converge(!use_path, *u, m, summary);
    }
    if (!direction_ok) {
      summary->iterations.push_back(rec);
      summary->message = "tangent could not be factorised";
      return false;
    }
    const Eigen::VectorXd u_before = *u;
    rec.step = line_search.step(du, Pi, system_.dot(R, du), rnorm, u);
    last_step = system_.max_abs(*u - u_before);
    summary->iterations.push_back(rec);
    if (options_.verbose && system_.slab().rank == 0) {
      std::cerr << "newton(petsc): step " << load_step << " load " << load << " it " << it
                << " |R| " << rnorm << " energy " << Pi << " s " << rec.step << " shift "
                << rec.shift << " krylov " << rec.krylov
                << (line_search.tentative() ? " (tentative)" : "") << "\n";
    }
    if (rec.step == 0.0) {
      summary->message = "line search failed at iteration " + std::to_string(it);
      return false;
    }
  }
  return false;
}

Eigen::VectorXd DistributedNewton::solve_converged_tangent(const Eigen::VectorXd& b) {
  if (!converged_) throw InvalidArgument("Newton (PETSc): no converged state to solve with");
  if (!path_tangent_) {
    NewtonSummary scratch;
    converge(false, last_u_, last_m_, &scratch);
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
  const Eigen::MatrixXd m0 = *state_m;
  double t = 0.0, inc = options_.initial_load_increment;
  Eigen::VectorXd u = *state_u;
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
    if (options_.path_predictor && !path_tangent_ && has_free) {
      // Tangent at the last converged state (u, m_t) for the Euler predictor.
      if (assemble(*state_u, *state_m, nullptr, nullptr, true, &summary)) path_tangent_ = true;
    }
    const int before = summary.newton_iterations;
    const bool ok = solve_load_step(m, summary.load_steps, t_try,
                                    options_.path_predictor && has_free, &u, &summary);
    ++summary.load_steps;
    if (ok) {
      t = t_try;
      *state_u = u;
      *state_m = m;
      summary.message.clear();
      if (t >= 1.0) {
        summary.status = NewtonStatus::kConverged;
        break;
      }
      if (summary.newton_iterations - before < options_.max_iterations / 2)
        inc = std::min(1.0, 2.0 * inc);
    } else {
      ++summary.failed_load_steps;
      u = *state_u;  // back to the last converged state (its tangent is assembled again)
      path_tangent_ = false;
      inc *= 0.5;
      if (inc < options_.min_load_increment) {
        summary.status = NewtonStatus::kLoadIncrementTooSmall;
        summary.message = "at load " + std::to_string(t) + ": " + summary.message;
        break;
      }
    }
  }
  converged_ = summary.converged();
  last_u_ = *state_u;
  last_m_ = *state_m;
  if (!converged_) path_tangent_ = false;
  summary.final_load = t;
  summary.seconds_total = seconds_since(t_start);
  return summary;
}

}  // namespace softhd::fe::petsc_detail
