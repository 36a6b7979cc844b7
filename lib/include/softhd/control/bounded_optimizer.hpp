#pragma once
/// \file bounded_optimizer.hpp
/// Bound-constrained minimisation on NLopt (docs/formulation.md §4.5): MMA by default,
/// CCSAQ, L-BFGS and SLSQP selectable, variables scaled to O(1), stopping on
/// iterations, relative change, a target value and wall-clock time, and failed
/// evaluations turned into rejected steps instead of crashes.

#include <Eigen/Core>
#include <functional>
#include <limits>
#include <string>
#include <vector>

namespace softhd {

/// NLopt gradient algorithms for bound-constrained problems: MMA (the default), CCSAQ,
/// L-BFGS and SLSQP.
enum class Algorithm { mma, ccsaq, lbfgs, slsqp };

/// "mma", "ccsaq", "lbfgs", "slsqp"; algorithm_from_string throws InvalidArgument.
std::string to_string(Algorithm algorithm);
/// The Algorithm named by to_string.
Algorithm algorithm_from_string(const std::string& name);

/// One evaluation of the objective. `gradient` is null when only the value is needed.
/// Returns false if the evaluation failed (e.g. the state solve did not converge): the
/// point is then rejected and the optimiser steered back. An exception ends minimise(),
/// which rethrows it (NLopt in between never sees it).
using BoundedObjective =
    std::function<bool(const Eigen::VectorXd& x, double& value, Eigen::VectorXd* gradient)>;

/// Settings of minimise(); defaults as documented per field (docs/formulation.md §4.5).
struct BoundedOptimizerOptions {
  Algorithm algorithm = Algorithm::mma;  ///< NLopt algorithm
  int max_iterations = 200;              ///< accepted iterations (improvements of the best value)
  int max_evaluations = 1000;            ///< objective evaluations, accepted or not
  double relative_change = 1e-6;         ///< stop when |ΔJ| ≤ this × |J| between iterations
  double target_value = -std::numeric_limits<double>::infinity();  ///< stop when J ≤ this
  double max_seconds = 0.0;                                        ///< wall-clock limit; 0 = none
  /// Value reported to NLopt for a failed evaluation: this factor times the largest
  /// |J| seen so far (at least 1). Large enough that MMA's conservative step shrinks.
  double failure_penalty = 10.0;
  /// Move limit: if > 0, NLopt runs in rounds of at most `round_evaluations`
  /// evaluations on the box [x − δ(u − l), x + δ(u − l)] ∩ [l, u] around the best x,
  /// δ = move_limit, halved after a round without progress. A round also ends as soon as
  /// the best point reaches a side of its box that is not a bound (the next round is
  /// centred there), so MMA does not spend evaluations on the box's own optimum. Keeps MMA's first
  /// steps (which may span half the bounds) from asking the state solver for huge deformations. 0 =
  /// one NLopt run on the whole box.
  double move_limit = 0.0;
  int round_evaluations = 10;  ///< evaluations per round when move_limit > 0
  /// Per variable: a factor in (0, 1] on the move limit (the box's half-width is
  /// move_limit × move_scale_k × (u_k − l_k)), e.g. to let some variables move more slowly than
  /// others. Empty (default): 1 for every variable; else one entry per variable (minimise()).
  Eigen::VectorXd move_scale;

  /// Throws InvalidArgument naming the first invalid field.
  void validate() const;
};

/// One accepted iteration.
struct IterationRecord {
  int iteration = 0;                     ///< 1-based
  int evaluation = 0;                    ///< evaluation count when it was accepted
  double value = 0.0;                    ///< J
  double projected_gradient_norm = 0.0;  ///< ‖P(x − ∇J) − x‖ in scaled variables
  double seconds = 0.0;                  ///< wall time since the start of minimise()
};

/// Why minimise() stopped.
enum class OptimizerStatus {
  iteration_limit,   ///< max_iterations accepted iterations
  evaluation_limit,  ///< max_evaluations evaluations
  time_limit,        ///< max_seconds of wall time
  relative_change,   ///< J changed by ≤ relative_change three iterations in a row (converged)
  target_value,      ///< J ≤ target_value (converged)
  nlopt_converged,   ///< NLopt reports convergence (converged)
  no_progress,       ///< no progress within the smallest move limit (converged)
  move_limit,        ///< a relative_change or no_progress stop under a move limit below
                     ///< kCertifyingMoveLimit: its steps were too short to tell a minimum
  stopped,           ///< an on_iteration observer threw StopRequest
  start_failed,      ///< the evaluation at the starting point failed
  nlopt_failure,     ///< NLopt stopped otherwise (round-off, a rejected problem; see termination)
};

/// The smallest move limit whose tolerance stops (relative_change, no_progress) count as
/// converged: under a smaller one every step is so short that a small change of J, or none,
/// does not tell a minimum (status move_limit; docs/formulation.md §4.5).
constexpr double kCertifyingMoveLimit = 1e-3;

/// "iteration_limit", "relative_change", ...: the enumerator's name.
std::string to_string(OptimizerStatus status);
/// True for the statuses that mean a tolerance or the target value was reached.
bool is_converged(OptimizerStatus status);

/// What minimise() did: why it stopped, the best point and the accepted iterations.
struct BoundedOptimizerSummary {
  OptimizerStatus status = OptimizerStatus::nlopt_failure;  ///< why it stopped
  std::string termination;                                  ///< why it stopped, one line
  double initial_value = 0.0;            ///< f at the start (NaN if that evaluation failed)
  double final_value = 0.0;              ///< f at the best point
  Eigen::VectorXd x;                     ///< the best point found
  int iterations = 0;                    ///< accepted iterations
  int evaluations = 0;                   ///< objective evaluations, including the start
  int failed_evaluations = 0;            ///< evaluations that returned false (rejected points)
  double seconds = 0.0;                  ///< wall time of minimise()
  std::vector<IterationRecord> history;  ///< one record per accepted iteration

  /// Stopped on a tolerance or the target value, not on a limit: is_converged(status).
  bool converged() const { return is_converged(status); }
  /// One line: status, iterations, evaluations, J from start to end, time.
  std::string BriefReport() const;
};

/// Thrown by an `on_iteration` observer of minimise() to end the run after that iteration:
/// minimise() then returns normally, with the termination "stopped by the caller" and
/// converged false. A signal, not an error (not derived from std::exception).
struct StopRequest {};

/// Minimises f(x) subject to lower ≤ x ≤ upper.
///
/// Internally the variables are z = x / s with s = max(|lower|, |upper|) per
/// component (so z is O(1)), and f is divided by |f(x0)| (or 1 if it is 0).
/// `on_iteration` (optional) is called after each accepted iteration with its record
/// and the current best x; it may write a checkpoint, and throw StopRequest to end the run. Throws
/// InvalidArgument for inconsistent bounds or a start outside them (naming the component), and
/// rethrows any other exception of the objective or of `on_iteration` once NLopt has stopped
/// (NLopt would turn it into a result code).
BoundedOptimizerSummary minimise(
    const BoundedObjective& objective, const Eigen::VectorXd& x0, const Eigen::VectorXd& lower,
    const Eigen::VectorXd& upper, const BoundedOptimizerOptions& options = {},
    const std::function<void(const IterationRecord&, const Eigen::VectorXd&)>& on_iteration = {});

/// ‖P(x − g) − x‖₂: the projected-gradient norm for bounds lower ≤ x ≤ upper.
double projected_gradient_norm(const Eigen::VectorXd& x, const Eigen::VectorXd& g,
                               const Eigen::VectorXd& lower, const Eigen::VectorXd& upper);

}  // namespace softhd
