#pragma once
/// \file bounded_optimizer.hpp
/// Bound-constrained minimisation (docs/formulation.md §4.5, §4.5.1): MMA by default, CCSAQ,
/// L-BFGS and SLSQP (NLopt), and a trust-region Newton–CG with exact Hessian-vector products
/// (ROL's Lin–Moré); variables scaled to O(1), stopping on iterations, relative change, the
/// projected gradient, a target value and wall-clock time, and failed evaluations turned into
/// rejected steps instead of crashes.

#include <Eigen/Core>
#include <functional>
#include <limits>
#include <string>
#include <vector>

namespace softhd {

/// Algorithms for bound-constrained problems: NLopt's gradient methods MMA (the default),
/// CCSAQ, L-BFGS and SLSQP, and newton, a trust-region Newton–CG (ROL's Lin–Moré) that needs a
/// Hessian-vector product (BoundedHessVec).
enum class Algorithm { mma, ccsaq, lbfgs, slsqp, newton };

/// "mma", "ccsaq", "lbfgs", "slsqp", "newton"; algorithm_from_string throws InvalidArgument.
std::string to_string(Algorithm algorithm);
/// The Algorithm named by to_string.
Algorithm algorithm_from_string(const std::string& name);

/// One evaluation of the objective. `gradient` is null when only the value is needed.
/// Returns false if the evaluation failed (e.g. the state solve did not converge): the
/// point is then rejected and the optimiser steered back. An exception ends minimise(),
/// which rethrows it (NLopt in between never sees it).
using BoundedObjective =
    std::function<bool(const Eigen::VectorXd& x, double& value, Eigen::VectorXd* gradient)>;

/// The Hessian-vector product ∇²f(x) v into *Hv (resized by the callee). newton asks only at
/// the current iterate (the last accepted point, evaluated with its gradient), which after a
/// rejected step is not the last point evaluated: a callee that reuses the state of an
/// evaluation must keep the accepted one's. Returns false if it failed: the run then ends at
/// the best point with status hessian_failed; an exception ends minimise(), which rethrows it.
/// Needed by Algorithm::newton; the NLopt algorithms never call it.
using BoundedHessVec =
    std::function<bool(const Eigen::VectorXd& x, const Eigen::VectorXd& v, Eigen::VectorXd* Hv)>;

/// Settings of the trust-region Newton–CG (Algorithm::newton; docs/formulation.md §4.5.1), in
/// the scaled variables z = x / s and the scaled objective f̃ = f / value_scale. The first
/// three are the algorithm's state between iterations: a run restarted from an iteration's x
/// with that iteration's trust_radius and cauchy_step and the run's value_scale (all in its
/// IterationRecord and summary) continues as the uninterrupted run did.
struct TrustRegionOptions {
  /// Δ₀ (scaled variables); 0 = min(‖∇f̃(z₀)‖, Δ_max), Δ_max the move limit's bound
  /// (BoundedOptimizerOptions::move_limit; without one, ‖∇f̃(z₀)‖, ROL's default).
  double initial_radius = 0.0;
  /// α₀ of the Cauchy-point search; 0 = Δ₀/‖∇f̃(z₀)‖, the step along the gradient that reaches
  /// the initial radius (ROL's default, 1, can cost several products to reduce or extend)
  double cauchy_step = 0.0;
  double value_scale = 0.0;  ///< f̃ = f / value_scale; 0 = |f(x₀)| (1 if f(x₀) = 0)
  /// Truncated CG: at most this many iterations per step (over all faces of the box) ...
  int cg_iterations = 50;
  /// ... until the free part of the model gradient is ≤ min(cg_absolute_tolerance,
  /// cg_relative_tolerance ‖g_free‖²): the squared norm (ROL's exponent 2) keeps Newton's
  /// quadratic convergence.
  double cg_relative_tolerance = 1e-2;
  double cg_absolute_tolerance = 1e-4;  ///< see cg_relative_tolerance
  /// Stop (status no_progress) when rejected steps have shrunk the radius below this.
  double min_radius = 1e-12;

  /// Throws InvalidArgument naming the first invalid field (trust_region.…).
  void validate() const;
};

/// Settings of minimise(); defaults as documented per field (docs/formulation.md §4.5).
struct BoundedOptimizerOptions {
  Algorithm algorithm = Algorithm::mma;  ///< NLopt algorithm, or newton
  int max_iterations = 200;              ///< accepted iterations (IterationRecord)
  int max_evaluations = 1000;            ///< objective evaluations, accepted or not
  double relative_change = 1e-6;         ///< stop when |ΔJ| ≤ this × |J| between iterations
  double target_value = -std::numeric_limits<double>::infinity();  ///< stop when J ≤ this
  /// Stop (converged, status gradient_tolerance) when an iteration's projected gradient norm
  /// ‖P(z − ∇_z f̃) − z‖ (IterationRecord::projected_gradient_norm, scaled variables and value)
  /// is ≤ this; 0 = off (newton still stops where it is exactly 0).
  double gradient_tolerance = 0.0;
  double max_seconds = 0.0;  ///< wall-clock limit; 0 = none
  /// Value reported to NLopt for a failed evaluation: this factor times the largest
  /// |J| seen so far (at least 1). Large enough that MMA's conservative step shrinks.
  double failure_penalty = 10.0;
  /// Move limit: if > 0, NLopt runs in rounds of at most `round_evaluations`
  /// evaluations on the box [x − δ(u − l), x + δ(u − l)] ∩ [l, u] around the best x,
  /// δ = move_limit, halved after a round without progress. A round also ends as soon as
  /// the best point reaches a side of its box that is not a bound (the next round is
  /// centred there), so MMA does not spend evaluations on the box's own optimum. Keeps MMA's first
  /// steps (which may span half the bounds) from asking the state solver for huge deformations. 0 =
  /// one NLopt run on the whole box. For newton the trust radius is bounded instead:
  /// Δ ≤ Δ_max = move_limit ‖(u − l)/s‖₂ in the scaled variables z = x/s (0: no bound, ROL's
  /// default). Lin–Moré bounds the Cauchy step and each subspace (CG) step of an iteration by
  /// Δ, so a step's root-mean-square over the variables is of the order of move_limit × their
  /// bound range.
  double move_limit = 0.0;
  int round_evaluations = 10;  ///< evaluations per round when move_limit > 0
  /// Per variable: a factor in (0, 1] on the move limit (the box's half-width is
  /// move_limit × move_scale_k × (u_k − l_k)), e.g. to let some variables move more slowly than
  /// others. Empty (default): 1 for every variable; else one entry per variable (minimise()).
  Eigen::VectorXd move_scale;
  TrustRegionOptions trust_region;  ///< Algorithm::newton only

  /// Throws InvalidArgument naming the first invalid field.
  void validate() const;
};

/// One accepted iteration: for the NLopt algorithms an evaluation that improves the best value;
/// for newton a step the trust region accepts (J does not increase, beyond ROL's round-off
/// safeguard of 100 ε max(1, |J / value_scale|) relative to value_scale).
struct IterationRecord {
  int iteration = 0;                     ///< 1-based
  int evaluation = 0;                    ///< evaluation count when it was accepted
  double value = 0.0;                    ///< J
  double projected_gradient_norm = 0.0;  ///< ‖P(x − ∇J) − x‖ in scaled variables
  double seconds = 0.0;                  ///< wall time since the start of minimise()
  /// newton: CG iterations of this iteration's step (the accepted one); 0 for NLopt's.
  int cg_iterations = 0;
  /// newton: Hessian-vector products since the previous record (the Cauchy-point search, CG,
  /// and the steps rejected in between); 0 for NLopt's.
  int hessian_products = 0;
  /// newton: the trust radius Δ after this iteration (the next step's; scaled variables).
  double trust_radius = std::numeric_limits<double>::quiet_NaN();
  /// newton: the Cauchy-point step length α after this iteration (a restart's cauchy_step).
  double cauchy_step = std::numeric_limits<double>::quiet_NaN();
};

/// Why minimise() stopped.
enum class OptimizerStatus {
  iteration_limit,     ///< max_iterations accepted iterations
  evaluation_limit,    ///< max_evaluations evaluations
  time_limit,          ///< max_seconds of wall time
  relative_change,     ///< J changed by ≤ relative_change three iterations in a row (converged)
  target_value,        ///< J ≤ target_value (converged)
  nlopt_converged,     ///< NLopt reports convergence (converged)
  no_progress,         ///< no progress within the smallest move limit, or (newton) trust
                       ///< radius: trust_region.min_radius (converged)
  move_limit,          ///< a relative_change or no_progress stop under a move limit below
                       ///< kCertifyingMoveLimit: its steps were too short to tell a minimum
  stopped,             ///< an on_iteration observer threw StopRequest
  start_failed,        ///< the evaluation at the starting point failed
  nlopt_failure,       ///< NLopt stopped otherwise (round-off, a rejected problem; see termination)
  gradient_tolerance,  ///< the projected gradient norm fell to gradient_tolerance (converged)
  hessian_failed,      ///< newton: a Hessian-vector product failed
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
  double initial_value = 0.0;  ///< f at the start (NaN if that evaluation failed)
  double final_value = 0.0;    ///< f at the best point
  Eigen::VectorXd x;           ///< the best point found
  int iterations = 0;          ///< accepted iterations
  int evaluations = 0;         ///< objective evaluations, including the start
  int failed_evaluations = 0;  ///< evaluations that returned false (rejected points)
  int hessian_products = 0;    ///< newton: Hessian-vector products (computed)
  /// newton: products ROL asked for whose vector lay in the span of those already computed at
  /// the same point, answered from them by linearity (docs/formulation.md §4.5.1), not counted
  /// in hessian_products.
  int hessian_products_reused = 0;
  /// The f scale of the records' gradients: |f(x₀)| (1 if 0), or trust_region.value_scale.
  double value_scale = 1.0;
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
/// component (so z is O(1); newton rounds s up to a power of 2, so that x / s is exact), and f is
/// divided by |f(x0)| (or 1 if it is 0). Algorithm::newton needs `hess_vec` (the other overload:
/// InvalidArgument naming it); the NLopt algorithms ignore it.
/// `on_iteration` (optional) is called after each accepted iteration with its record
/// and the current best x; it may write a checkpoint, and throw StopRequest to end the run. Throws
/// InvalidArgument for inconsistent bounds or a start outside them (naming the component), and
/// rethrows any other exception of the objective or of `on_iteration` once NLopt has stopped
/// (NLopt would turn it into a result code).
BoundedOptimizerSummary minimise(
    const BoundedObjective& objective, const BoundedHessVec& hess_vec, const Eigen::VectorXd& x0,
    const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
    const BoundedOptimizerOptions& options = {},
    const std::function<void(const IterationRecord&, const Eigen::VectorXd&)>& on_iteration = {});

/// minimise() without a Hessian-vector product (the NLopt algorithms).
BoundedOptimizerSummary minimise(
    const BoundedObjective& objective, const Eigen::VectorXd& x0, const Eigen::VectorXd& lower,
    const Eigen::VectorXd& upper, const BoundedOptimizerOptions& options = {},
    const std::function<void(const IterationRecord&, const Eigen::VectorXd&)>& on_iteration = {});

/// ‖P(x − g) − x‖₂: the projected-gradient norm for bounds lower ≤ x ≤ upper.
double projected_gradient_norm(const Eigen::VectorXd& x, const Eigen::VectorXd& g,
                               const Eigen::VectorXd& lower, const Eigen::VectorXd& upper);

}  // namespace softhd
