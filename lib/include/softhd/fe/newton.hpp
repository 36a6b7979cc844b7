#pragma once
/// \file newton.hpp
/// Newton–Raphson for the equilibrium R(u; m) = 0 (docs/formulation.md §3.6): energy-based
/// backtracking line search that never accepts det F <= 0 at a quadrature point, adaptive load
/// stepping on m when a load step fails, warm start from any state, and the factorisation of the
/// converged tangent kept for the adjoint. Non-convergence is a status in the summary,
/// never an exception; misuse (wrong sizes, invalid options) throws InvalidArgument.

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "softhd/fe/assembly.hpp"
#include "softhd/fe/linear_solver.hpp"

namespace softhd::fe {

/// Settings of NewtonSolver; defaults per field (docs/formulation.md §3.6).
struct NewtonOptions {
  /// Newton iterations allowed per load step.
  int max_iterations = 25;
  /// Converged when |R|₂ <= relative_tolerance · R_ref + absolute_tolerance, with R_ref =
  /// |R(0; m)|₂ (the unbalanced fiber force of the load step), or |R(u₀; m)|₂ if that is 0.
  double relative_tolerance = 1e-9;
  /// The absolute part of the test above (a force).
  double absolute_tolerance = 0.0;
  /// Armijo constant c of Π(u + s du) <= Π(u) + c s R·du.
  double armijo = 1e-4;
  /// Step shrink factor and maximum number of shrinks of the line search.
  double backtrack = 0.5;
  /// See backtrack.
  int max_line_search_steps = 40;
  /// Nonmonotone (watchdog) line search: a full step that raises the energy is taken
  /// tentatively and kept only if the next full step ends below the Armijo line of the
  /// point before it; otherwise the line search backtracks from that point.
  bool watchdog = true;
  /// First load increment (fraction of the change of m from the start state) and the
  /// smallest one tried before giving up; increments halve on failure and double after
  /// a step that converged in fewer than max_iterations / 2 iterations.
  double initial_load_increment = 1.0;
  /// See initial_load_increment.
  double min_load_increment = 1.0 / 4096.0;
  /// Take the first iteration of each load step with the tangent at the last converged
  /// state (u_t, m_t): the Euler predictor along the equilibrium path. The tangent at
  /// (u_t, m_{t+Δ}) carries the geometric stiffness of the whole unbalanced fiber tension
  /// and predicts bending of thin bodies far too stiff. Costs one factorisation per
  /// load step (shared with the adjoint's) and one at the start unless the previous
  /// solve ended at the start state.
  bool path_predictor = true;
  /// Total load steps (successful or not) allowed in one solve.
  int max_load_steps = 400;
  /// Total Newton iterations allowed in one solve (a time budget for callers such as the
  /// optimiser; the full-turn plate of issue 4 needs about 420). Checked between load
  /// steps, so a solve may overrun it by up to max_iterations.
  int max_total_iterations = 3000;
  /// Sparse direct solver. CHOLMOD (supernodal, here with Debian's reference BLAS): on the
  /// bending mesh (16 500 dofs) Eigen's LDLT factorises in 0.31 s CPU against 0.39 s, on
  /// the mesh 2x finer in each direction (113 400 dofs) CHOLMOD takes 15.8 s against 60.2 s
  /// (bench_state solvers 1 | 2), so CHOLMOD is the default that scales.
  LinearSolverType linear_solver = LinearSolverType::kCholmod;
  /// Factorise the tangent at the converged state (needed by the adjoint).
  bool factorize_converged_tangent = true;
  /// Print one line per iteration to stderr.
  bool verbose = false;

  /// True if the options are consistent; otherwise false with a message in *error.
  bool IsValid(std::string* error) const;
};

/// How a Newton solve ended.
enum class NewtonStatus {
  kConverged,
  kLoadIncrementTooSmall,  ///< a load step failed with the smallest increment
  kTooManyLoadSteps,
  kTooManyIterations,  ///< max_total_iterations reached
};
/// A short name of the status.
std::string to_string(NewtonStatus status);

/// One Newton iteration.
struct NewtonIteration {
  int load_step = 0;      ///< index of the load step (counting failed ones)
  double load = 0.0;      ///< fraction t of the change of m being applied
  int iteration = 0;      ///< within the load step
  double residual = 0.0;  ///< |R|₂ before the update
  double energy = 0.0;    ///< Π before the update
  double step = 0.0;      ///< accepted line-search step (0 if none)
  double shift = 0.0;     ///< diagonal shift added because K was not positive definite
};

/// The result of NewtonSolver::solve: status, counts, residuals and timings.
struct NewtonSummary {
  NewtonStatus status = NewtonStatus::kConverged;  ///< converged, or why not
  int newton_iterations = 0;                       ///< total, over all load steps
  int load_steps = 0;                              ///< attempted (successful + failed)
  int failed_load_steps = 0;        ///< load steps that did not converge (then halved)
  double final_load = 0.0;          ///< fraction of the change of m reached (1 on success)
  double residual = 0.0;            ///< final |R|₂
  double residual_reference = 0.0;  ///< R_ref of the convergence test
  double energy = 0.0;              ///< final Π
  ///@{
  /// Wall time (seconds) of assembly, factorisations, solves and the whole solve.
  double seconds_assembly = 0.0, seconds_factorization = 0.0, seconds_solve = 0.0,
         seconds_total = 0.0;
  ///@}
  int factorizations = 0;                   ///< numeric factorisations made
  std::vector<NewtonIteration> iterations;  ///< one record per Newton iteration
  std::string message;                      ///< why a failure happened

  /// True if status is kConverged.
  bool converged() const { return status == NewtonStatus::kConverged; }
  /// One line: status, iterations, load steps, residual, time.
  std::string BriefReport() const;
  /// BriefReport plus the residual history per load step.
  std::string FullReport() const;
};

/// A displacement (all num_dofs entries, fixed ones zero) in equilibrium with m_qp.
struct State {
  Eigen::VectorXd u;     ///< displacement, num_dofs entries
  Eigen::MatrixXd m_qp;  ///< the control at the quadrature points, E by nq
};

/// The reference state u = 0, m = 0 of an assembler (a valid cold start).
State rest_state(const Assembler& assembler);

/// Newton–Raphson with line search and load stepping for R(u; m) = 0 on one assembler.
class NewtonSolver {
 public:
  /// The assembler must outlive the solver. Throws InvalidArgument on invalid options.
  explicit NewtonSolver(const Assembler& assembler, NewtonOptions options = {});

  /// Moves `state` to equilibrium with `m_qp` (E by nq), starting from state->u and
  /// ramping m from state->m_qp. On failure *state is the last converged load step.
  NewtonSummary solve(const Eigen::MatrixXd& m_qp, State* state);

  /// The factorisation of the tangent at the last converged state, or null if the last
  /// solve failed or factorize_converged_tangent is off.
  const LinearSolver* converged_factorization() const {
    return factorization_valid_ ? solver_.get() : nullptr;
  }
  /// The options given at construction.
  const NewtonOptions& options() const { return options_; }

 private:
  /// Newton at fixed m from *u; returns true on convergence.
  bool solve_load_step(const Eigen::MatrixXd& m, int load_step, double load, Eigen::VectorXd* u,
                       NewtonSummary* summary);
  /// Backtracking from u0 along du starting at step s; sets *u and returns the accepted
  /// step, or 0 (u untouched) if none.
  double backtrack(const Eigen::MatrixXd& m, const Eigen::VectorXd& u0, double Pi0, double slope,
                   const Eigen::VectorXd& du, double s, double rnorm, Eigen::VectorXd* u,
                   NewtonSummary* summary) const;
  /// Factorises K (shifting its diagonal until positive definite); returns the shift.
  double factorize_with_fallback(NewtonSummary* summary);

  const Assembler& assembler_;
  NewtonOptions options_;
  std::unique_ptr<LinearSolver> solver_;
  SparseMatrix K_, shifted_;
  std::vector<int> diagonal_;  ///< index of each diagonal entry in K_'s values
  bool factorization_valid_ = false;
  /// solver_ holds the factorisation at the last converged state (last_u_, last_m_).
  bool have_path_tangent_ = false;
  Eigen::VectorXd last_u_;
  Eigen::MatrixXd last_m_;
};

}  // namespace softhd::fe
