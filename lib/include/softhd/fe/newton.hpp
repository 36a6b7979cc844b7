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
#include "softhd/fe/tangent_solver.hpp"

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
  /// If > 0, convergence also needs the last Newton correction to be small:
  /// |Δu|_∞ <= displacement_tolerance · |u|_∞ (the test of FEniCS-style solvers). Soft
  /// modes (a plate near buckling, a twisted beam) keep a displacement error of about
  /// |R|/λ_min after the residual test alone; this removes it at the price of about one
  /// more iteration. 0 = the residual test alone.
  double displacement_tolerance = 0.0;
  /// Relative residual at which an intermediate load step (t < 1) is accepted: the path
  /// to the final load need not be followed to the final tolerance.
  double intermediate_tolerance = 1e-9;
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
  /// state (u_t, m_t): u_t − K(u_t, m_t)⁻¹ R(u_t; m_{t+Δ}) is the first-order (Euler)
  /// predictor of the equilibrium path, since R is linear in m and R(u_t; m_t) = 0. The
  /// tangent at (u_t, m_{t+Δ}) carries the geometric stiffness of the whole unbalanced
  /// fiber tension and predicts bending of thin bodies far too stiff. The converged
  /// tangent is kept, so this costs one assembly only when a solve does not start where
  /// the previous one ended.
  bool path_predictor = true;
  /// Total load steps (successful or not) allowed in one solve.
  int max_load_steps = 400;
  /// Total Newton iterations allowed in one solve (a time budget for callers such as the
  /// optimiser; a plate bent by a full turn needs about 420). Checked between load
  /// steps, so a solve may overrun it by up to max_iterations.
  int max_total_iterations = 3000;
  /// Linear solves with the tangent: PCG preconditioned by a kept Cholesky factorisation,
  /// refactorising when it is stale (tangent_solver.hpp); `tangent.reuse_factorization =
  /// false` factorises every tangent (classical Newton). The factorisations are CHOLMOD's
  /// (supernodal, AMD ordering, chosen by measurement: bench_state solvers).
  TangentSolverOptions tangent;
  /// A Newton direction is computed to a relative residual η = min(forcing, |R|/R_ref,
  /// 1e-3 tol/|R|), tol the convergence threshold: inexact Newton whose forcing term falls
  /// like the residual (convergence stays quadratic) and whose last direction is as
  /// accurate as an exact one at the tolerance; a direct solve is exact anyway.
  double forcing = 1e-2;
  /// Relative residual of the solve with the converged tangent (the adjoint).
  double adjoint_tolerance = 1e-12;
  /// Print one line per iteration to stderr.
  bool verbose = false;

  /// Throws InvalidArgument "Newton options: <field> must be ..." naming the first
  /// inconsistent field (the tangent solver's options included).
  void validate() const;
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
  int load_step = 0;        ///< index of the load step (counting failed ones)
  double load = 0.0;        ///< fraction t of the change of m being applied
  int iteration = 0;        ///< within the load step
  double residual = 0.0;    ///< |R|₂ before the update
  double energy = 0.0;      ///< Π before the update
  double step = 0.0;        ///< accepted line-search step (0 if none)
  double shift = 0.0;       ///< diagonal shift added because K was not positive definite
  int krylov = 0;           ///< PCG iterations of the direction (0: direct solve)
  bool factorized = false;  ///< the direction came with a new factorisation
  bool truncated = false;   ///< PCG stopped at negative curvature (Newton–CG direction)
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
  int assemblies = 0;                       ///< evaluations of Π, R or K (line searches included)
  int factorizations = 0;                   ///< numeric factorisations (shift searches included)
  int krylov_iterations = 0;                ///< PCG iterations of the Newton directions
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

/// The absolute residual tolerance used when NewtonOptions::absolute_tolerance is 0 (by
/// make_state_solver and ShapeObjective): 1e-10 · stiffness · |Ω₀|^((d−1)/d), a force far
/// above the residual's round-off and far below any load that matters. Without it the
/// relative test alone fails when the load is tiny or zero (m = 0: R(0; m) is round-off,
/// and 1e-9 of round-off cannot be reached).
double residual_floor(double stiffness_scale, double volume, int dim);

/// Newton–Raphson with line search and load stepping for R(u; m) = 0 on one assembler.
class NewtonSolver {
 public:
  /// The assembler must outlive the solver. Throws InvalidArgument on invalid options.
  explicit NewtonSolver(const Assembler& assembler, NewtonOptions options = {});

  /// Moves `state` to equilibrium with `m_qp` (E by nq), starting from state->u and
  /// ramping m from state->m_qp. On failure *state is the last converged load step.
  NewtonSummary solve(const Eigen::MatrixXd& m_qp, State* state);

  /// x with K x = b on the free dofs (num_free entries) for the tangent K at the last
  /// converged state, to the relative residual adjoint_tolerance (PCG with the kept
  /// factorisation, or a factorisation of K). Throws InvalidArgument if the last solve
  /// failed, NumericalError if that tangent is not positive definite.
  Eigen::VectorXd solve_converged_tangent(const Eigen::VectorXd& b);
  /// True if the last solve converged (solve_converged_tangent is then available).
  bool converged() const { return converged_; }
  /// What the last solve_converged_tangent did.
  const TangentSolveReport& last_tangent_solve() const { return last_tangent_solve_; }
  /// The options given at construction.
  const NewtonOptions& options() const { return options_; }

 private:
  /// Newton at fixed m from *u; returns true on convergence. `predictor`: take the first
  /// direction with K_path_ (the tangent at the last converged state).
  /// The linear algebra of the shared Newton loop (newton_load_step.hpp).
  struct Algebra;
  /// Newton direction du (num_dofs) from K du = −R to the relative residual eta
  /// (`reference`: the load step's R_ref).
  bool direction(const SparseMatrix& K, const Eigen::VectorXd& R, double reference, double eta,
                 Eigen::VectorXd* du, NewtonIteration* rec, NewtonSummary* summary);
  /// Energy and/or residual and/or tangent at (u, m), timed and counted.
  bool assemble(const Eigen::VectorXd& u, const Eigen::MatrixXd& m, double* energy,
                Eigen::VectorXd* residual, SparseMatrix* tangent, NewtonSummary* summary) const;

  const Assembler& assembler_;
  NewtonOptions options_;
  TangentSolver tangent_;
  SparseMatrix K_;       ///< tangent at the current iterate
  SparseMatrix K_path_;  ///< tangent at the last converged state (last_u_, last_m_)
  bool have_path_tangent_ = false;
  bool last_truncated_ = false;  ///< the last direction was a truncated PCG one
  bool converged_ = false;
  Eigen::VectorXd last_u_;
  Eigen::MatrixXd last_m_;
  TangentSolveReport last_tangent_solve_;
};

}  // namespace softhd::fe
