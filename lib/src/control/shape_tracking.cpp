#include "softhd/control/shape_tracking.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>

#include "softhd/error.hpp"
#include "softhd/interrupt.hpp"
#include "softhd/parallel.hpp"

namespace softhd {

std::pair<double, double> shape_error(const fe::Mesh& mesh, const Eigen::VectorXd& u,
                                      const Eigen::VectorXd& u_T) {
  const int d = mesh.dim;
  if (u.size() != mesh.num_nodes() * d || u_T.size() != u.size())
    throw InvalidArgument("shape_error: displacements must have num_nodes * dim entries");
  double mx = 0.0, sum = 0.0;
  for (Eigen::Index n = 0; n < mesh.num_nodes(); ++n) {
    const double e = (u.segment(n * d, d) - u_T.segment(n * d, d)).norm();  // |x_i − T(X_i)|
    mx = std::max(mx, e);
    sum += e * e;
  }
  return {mx, std::sqrt(sum / static_cast<double>(mesh.num_nodes()))};
}

std::optional<TrackingIteration> first_below(const std::vector<TrackingIteration>& history,
                                             double k) {
  for (const TrackingIteration& it : history)  // on the user's mesh (a coarse level's floor is
    if (it.level == 0 && it.rho_over_floor <= k) return it;  // its own)
  return std::nullopt;
}

namespace {

template <class Matrix>
std::string hash_of(const Matrix& a) {
  return content_hash(a.data(), static_cast<std::size_t>(a.size()) * sizeof(a.data()[0]));
}

// Serves evaluations from a checkpoint while it lasts, then evaluates and logs them.
class Recorder {
 public:
  Recorder(ShapeObjective& objective, const ShapeTrackingOptions& options,
           const RunFingerprint& fingerprint)
      : objective_(objective), t_base_(Clock::now()) {
    if (options.checkpoint.empty()) return;
    checkpointing_ = true;
    if (options.resume) {
      log_ = read_run_log(options.checkpoint);
      check_fingerprint(log_.fingerprint, fingerprint, options.checkpoint);
    }
    // A fresh run gets a new run id and removes an earlier run's states file.
    if (options.write_checkpoint)
      writer_ = std::make_unique<RunLogWriter>(options.checkpoint, fingerprint,
                                               options.resume ? &log_ : nullptr);
  }

  bool replaying() const { return next_ < log_.evaluations.size(); }
  double seconds() const {
    return base_ + std::chrono::duration<double>(Clock::now() - t_base_).count();
  }
  std::size_t replayed() const { return std::min(next_, log_.evaluations.size()); }
  double logged_seconds() const {
    return log_.evaluations.empty() ? 0.0 : log_.evaluations.back().seconds;
  }

  /// The evaluation at x = [m; ξ]: from the log, or made (and logged); its gradient [dJ/dm;
  /// dJ/dξ].
  ShapeEvaluation evaluate(const Eigen::VectorXd& m, bool gradient, fe::State* best) {
    if (replaying()) {
      const LoggedEvaluation& e = log_.evaluations[next_];
      if (e.direction.size() != 0 || !same_bits(e.x, m) || e.gradient != gradient) mismatch();
      ++next_;
      base_ = e.seconds;
      t_base_ = Clock::now();
      return e.result;
    }
    restore(best);
    ++next_;
    const Eigen::Index np = pose_variables(objective_), nm = m.size() - np;
    LoggedEvaluation e{m, gradient, objective_.evaluate(m.head(nm), gradient, m.tail(np)), 0.0, {}};
    if (np > 0 && e.result.gradient.size() == nm) {
      e.result.gradient.conservativeResize(nm + np);
      e.result.gradient.tail(np) = e.result.pose_gradient;
      e.result.pose_gradient.resize(0);
    }
    e.seconds = seconds();
    if (writer_) writer_->append(e);
    return e.result;
  }
  /// newton's Hessian-vector product at x in the direction v: from the log, or made (and
  /// logged). False if it failed (a failed state solve at x; *failure says why).
  bool hessian_product(const Eigen::VectorXd& x, const Eigen::VectorXd& v, HessianPart part,
                       fe::State* best, Eigen::VectorXd* Hv, HessianProductStats* stats,
                       std::string* failure) {
    if (replaying()) {
      const LoggedEvaluation& e = log_.evaluations[next_];
      if (e.direction.size() == 0 || !same_bits(e.x, x) || !same_bits(e.direction, v)) mismatch();
      ++next_;
      base_ = e.seconds;
      t_base_ = Clock::now();
      *Hv = e.result.gradient;
      *failure = e.result.failure;
      return e.result.status == EvaluationStatus::ok;
    }
    restore(best);
    ++next_;
    LoggedEvaluation e{x, false, ShapeEvaluation(), 0.0, v};
    try {
      e.result.gradient = objective_.hessian_product(x, v, part, stats);
      e.result.status = EvaluationStatus::ok;
    } catch (const StateSolveError& error) {
      e.result.failure = error.what();  // status state_failed
    }
    e.seconds = seconds();
    if (writer_) writer_->append(e);
    *Hv = e.result.gradient;
    *failure = e.result.failure;
    return e.result.status == EvaluationStatus::ok;
  }
  /// After an accepted iteration on the checkpoint schedule: the warm-start states saved
  /// (when a checkpoint is written) and the solver renewed, unless still replaying.
  void snapshot(int iterations, const fe::State& best) {
    if (checkpointing_ && next_ <= log_.evaluations.size()) return;
    if (writer_) {
      RunSnapshot s;
      s.evaluations = static_cast<std::int64_t>(next_);
      s.iterations = iterations;
      s.states.assign(objective_.state_path().warm_starts().begin(),
                      objective_.state_path().warm_starts().end());
      s.best = best;
      writer_->write_states(s);
    }
    // The solver's kept factorisations are not in the checkpoint: a resumed run starts
    // here with a new solver, so the uninterrupted run does too, and so does a run that
    // saves no checkpoint (Python's, a benchmark's): a run's path does not depend on
    // whether it is saved.
    objective_.state_path().reset();
  }
  /// The warm-start states and the best state the log ended with, once replay is over.
  void restore(fe::State* best) {
    if (restored_ || !log_.has_snapshot || log_.evaluations.empty()) return;
    objective_.state_path().restore(log_.snapshot.states);
    const fe::State& b = log_.snapshot.best;
    if (b.u.size() != best->u.size() || b.m_qp.rows() != best->m_qp.rows() ||
        b.m_qp.cols() != best->m_qp.cols())
      throw InvalidArgument("the checkpoint's best state does not fit this problem");
    *best = b;
    objective_.state_path().reset();  // as the uninterrupted run did at its snapshot
    restored_ = true;
  }

 private:
  static bool same_bits(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
    return a.size() == b.size() &&
           std::memcmp(a.data(), b.data(), static_cast<std::size_t>(a.size()) * 8) == 0;
  }
  [[noreturn]] void mismatch() const {
    throw InvalidArgument("the checkpoint's evaluation " + std::to_string(next_ + 1) +
                          " is at another control than the resumed run asks for (a "
                          "different build or optimiser?); start afresh without resume");
  }
  using Clock = std::chrono::steady_clock;
  ShapeObjective& objective_;
  RunLog log_;
  std::unique_ptr<RunLogWriter> writer_;  // null if this process does not write
  bool checkpointing_ = false;            // a checkpoint is read and/or written
  std::size_t next_ = 0;                  // evaluations served or made
  double base_ = 0.0;
  Clock::time_point t_base_;
  bool restored_ = false;
};

// The record of an accepted iteration from the evaluation that produced it.
TrackingIteration record(const IterationRecord& rec, const ShapeEvaluation& last,
                         const std::optional<double>& floor) {
  TrackingIteration it;
  it.iteration = rec.iteration;
  it.evaluation = rec.evaluation;
  it.J = last.J;
  it.rho = last.rho;
  it.A = last.A;
  it.B = last.B;
  it.rho_over_floor = floor ? last.rho / *floor : std::numeric_limits<double>::quiet_NaN();
  it.projected_gradient_norm = rec.projected_gradient_norm;
  it.newton_iterations = last.newton_iterations;
  it.factorizations = last.factorizations;
  it.seconds_state = last.seconds_state;
  it.seconds_distance = last.seconds_distance;
  it.seconds_adjoint = last.seconds_adjoint;
  it.cg_iterations = rec.cg_iterations;
  it.hessian_products = rec.hessian_products;
  it.trust_radius = rec.trust_radius;
  return it;
}

// The final state (the best control's, re-solved from the nearest warm start) and the
// summary's totals.
void finish(ShapeObjective& objective, Recorder& recorder, const BoundedOptimizerSummary& r,
            const std::optional<Eigen::VectorXd>& map_displacement, int checkpoint_every,
            fe::State* best_state, ShapeTrackingSummary* s) {
  // The states at the end only on the checkpoint schedule (every checkpoint_every
  // iterations), where the uninterrupted run renews its solver too: a finished run continued
  // with a larger limit then replays to its last scheduled snapshot and recomputes the
  // iterations after it, and so is the uninterrupted run bit for bit (an extra snapshot at an
  // off-schedule end renewed the solver there, which the uninterrupted run never does).
  if (r.iterations % checkpoint_every == 0) recorder.snapshot(r.iterations, *best_state);
  // In a run resumed after its end, the states it ended with.
  recorder.restore(best_state);
  // The best control's state, evaluated again from its own state (Newton stops at once
  // there, so the final ρ̃ is the one the optimiser saw).
  const Eigen::Index np = pose_variables(objective), nm = r.x.size() - np;
  const Eigen::VectorXd m = r.x.head(nm), xi = r.x.tail(np);
  objective.state_path().remember(m, *best_state);
  const ShapeEvaluation final_eval = objective.evaluate(m, false, xi);
  if (final_eval.status != EvaluationStatus::ok)
    throw StateSolveError("the state solve at the best control failed: " + final_eval.failure);
  s->control = m;
  if (objective.pose()) {  // joint: the optimiser's ξ; projection: the final evaluation's
    s->pose_twist = final_eval.pose_twist;
    s->pose = pose_at(objective, s->pose_twist);
  }
  s->displacement = objective.state_path().last_state().u;
  s->rho_final = final_eval.rho;
  s->J_final = final_eval.J;
  s->iterations = r.iterations;
  s->evaluations = r.evaluations;
  s->failed_evaluations = r.failed_evaluations;
  s->status = r.status;
  s->termination = r.termination;
  s->replayed_evaluations = static_cast<int>(recorder.replayed());
  if (map_displacement) {
    const auto [mx, rms] =
        shape_error(objective.assembler().mesh(), s->displacement, *map_displacement);
    s->shape_error_max = mx;
    s->shape_error_rms = rms;
  }
  s->seconds = recorder.seconds();
  s->seconds_optimizer = std::max(0.0, s->seconds - s->seconds_state - s->seconds_distance -
                                           s->seconds_adjoint - s->seconds_hessian);
}

}  // namespace

RunFingerprint run_fingerprint(const ShapeObjective& objective, const Eigen::VectorXd& lower,
                               const Eigen::VectorXd& upper, const Eigen::VectorXd& m0,
                               const ShapeTrackingOptions& options) {
  RunFingerprint f = options.fingerprint;
  const fe::Mesh& mesh = objective.assembler().mesh();
  f["mesh"] = hash_of(mesh.nodes) + "/" + hash_of(mesh.elements);
  f["constraints"] = hash_of(objective.assembler().dofs().free_index);
  f["controls"] = std::to_string(m0.size()) + " values, bounds " + hash_of(lower) + "/" +
                  hash_of(upper) + ", start " + hash_of(m0);
  const PointCloud& Y = objective.target().cloud();
  f["target"] =
      std::to_string(Y.size()) + " points " + hash_of(Y.points()) + "/" + hash_of(Y.volumes());
  const ShapeObjectiveOptions& so = objective.options();
  const HausdorffOptions& h = so.hausdorff;
  f["distance"] = "alpha " + exact_text(h.params.alpha) + " beta " + exact_text(h.params.beta) +
                  " gamma " + exact_text(h.params.gamma) + " eps " + exact_text(h.params.epsilon) +
                  " method " + to_string(h.method) + " tol " + exact_text(h.tolerance);
  // Only the cell quadrature is recorded (older checkpoints are collocation's).
  if (h.quadrature == Quadrature::cells) f["distance"] += " quadrature cells";
  // Only a form other than the default is recorded (older checkpoints have no such key).
  if (so.form.sides != Sides::symmetric || so.form.cap.c != 0.0) {
    f["form"] = to_string(so.form.sides) + " cap " + exact_text(so.form.cap.c) + " q " +
                exact_text(so.form.cap.q);
    if (so.form.sides == Sides::visible)
      f["form"] += " visible " + hash_of(so.form.camera_mask.cast<double>().matrix().eval());
  }
  f["threads"] = std::to_string(resolve_threads(h.threads));
  f["objective"] = "particles " + to_string(so.particles) + " volumes " + to_string(so.volumes) +
                   " tikhonov " + exact_text(so.tikhonov_mass) + " " +
                   exact_text(so.tikhonov_gradient) + " warm starts " +
                   std::to_string(so.warm_start_states);
  if (const fe::Assembler* coarse = objective.state_path().coarse_level()) {
    f["objective"] += " coarse level " + hash_of(coarse->mesh().nodes) + " from " +
                      std::to_string(so.coarse_correction_iterations) + " iterations";
  }
  if (const std::optional<scan::Pose>& pose = so.pose) {
    const PoseBounds& b = options.pose_bounds;
    f["pose"] = to_string(so.pose_kind) + " from " + hash_of(pose->matrix()) + " bounds " +
                exact_text(b.rotation) + " " + exact_text(b.translation) + " " +
                exact_text(b.scale_min) + " " + exact_text(b.scale_max);
    if (b.move != 1.0) f["pose"] += " move " + exact_text(b.move);
    if (so.pose_method != PoseMethod::joint)  // (older checkpoints: joint, not recorded)
      f["pose"] += " method " + to_string(so.pose_method) + " tolerance " +
                   exact_text(so.pose_tolerance) + " iterations " +
                   std::to_string(so.pose_iterations);
    if (so.pose_bound)
      f["pose"] += " bound " + exact_text(so.pose_bound->rotation) + " " +
                   exact_text(so.pose_bound->translation);
    if (const std::optional<Eigen::Vector3d>& n = so.pose_table_normal)
      f["pose"] += " table normal " + exact_text((*n)[0]) + " " + exact_text((*n)[1]) + " " +
                   exact_text((*n)[2]);
  }
  f["checkpoint"] = "every " + std::to_string(options.checkpoint_every) + " iterations";
  const BoundedOptimizerOptions& o = options.optimizer;
  f["optimiser"] = to_string(o.algorithm) + " rel-tol " + exact_text(o.relative_change) +
                   " target " + exact_text(o.target_value) + " penalty " +
                   exact_text(o.failure_penalty) + " move limit " + exact_text(o.move_limit) +
                   " round " + std::to_string(o.round_evaluations);
  if (o.algorithm == Algorithm::newton) f["optimiser"] += " hessian " + to_string(options.hessian);
  return f;
}

void PoseBounds::validate() const {
  if (!(rotation > 0.0 && rotation <= M_PI))
    throw InvalidArgument("pose_bounds.rotation must be in (0, pi] radians");
  if (!(translation > 0.0 && std::isfinite(translation)))
    throw InvalidArgument("pose_bounds.translation must be finite and > 0 (a fraction of L)");
  if (!(scale_min > 0.0 && scale_min <= scale_max && std::isfinite(scale_max)))
    throw InvalidArgument("pose_bounds.scale_min, scale_max: need 0 < scale_min <= scale_max");
  if (!(move > 0.0 && move <= 1.0)) throw InvalidArgument("pose_bounds.move must be in (0, 1]");
}

namespace {

/// The bounds of ξ (docs/formulation.md §8.10): |ω_k| ≤ rotation, |v_k| ≤ translation × L and,
/// for a similarity, σ with s₀ e^{−σ} within [scale_min, scale_max].
void pose_bounds(const ShapeObjective& objective, const PoseBounds& b, Eigen::VectorXd* lower,
                 Eigen::VectorXd* upper) {
  const int np = pose_variables(objective);
  lower->resize(np);
  upper->resize(np);
  const fe::State& rest = objective.state_path().warm_starts().back().state;
  const PointCloud X = objective.moving_cloud().at(Eigen::VectorXd::Zero(rest.u.size()));
  const double L = (X.points().colwise().maxCoeff() - X.points().colwise().minCoeff()).norm();
  for (int k = 0; k < 3; ++k) {
    (*lower)[k] = -b.rotation;
    (*upper)[k] = b.rotation;
    (*lower)[3 + k] = -b.translation * L;
    (*upper)[3 + k] = b.translation * L;
  }
  if (np == 7) {
    const double s0 = objective.options().pose->s;
    (*lower)[6] = std::log(s0 / b.scale_max);
    (*upper)[6] = std::log(s0 / b.scale_min);
    if (!((*lower)[6] <= 0.0 && 0.0 <= (*upper)[6])) {
      char text[160];
      std::snprintf(text, sizeof text,
                    "pose_bounds: the start pose's scale %.10g is outside [scale_min, scale_max] "
                    "= [%.10g, %.10g]",
                    s0, b.scale_min, b.scale_max);
      throw InvalidArgument(text);
    }
  }
}

}  // namespace

void ShapeTrackingOptions::validate() const {
  optimizer.validate();
  pose_bounds.validate();
  if (!(self_floor_max_pairs >= 0.0)) throw InvalidArgument("self_floor_max_pairs must be >= 0");
  if (checkpoint_every < 1) throw InvalidArgument("checkpoint_every must be >= 1");
  if (resume && checkpoint.empty())
    throw InvalidArgument("resume needs a checkpoint file (the checkpoint field is empty)");
}

namespace {

/// The optimiser's variables x = [m; ξ] with their bounds: the control, then the pose twist
/// from 0 (the start pose) within the pose bounds, when the objective has a pose.
void joint_variables(const ShapeObjective& objective, const PoseBounds& b, Eigen::VectorXd* x0,
                     Eigen::VectorXd* lower, Eigen::VectorXd* upper) {
  const Eigen::Index nm = x0->size(), np = pose_variables(objective);
  if (np == 0) return;
  Eigen::VectorXd pl, pu;
  pose_bounds(objective, b, &pl, &pu);
  x0->conservativeResize(nm + np);
  x0->tail(np).setZero();
  lower->conservativeResize(nm + np);
  lower->tail(np) = pl;
  upper->conservativeResize(nm + np);
  upper->tail(np) = pu;
}

/// The requests of the floors (docs/formulation.md §2.2, §5.3), both in the objective's
/// distance form: the matched floor's (the body deformed by the known map, with the map's
/// visible set) and the self floor's (the target against itself, without a visible mask, which
/// marks body points: the target against itself is symmetric there).
struct FloorRequests {
  HausdorffRequest matched, self;
};
FloorRequests floor_requests(const ShapeObjective& objective,
                             const std::optional<Eigen::VectorXd>& map_displacement) {
  FloorRequests r;
  r.matched.form = objective.options().form;
  r.self.form.sides =
      r.matched.form.sides == Sides::visible ? Sides::symmetric : r.matched.form.sides;
  r.self.form.cap = r.matched.form.cap;
  if (map_displacement) r.matched.form = objective.distance_form(*map_displacement);
  return r;
}

/// The optimiser's options for this run: the pose moving slower than the control if asked,
/// and the time limit a total over the resumes.
BoundedOptimizerOptions run_optimizer_options(const ShapeTrackingOptions& options, Eigen::Index nm,
                                              Eigen::Index np, double logged_seconds) {
  BoundedOptimizerOptions opt = options.optimizer;
  if (np > 0 && options.pose_bounds.move != 1.0) {
    opt.move_scale.setOnes(nm + np);
    opt.move_scale.tail(np).setConstant(options.pose_bounds.move);
  }
  if (opt.max_seconds > 0.0) opt.max_seconds = std::max(1e-9, opt.max_seconds - logged_seconds);
  return opt;
}

}  // namespace

ShapeTrackingSummary track_shape(ShapeObjective& objective, const Eigen::VectorXd& lower,
                                 const Eigen::VectorXd& upper, const Eigen::VectorXd& m0_in,
                                 const std::optional<Eigen::VectorXd>& map_displacement,
                                 const ShapeTrackingOptions& options,
                                 const ShapeTrackingCallbacks& callbacks) {
  options.validate();
  if (options.optimizer.algorithm == Algorithm::newton && !objective.options().second_order)
    throw InvalidArgument(
        "optimizer.algorithm newton needs the objective's Hessian-vector product "
        "(ShapeObjectiveOptions::second_order)");
  const fe::Mesh& mesh = objective.assembler().mesh();
  if (map_displacement && map_displacement->size() != mesh.num_nodes() * mesh.dim)
    throw InvalidArgument("track_shape: the known map has the wrong number of entries");
  if (m0_in.size() != lower.size() || lower.size() != upper.size())
    throw InvalidArgument("track_shape: m0, lower and upper differ in size");
  const Eigen::VectorXd m0 = m0_in.cwiseMax(lower).cwiseMin(upper);
  Recorder recorder(objective, options, run_fingerprint(objective, lower, upper, m0_in, options));
  const Eigen::Index nm = m0.size(), np = pose_variables(objective);
  Eigen::VectorXd x0 = m0, x_lower = lower, x_upper = upper;
  joint_variables(objective, options.pose_bounds, &x0, &x_lower, &x_upper);

  ShapeTrackingSummary s;
  // Floors (docs/formulation.md §2.2, §5.3): the target against itself, and the body deformed
  // exactly by the known map at this discretisation. With a known map the matched floor judges
  // progress, and the self floor (M² pairs, often the most expensive evaluation of the run) is
  // only reported: computed after the run.
  const HausdorffTarget& Y = objective.target();
  const double m_points = static_cast<double>(Y.cloud().size());
  // Quadrature cells: both floors by the cell form; the self floor when the target has at most
  // twice the body's hexahedra (it then costs about two evaluations; bending's 8×: 687 s).
  const std::pair<long, long> hexahedra = objective.cell_counts();
  const bool cells = hexahedra.first > 0;
  // (none against a scan's surface, which has no cells: hexahedra.second = 0).
  const bool self_floor = cells ? hexahedra.second > 0 && hexahedra.second <= 2 * hexahedra.first
                                : m_points * m_points <= options.self_floor_max_pairs;
  const FloorRequests floors = floor_requests(objective, map_displacement);
  const auto self_rho = [&] {
    return cells ? objective.cell_rho(nullptr) : Y.evaluate(Y.cloud(), floors.self).rho;
  };
  if (self_floor && !map_displacement) s.floor_self = self_rho();
  if (map_displacement)  // with a pose: the map's body at the start pose (the true one unknown)
    s.floor_matched =
        cells ? objective.cell_rho(&*map_displacement)
              : Y.evaluate(target_frame_cloud(objective, *map_displacement), floors.matched).rho;
  const std::optional<double> floor = s.floor();

  const ShapeEvaluation start = objective.evaluate(m0, false);
  if (start.status != EvaluationStatus::ok)
    throw StateSolveError("the state solve at the starting control failed: " + start.failure);
  s.rho_start = start.rho;
  // The projection's inner minimisations start from the pose of the best control so far: the
  // start's, then each accepted iterate's (set in on_iteration, replayed ones too, so a resumed
  // run has the uninterrupted run's; docs/formulation.md §8.11).
  const bool projection = objective.pose() && np == 0;
  if (projection) objective.set_pose_warm_start(start.pose_twist);
  s.control = m0;  // the best so far
  if (callbacks.on_start) callbacks.on_start(s);

  // The objective for the optimiser, remembering the last evaluation for the records. Its
  // exceptions (and on_iteration's) end minimise(), which rethrows them.
  ShapeEvaluation last;
  fe::State best_state =
      objective.state_path().last_state();  // the state of the best control so far
  bool last_replayed = false;
  const BoundedObjective f = [&](const Eigen::VectorXd& m, double& value, Eigen::VectorXd* g) {
    check_interrupt("between optimiser evaluations");
    last_replayed = recorder.replaying();
    last = recorder.evaluate(m, g != nullptr, &best_state);
    s.seconds_state += last.seconds_state;
    s.seconds_distance += last.seconds_distance;
    s.seconds_adjoint += last.seconds_adjoint;
    s.newton_iterations += last.newton_iterations;
    s.factorizations += last.factorizations;
    if (last.status != EvaluationStatus::ok) {
      if (callbacks.on_failure && !last_replayed) callbacks.on_failure(last.failure);
      return false;
    }
    value = last.J;
    if (g) *g = last.gradient;
    return true;
  };
  // newton: H v at the accepted iterate x (objective.hessian_product re-establishes its state
  // after a rejected trial); a failed state solve there ends the run at the best point.
  const BoundedHessVec hess_vec = [&](const Eigen::VectorXd& x, const Eigen::VectorXd& v,
                                      Eigen::VectorXd* Hv) {
    check_interrupt("between Hessian-vector products");
    const bool replayed = recorder.replaying();
    HessianProductStats st;
    std::string failure;
    const bool ok = recorder.hessian_product(x, v, options.hessian, &best_state, Hv, &st, &failure);
    s.seconds_hessian += st.seconds;
    s.newton_iterations += st.newton_iterations;
    s.factorizations += st.factorizations;
    if (!ok && callbacks.on_failure && !replayed) callbacks.on_failure(failure);
    return ok;
  };
  int iterations = 0;  // accepted so far (for the message of an interrupt)
  const auto on_iteration = [&](const IterationRecord& rec, const Eigen::VectorXd& x) {
    iterations = rec.iteration;
    if (!last_replayed)
      best_state = objective.state_path().last_state();  // else restored from the log
    TrackingIteration it = record(rec, last, floor);
    it.seconds = recorder.seconds();
    it.replayed = last_replayed;
    if (objective.pose())  // the iterate's pose: joint x's ξ, projection its evaluation's
      it.pose = pose_at(objective, np > 0 ? Eigen::VectorXd(x.tail(np)) : last.pose_twist).twist();
    if (projection && last.pose_twist.size() != 0) objective.set_pose_warm_start(last.pose_twist);
    s.history.push_back(it);
    bool stop = false;
    try {
      if (callbacks.on_iteration) callbacks.on_iteration(it, x.head(nm));
    } catch (const StopRequest&) {
      stop = true;  // minimise() ends the run after this iteration
    }
    // The snapshot after the callback: an iteration in the log had its outputs written.
    if (rec.iteration % options.checkpoint_every == 0) recorder.snapshot(rec.iteration, best_state);
    if (stop) throw StopRequest{};
  };
  const BoundedOptimizerOptions opt =
      run_optimizer_options(options, nm, np, recorder.logged_seconds());
  BoundedOptimizerSummary r;
  try {
    r = opt.algorithm == Algorithm::newton
            ? minimise(f, hess_vec, x0, x_lower, x_upper, opt, on_iteration)
            : minimise(f, x0, x_lower, x_upper, opt, on_iteration);
  } catch (const Interrupted& e) {
    // The checkpoint holds every evaluation finished and the states of the last save, as
    // when the process is killed: resuming it continues the uninterrupted run.
    if (options.checkpoint.empty() || !options.write_checkpoint) throw;
    throw Interrupted(std::string(e.what()) + " after " + std::to_string(iterations) +
                      " iterations (resume from the checkpoint '" + options.checkpoint + "')");
  }
  finish(objective, recorder, r, map_displacement, options.checkpoint_every, &best_state, &s);
  if (self_floor && map_displacement) s.floor_self = self_rho();
  return s;
}

}  // namespace softhd
