#pragma once
/// \file shape_tracking.hpp
/// One shape-tracking run (docs/formulation.md §4): the floors, the optimisation of J(m)
/// on the bounded optimiser, per-iteration records with stage timings, and the true shape error
/// where the target comes from a known map T. TrackingRun (tracking_run.hpp) sets a run up
/// around it for the CLI, Python and the benchmarks.

#include <Eigen/Core>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "softhd/control/bounded_optimizer.hpp"
#include "softhd/control/run_log.hpp"
#include "softhd/control/shape_objective.hpp"
#include "softhd/fe/mesh.hpp"

namespace softhd {

/// One accepted iteration, with the stage timings of the evaluation that produced it.
struct TrackingIteration {
  ///@{
  /// Iteration number and evaluation count (1-based, continued after a resume).
  int iteration = 0, evaluation = 0;
  ///@}
  ///@{
  /// J, ρ̃, A and B of the accepted evaluation.
  double J = 0.0, rho = 0.0, A = 0.0, B = 0.0;
  ///@}
  /// ρ̃ / matched floor (self floor without a known map); NaN if neither is known (no
  /// map, and the self floor skipped for a huge target).
  double rho_over_floor = 0.0;
  double projected_gradient_norm = 0.0;  ///< in the optimiser's scaled variables
  int newton_iterations = 0;             ///< of this evaluation's state solve
  int factorizations = 0;                ///< numeric factorisations (state solve and adjoint)
  ///@{
  /// newton (IterationRecord): CG iterations of the accepted step, Hessian-vector products
  /// since the previous iteration, and the trust radius after it (scaled variables); 0, 0, NaN
  /// for the other algorithms.
  int cg_iterations = 0, hessian_products = 0;
  double trust_radius = std::numeric_limits<double>::quiet_NaN();
  ///@}
  ///@{
  /// Wall time (seconds) of this evaluation's state solve, distance and adjoint.
  double seconds_state = 0.0, seconds_distance = 0.0, seconds_adjoint = 0.0;
  ///@}
  double seconds = 0.0;   ///< wall time of the run (over all resumes)
  bool replayed = false;  ///< served from the checkpoint of a resumed run (no state at hand)
  /// The multilevel level (TrackingRunOptions::Levels): how many times the user's mesh was
  /// halved for it, 0 on the user's mesh.
  int level = 0;
  /// With a pose (docs/formulation.md §8.10): the twist (ω, t, log s) of the best pose P so far
  /// (scan::Pose::twist, 7 entries); empty otherwise.
  Eigen::VectorXd pose;
};

/// Bounds of the pose twist ξ = (ω, v[, σ]) of a joint run (docs/formulation.md §8.10); ξ = 0
/// (the start pose) must lie inside them.
struct PoseBounds {
  double rotation = 0.5;      ///< |ω_k| ≤ this (radians)
  double translation = 0.25;  ///< |v_k| ≤ this × L (L: the rest cloud's bounding-box diagonal)
  ///@{
  /// Similarity only: the scale s of P_ξ (scan → body) within [scale_min, scale_max], i.e.
  /// σ within [log(s₀/scale_max), log(s₀/scale_min)] (s₀: the start's scale).
  double scale_min = 0.5, scale_max = 2.0;
  ///@}
  /// The pose's move limit as a fraction of the control's (BoundedOptimizerOptions::move_scale
  /// of the pose variables), in (0, 1]: 1 (default) moves both by the same fraction of their
  /// range; smaller lets the control bend before the pose turns (docs/formulation.md §8.10).
  double move = 1.0;
  /// Throws InvalidArgument naming the first invalid field.
  void validate() const;
};

/// Settings of track_shape(); defaults per field.
struct ShapeTrackingOptions {
  BoundedOptimizerOptions optimizer;  ///< algorithm, stopping, move limit
  /// Algorithm::newton: the part of ShapeObjective::hessian_product it uses (the objective
  /// must have ShapeObjectiveOptions::second_order).
  HessianPart hessian = HessianPart::full;
  /// The self floor ρ̃(Ω_d, Ω_d) costs M² pairs: skipped (nullopt) above this many, e.g. for a
  /// 1e6-point scan (1e12 pairs, ~20 minutes on 2 cores). The default costs ~15 s.
  double self_floor_max_pairs = 1e10;
  /// Checkpoint log (run_log.hpp) written as the run goes; empty: none.
  std::string checkpoint;
  /// False: the checkpoint is read (resume) but never written, and the run behaves
  /// otherwise as if it were (the solver renewed at each save): the other ranks of an MPI
  /// run, where rank 0 alone writes (default true).
  bool write_checkpoint = true;
  /// The warm-start states are saved every this many iterations (and at the end); a
  /// resume continues from the last save, recomputing the evaluations after it. Each save
  /// renews the state solver (its kept factorisation is not saved), which costs a
  /// factorisation, hence not every iteration. A run without a checkpoint renews it on the
  /// same schedule, so its path is the saved run's.
  int checkpoint_every = 5;
  /// Continue the run recorded in `checkpoint`: the optimiser starts again and its
  /// evaluations are served from the log (bitwise, x checked) until it runs out, so the
  /// resumed run is the uninterrupted one, and the stopping limits (iterations,
  /// evaluations, wall clock) count over the whole run. A checkpoint whose fingerprint
  /// differs is refused (InvalidArgument naming the key); a malformed one (FileError).
  bool resume = false;
  /// The caller's part of the fingerprint (e.g. a content hash of the scene file);
  /// track_shape adds the mesh, controls, target, objective and optimiser settings.
  RunFingerprint fingerprint;
  /// With an objective that has a pose: the bounds of its twist ξ, which joins the optimiser's
  /// variables as [m; ξ] (the optimiser scales each variable by its bound, so its move limit is
  /// the same fraction of the range for both).
  PoseBounds pose_bounds;

  /// Throws InvalidArgument naming the first invalid field (the optimiser's included).
  void validate() const;
};

/// The result of track_shape(): floors, final values, why it stopped, the shape error and
/// the time split (docs/formulation.md §5.3).
struct ShapeTrackingSummary {
  double rho_start = 0.0;               ///< ρ̃ at the starting control
  std::optional<double> floor_self;     ///< ρ̃(Ω_d, Ω_d), unless skipped (see options)
  std::optional<double> floor_matched;  ///< ρ̃(T(Ω₀), Ω_d), with a known map
  /// The floor progress is judged against: matched, else self, else none.
  std::optional<double> floor() const { return floor_matched ? floor_matched : floor_self; }
  ///@{
  /// ρ̃ and J at the best control.
  double rho_final = 0.0, J_final = 0.0;
  ///@}
  ///@{
  /// Accepted iterations, evaluations and failed evaluations, over all resumes.
  int iterations = 0, evaluations = 0, failed_evaluations = 0;
  ///@}
  OptimizerStatus status = OptimizerStatus::nlopt_failure;  ///< why the optimiser stopped
  std::string termination;                                  ///< why the optimiser stopped, one line
  ///@{
  /// Max and RMS of |x_i − T(X_i)| over the nodes (with a known map only).
  std::optional<double> shape_error_max, shape_error_rms;
  ///@}
  double seconds = 0.0;  ///< wall time over all resumes
  ///@{
  /// Total wall time (seconds) of the state solves, distances and adjoints.
  double seconds_state = 0.0, seconds_distance = 0.0, seconds_adjoint = 0.0;
  ///@}
  /// newton: total wall time (seconds) of the Hessian-vector products (re-established states
  /// included); 0 for the other algorithms.
  double seconds_hessian = 0.0;
  double seconds_optimizer = 0.0;  ///< the rest: the optimiser, records, callbacks
  int newton_iterations = 0;       ///< over all state solves of this run
  int factorizations = 0;          ///< numeric factorisations (state solves and adjoints)
  Eigen::VectorXd control;         ///< the best m found
  /// With a pose: the best twist ξ found and its pose P_ξ (scan → body); else empty / nullopt.
  Eigen::VectorXd pose_twist;
  std::optional<scan::Pose> pose;          ///< see pose_twist
  Eigen::VectorXd displacement;            ///< its state u
  std::vector<TrackingIteration> history;  ///< accepted iterations (replayed ones included)
  int replayed_evaluations = 0;            ///< served from the checkpoint

  /// Stopped on a tolerance, not on a limit: is_converged(status).
  bool converged() const { return is_converged(status); }
  /// One line: status, iterations, evaluations, ρ̃ from start to end (and over the floor), time.
  std::string BriefReport() const;
};

/// Max and RMS over the nodes of |x_i − T(X_i)| = |u_i − u_T,i| (node-major vectors).
std::pair<double, double> shape_error(const fe::Mesh& mesh, const Eigen::VectorXd& u,
                                      const Eigen::VectorXd& u_T);

/// Optional observers of a run.
struct ShapeTrackingCallbacks {
  /// After the start state is solved and the floors are known (history still empty; control
  /// the start, clamped to the bounds).
  std::function<void(const ShapeTrackingSummary&)> on_start;
  /// After each accepted iteration, with the best control so far. Throwing StopRequest
  /// ends the run after this iteration (termination "stopped by the caller").
  std::function<void(const TrackingIteration&, const Eigen::VectorXd& m)> on_iteration;
  /// A failed state solve (the step is rejected and the run goes on).
  std::function<void(const std::string& report)> on_failure;
};

/// The fingerprint track_shape records for a run (the caller's entries plus its own).
RunFingerprint run_fingerprint(const ShapeObjective& objective, const Eigen::VectorXd& lower,
                               const Eigen::VectorXd& upper, const Eigen::VectorXd& m0,
                               const ShapeTrackingOptions& options);

/// Minimises J(m) over lower ≤ m ≤ upper from m0 (clamped into the bounds); with a pose in the
/// objective, J(m, ξ) jointly, ξ from 0 within options.pose_bounds (the callbacks see m only).
/// `map_displacement` (optional) is u_T = T(X) − X at the nodes, for the matched floor and
/// the shape error. Throws StateSolveError if the state solve fails at m0 or at the best
/// control; the callbacks' exceptions (other than StopRequest) and Interrupted end the run and
/// propagate (through minimise(), which owns them while NLopt runs).
ShapeTrackingSummary track_shape(ShapeObjective& objective, const Eigen::VectorXd& lower,
                                 const Eigen::VectorXd& upper, const Eigen::VectorXd& m0,
                                 const std::optional<Eigen::VectorXd>& map_displacement,
                                 const ShapeTrackingOptions& options = {},
                                 const ShapeTrackingCallbacks& callbacks = {});

/// Time (seconds of the history) and iteration at which ρ̃ first fell to k × floor on the
/// user's mesh (level 0), or nullopt if it never did.
std::optional<TrackingIteration> first_below(const std::vector<TrackingIteration>& history,
                                             double k);

}  // namespace softhd
