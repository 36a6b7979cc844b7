#pragma once
// One load step of Newton–Raphson (docs/formulation.md §3.6), written once for the serial
// Newton (newton.cpp) and the distributed one of the PETSc backend (petsc/petsc_newton.cpp):
// the energy line search, the convergence test (|R|₂ <= rtol R_ref + atol and the step test
// |Δu|_∞ <= displacement_tolerance |u|_∞), the forcing terms, the unstable-equilibrium exit
// and the retry of a failed PCG direction with a fresh factorisation. Internal.
//
// What differs between the two is the linear algebra, a template parameter (resolved at
// compile time: no virtual call; the element loops stay inside Assembler::evaluate):
//
//   struct Algebra {
//     bool has_path_tangent() const;  // K at the last converged state is kept
//     // Π, R and/or the tangent K at u (tangent: K replaced; null outputs skipped). False
//     // (on every rank) if det F <= 0 somewhere.
//     bool assemble(const VectorXd& u, const MatrixXd& m, double* energy, VectorXd* R,
//                   bool tangent);
//     double norm(const VectorXd& R) const;     // |R|₂ (over the ranks)
//     double max_abs(const VectorXd& u) const;  // |u|_∞ (over the ranks)
//     double slope(const VectorXd& R, const VectorXd& du) const;  // R·du
//     bool iterative() const;  // directions by an iterative solver: no 1e-3 tol/|R| factor
//     // du with K du = −R to |K du + R| <= η |R|; K the path tangent if `path`, else the
//     // tangent assembled last. Fills rec's shift, krylov, factorized, truncated.
//     bool direction(bool path, const VectorXd& R, double R_ref, double eta, VectorXd* du,
//                    NewtonIteration* rec);
//     void drop_factorization();  // the next direction factorises afresh
//     // The load step converged at u: keep K there as the path tangent (assembled again
//     // unless `tangent_is_current`).
//     void converge(bool tangent_is_current, const VectorXd& u, const MatrixXd& m);
//     bool speaks() const;       // prints the verbose lines (rank 0)
//     const char* name() const;  // their prefix
//     // The Euler predictor's tangent at the last converged state (u, m); false if
//     // det F <= 0 there.
//     bool assemble_path_tangent(const VectorXd& u, const MatrixXd& m);
//     void load_step_failed();  // back at the last converged state
//   };

#include <Eigen/Core>
#include <algorithm>
#include <iostream>
#include <string>

#include "line_search.hpp"
#include "softhd/fe/newton.hpp"
#include "softhd/interrupt.hpp"

namespace softhd::fe {

/// Newton iterations at the load `load` (control m) from *u, with the Euler predictor's
/// path tangent as the first direction's K if `predictor`. True if converged (*u is then
/// the equilibrium and the algebra keeps its tangent); false with summary->message set.
template <class Algebra>
bool newton_load_step(Algebra& la, const NewtonOptions& options, const Eigen::MatrixXd& m,
                      int load_step, double load, bool predictor, Eigen::VectorXd* u,
                      NewtonSummary* summary) {
  Eigen::VectorXd R, R0;
  double Pi = 0.0;
  la.assemble(Eigen::VectorXd::Zero(u->size()), m, nullptr, &R0, false);
  double R_ref = la.norm(R0);
  EnergyLineSearch line_search(
      options,
      [&](const Eigen::VectorXd& v, double* e) { return la.assemble(v, m, e, nullptr, false); },
      [&](const Eigen::VectorXd& v) {
        Eigen::VectorXd Rv;
        la.assemble(v, m, nullptr, &Rv, false);
        return la.norm(Rv);
      });
  double last_step = 0.0;  // |Δu|_∞ of the last iteration
  const bool final = load >= 1.0;
  const double tolerance_factor =
      final ? options.relative_tolerance
            : std::max(options.relative_tolerance, options.intermediate_tolerance);
  for (int it = 0; it <= options.max_iterations; ++it) {
    check_interrupt("between Newton iterations");
    // The predictor's first direction uses the path tangent: K at u is not needed then.
    const bool use_path = predictor && it == 0 && la.has_path_tangent();
    if (!la.assemble(*u, m, &Pi, &R, !use_path)) {
      summary->message = "start state of the load step has det F <= 0";
      return false;
    }
    const double rnorm = la.norm(R);
    if (R_ref == 0.0) R_ref = rnorm;
    summary->residual = rnorm;
    summary->residual_reference = R_ref;
    summary->energy = Pi;
    NewtonIteration rec{load_step, load, it, rnorm, Pi, 0.0, 0.0, 0, false, false};
    const bool small_step = options.displacement_tolerance == 0.0 || it == 0 ||
                            last_step <= options.displacement_tolerance * la.max_abs(*u);
    const bool residual_ok = rnorm <= tolerance_factor * R_ref + options.absolute_tolerance;
    if ((residual_ok && (small_step || !final)) || rnorm == 0.0) {
      summary->iterations.push_back(rec);
      la.converge(!use_path, *u, m);
      return true;
    }
    if (it == options.max_iterations) {
      summary->iterations.push_back(rec);
      summary->message = "no convergence in " + std::to_string(it) + " iterations";
      return false;
    }
    ++summary->newton_iterations;
    // Forcing term η = min(forcing, |R|/R_ref, 1e-3 tol/|R|): falls like the residual
    // (quadratic convergence), and the last direction is solved to 1e-3 of the tolerance so
    // that the converged state is as accurate as after an exact Newton step. An iterative
    // solver (CG + GAMG) drops the last factor, which would ask every direction for 1e-3 of
    // the final tolerance (about 1000 CG iterations): the convergence test is unchanged.
    const double tol = tolerance_factor * R_ref + options.absolute_tolerance;
    const double eta = std::max(
        1e-14, la.iterative() ? std::min(options.forcing, rnorm / R_ref)
                              : std::min({options.forcing, rnorm / R_ref, 1e-3 * tol / rnorm}));
    Eigen::VectorXd du;
    const bool direction_ok = la.direction(use_path, R, R_ref, eta, &du, &rec);
    if (residual_ok && (!direction_ok || rec.shift != 0.0 || rec.truncated)) {
      // Only the step test is pending, and K is not positive definite here (an unstable
      // equilibrium, e.g. a compressed plate before it buckles): a Newton step would leave
      // it along a descent direction instead of confirming it. Converged at the residual.
      --summary->newton_iterations;
      rec.shift = 0.0;
      summary->iterations.push_back(rec);
      la.converge(!use_path, *u, m);
      return true;
    }
    if (!direction_ok) {
      summary->iterations.push_back(rec);
      summary->message = "tangent could not be factorised";
      return false;
    }
    const Eigen::VectorXd u_before = *u;
    rec.step = line_search.step(du, Pi, la.slope(R, du), rnorm, u);
    if (rec.step == 0.0 && !rec.factorized) {
      // The direction came from PCG with a kept factorisation: retry with K factorised.
      la.drop_factorization();
      *u = u_before;
      if (la.direction(use_path, R, R_ref, eta, &du, &rec))
        rec.step = line_search.step(du, Pi, la.slope(R, du), rnorm, u);
    }
    last_step = la.max_abs(*u - u_before);
    summary->iterations.push_back(rec);
    if (options.verbose && la.speaks()) {
      std::cerr << la.name() << ": step " << load_step << " load " << load << " it " << it
                << " |R| " << rnorm << " energy " << Pi << " s " << rec.step << " shift "
                << rec.shift << " pcg " << rec.krylov << (rec.factorized ? " factorised" : "")
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

/// The load stepping of Newton's method around newton_load_step: from the state
/// (*state_u, *state_m) towards the control m_qp, first with the load increment
/// initial_load_increment, doubled after quick steps and halved after failed ones, each step
/// started by the Euler predictor if path_predictor (and some dof is free). The state
/// follows the converged load steps. Sets summary->status; returns the load reached.
template <class Algebra>
double newton_load_stepping(Algebra& la, const NewtonOptions& options, const Eigen::MatrixXd& m_qp,
                            bool has_free, Eigen::VectorXd* state_u, Eigen::MatrixXd* state_m,
                            NewtonSummary* summary) {
  const Eigen::MatrixXd m0 = *state_m;
  double t = 0.0, inc = options.initial_load_increment;
  Eigen::VectorXd u = *state_u;
  while (true) {
    if (summary->load_steps >= options.max_load_steps) {
      summary->status = NewtonStatus::kTooManyLoadSteps;
      break;
    }
    if (summary->newton_iterations >= options.max_total_iterations) {
      summary->status = NewtonStatus::kTooManyIterations;
      break;
    }
    const double t_try = std::min(1.0, t + inc);
    const Eigen::MatrixXd m = m0 + t_try * (m_qp - m0);
    // Tangent at the last converged state (u, m_t) for the Euler predictor.
    if (options.path_predictor && !la.has_path_tangent() && has_free)
      la.assemble_path_tangent(*state_u, *state_m);
    const int before = summary->newton_iterations;
    const bool ok = newton_load_step(la, options, m, summary->load_steps, t_try,
                                     options.path_predictor && has_free, &u, summary);
    ++summary->load_steps;
    if (ok) {
      t = t_try;
      *state_u = u;
      *state_m = m;
      summary->message.clear();
      if (t >= 1.0) {
        summary->status = NewtonStatus::kConverged;
        break;
      }
      if (summary->newton_iterations - before < options.max_iterations / 2)
        inc = std::min(1.0, 2.0 * inc);
    } else {
      ++summary->failed_load_steps;
      u = *state_u;  // back to the last converged state
      la.load_step_failed();
      inc *= 0.5;
      if (inc < options.min_load_increment) {
        summary->status = NewtonStatus::kLoadIncrementTooSmall;
        summary->message = "at load " + std::to_string(t) + ": " + summary->message;
        break;
      }
    }
  }
  return t;
}

}  // namespace softhd::fe
