#include "softhd/control/tracking_run.hpp"

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <system_error>

#include "../common/decimal.hpp"
#include "multilevel.hpp"
#include "run_files.hpp"
#include "softhd/control/run_log.hpp"
#include "softhd/enum_names.hpp"
#include "softhd/error.hpp"
#include "softhd/fe/grid_sequencing.hpp"
#include "softhd/fe/state_equation.hpp"
#include "softhd/io/folder_lock.hpp"

namespace softhd {

namespace fs = std::filesystem;
using detail::decimal;

namespace {

constexpr EnumNames<CoarseLevel, 2> kCoarseLevelNames{
    {{CoarseLevel::automatic, "auto"}, {CoarseLevel::off, "0"}}};

// The content hash of a file's bytes (empty if it cannot be read): the fingerprint's "scene".
std::string file_hash(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  const std::string bytes = s.str();
  return content_hash(bytes.data(), bytes.size());
}

// The options checked against the scene and the target: optimiser.initial_control's length and
// bounds (those of track_shape: control.lower/upper where a control acts, 0 elsewhere),
// pose.move and pose.method (a camera-frame target's only; pose.move the joint pose's).
void check_against_scene(const Scene& scene, const fe::ControlSpace& control,
                         const SceneTarget& target, const TrackingRunOptions& o) {
  if (o.optimiser.initial_control) {
    const Eigen::VectorXd& m = *o.optimiser.initial_control;
    if (m.size() != control.size())
      throw InvalidArgument("optimiser.initial_control has " + std::to_string(m.size()) +
                            " values, expected " + std::to_string(control.size()) +
                            " (the scene's controls)");
    const Eigen::VectorXd lower = control.constant(scene.body.control_lower);
    const Eigen::VectorXd upper = control.constant(scene.body.control_upper);
    for (Eigen::Index k = 0; k < m.size(); ++k)
      if (!(m[k] >= lower[k] && m[k] <= upper[k]))
        throw InvalidArgument("optimiser.initial_control[" + std::to_string(k) +
                              "] = " + decimal(m[k]) + " is outside its bounds [" +
                              decimal(lower[k]) + ", " + decimal(upper[k]) +
                              "] (the scene's control.lower and control.upper; 0 and 0 where the "
                              "control acts on no region)");
  }
  if (o.pose.move != 1.0 && target.frame != TargetFrame::camera)
    throw InvalidArgument(
        "pose.move moves the pose of a target in the camera's frame; this target is in the "
        "body's frame (it has no pose)");
  if (o.pose.method != PoseMethod::joint && target.frame != TargetFrame::camera)
    throw InvalidArgument(
        "pose.method finds the pose of a target in the camera's frame; this target is in the "
        "body's frame (it has no pose)");
  if (target.pose_uncertainty && o.pose.method != PoseMethod::projection)
    throw InvalidArgument(
        "target.pose_uncertainty bounds the pose found by projection: give pose.method "
        "projection");
  if (target.fixture && o.pose.method != PoseMethod::projection)
    throw InvalidArgument(
        "target.fixture constrains the pose found by projection: give pose.method projection");
  if (o.pose.method == PoseMethod::projection && o.pose.move != 1.0)
    throw InvalidArgument(
        "pose.move is the joint pose's move limit; with pose.method projection the optimiser "
        "has no pose variables (leave pose.move at 1)");
}

void validate_levels(const TrackingRunOptions::Levels& levels) {
  if (levels.count < 0)
    throw InvalidArgument("levels.count must be >= 1 (0: automatic), got " +
                          std::to_string(levels.count));
  if (levels.coarse_iterations < 1)
    throw InvalidArgument("levels.coarse_iterations must be >= 1, got " +
                          std::to_string(levels.coarse_iterations));
  if (!(levels.switch_decrease >= 0.0 && levels.switch_decrease < 1.0))
    throw InvalidArgument("levels.switch_decrease must be in [0, 1)");
  if (!(levels.coarse_tolerance > 0.0 && levels.coarse_tolerance < 1.0))
    throw InvalidArgument("levels.coarse_tolerance must be in (0, 1)");
  if (!(levels.refined_move_limit >= 0.0 && levels.refined_move_limit <= 1.0))
    throw InvalidArgument("levels.refined_move_limit must be in [0, 1]");
}

// The distance's form of the options (distance.form): the one a run can use.
void validate_form(const TargetDistance& d) {
  if (d.sides == Sides::visible)
    throw InvalidArgument(
        "distance.form.sides visible needs the camera's position, which a tracking run "
        "cannot give yet; use symmetric or scan_to_body");
  if (!(std::isfinite(d.cap) && d.cap >= 0.0))
    throw InvalidArgument("distance.form.cap must be 0 (none) or finite and > 0");
  if (!(std::isfinite(d.cap_q) && d.cap_q >= SoftCap::kMinQ))
    throw InvalidArgument("distance.form.cap_q must be finite and >= 0.001, got " +
                          decimal(d.cap_q));
  if (!(d.cap_quantile >= 0.0 && d.cap_quantile <= 1.0))
    throw InvalidArgument("distance.form.cap_quantile must be in [0, 1]");
  if (!(std::isfinite(d.cap_factor) && d.cap_factor >= 0.0))
    throw InvalidArgument("distance.form.cap_factor must be 0 (no rule) or finite and > 0");
}

}  // namespace

std::string to_string(CoarseLevel level) { return enum_name(kCoarseLevelNames, level); }

CoarseLevel coarse_level_from_string(const std::string& name) {
  return enum_from_name(kCoarseLevelNames, name, "state.coarse_levels");
}

void TrackingRunOptions::validate() const {
  const Optimiser& op = optimiser;
  if (op.max_iterations < 1)
    throw InvalidArgument("optimiser.max_iterations must be >= 1, got " +
                          std::to_string(op.max_iterations));
  if (op.max_evaluations < 0)
    throw InvalidArgument(
        "optimiser.max_evaluations must be >= 0 (0: 5 x max_iterations + 20), got " +
        std::to_string(op.max_evaluations));
  if (distance.method == Method::nearest)
    throw InvalidArgument("distance.method: nearest has no gradient; expected exact or tree");
  if (op.hessian != HessianPart::full && op.algorithm != Algorithm::newton)
    throw InvalidArgument("optimiser.hessian " + to_string(op.hessian) +
                          " is a setting of optimiser.algorithm newton (got " +
                          to_string(op.algorithm) + ")");
  // The state's second-order side exists for the serial Newton (fe::StateSolver) only.
  if (op.algorithm == Algorithm::newton && state.backend != fe::StateBackend::kCholmod)
    throw InvalidArgument("state.backend " + fe::to_string(state.backend) +
                          ": optimiser.algorithm newton needs the cholmod backend (its "
                          "Hessian-vector product)");
  if (output.vtu_every < 0) throw InvalidArgument("output.vtu_every must be >= 0");
  if (!(memory_limit > 0.0)) throw InvalidArgument("memory_limit must be > 0");
  validate_levels(levels);
  if (output.resume && output.folder.empty())
    throw InvalidArgument("output.resume needs the run's folder (output.folder is empty)");
  if (op.initial_control && levels.count > 1)
    throw InvalidArgument(
        "optimiser.initial_control: a multilevel run (levels.count > 1) starts from its coarse "
        "levels' control; give levels.count 1");
  if (op.initial_control && op.initial_control->size() == 0)
    throw InvalidArgument(
        "optimiser.initial_control is empty: give one value per control (or none for the "
        "scene's control.initial)");
  if (op.initial_control && !op.initial_control->allFinite())
    throw InvalidArgument("optimiser.initial_control must be finite");
  if (!(pose.move > 0.0 && pose.move <= 1.0))
    throw InvalidArgument("pose.move must be in (0, 1] (the pose's move limit over the control's)");
  if (distance.form) validate_form(*distance.form);
  objective().validate();
  tracking().validate();
}

double TrackingRunOptions::Distance::beta_for(Sides sides) const {
  if (params.beta != 0.0) return params.beta;  // as given (validated by the objective)
  return sides == Sides::symmetric ? 4.0 : kScanFormBeta;
}

ShapeObjectiveOptions TrackingRunOptions::objective() const {
  ShapeObjectiveOptions o;
  o.hausdorff.params = distance.params;
  o.hausdorff.params.beta =
      distance.beta_for(distance.form ? distance.form->sides : Sides::symmetric);
  o.hausdorff.method = distance.method;
  o.hausdorff.tolerance = distance.tolerance;
  o.hausdorff.threads = threads;
  o.hausdorff.share = share;
  o.particles = distance.particles;
  o.volumes = distance.volumes;
  o.tikhonov_mass = tikhonov.mass;
  o.tikhonov_gradient = tikhonov.gradient;
  o.second_order = optimiser.algorithm == Algorithm::newton;  // MMA's evaluations pay nothing
  o.pose_method = pose.method;
  return o;
}

ShapeTrackingOptions TrackingRunOptions::tracking() const {
  ShapeTrackingOptions t;
  BoundedOptimizerOptions& o = t.optimizer;
  o.algorithm = optimiser.algorithm;
  o.max_iterations = optimiser.max_iterations;
  // A failed or repeated evaluation per step, and more.
  const long evaluations = 5L * optimiser.max_iterations + 20;
  o.max_evaluations = optimiser.max_evaluations > 0
                          ? optimiser.max_evaluations
                          : static_cast<int>(std::min<long>(INT_MAX, evaluations));
  o.max_seconds = optimiser.max_seconds;
  o.relative_change = optimiser.relative_change;
  o.move_limit = optimiser.move_limit;
  t.hessian = optimiser.hessian;
  t.checkpoint_every = output.checkpoint_every;
  t.pose_bounds.move = pose.move;
  if (!output.folder.empty()) t.checkpoint = (fs::path(output.folder) / "checkpoint.bin").string();
  t.resume = output.resume;
  return t;
}

namespace {

/// The quadrature a run asks for: the options', else the scene target's, else collocation.
Quadrature run_quadrature(const TrackingRunOptions& options, const SceneTarget& target) {
  return options.distance.quadrature.value_or(target.quadrature.value_or(Quadrature::collocation));
}

/// With quadrature cells: the objective's cell form against the target's cells, one level only;
/// with the distance scan_to_body and a target without cells, against the scan's surface (its
/// points with their weights); another target without cells falls back to collocation. Each
/// said in the target's description.
void apply_quadrature(const TrackingRunOptions& options, SceneTarget* target,
                      ShapeObjectiveOptions* so) {
  if (run_quadrature(options, *target) != Quadrature::cells) return;
  const Sides sides = options.distance.form ? options.distance.form->sides : target->distance.sides;
  const bool scan_surface = !target->cells && sides == Sides::scan_to_body;
  if (!target->cells && !scan_surface) {
    target->description += "; quadrature cells: the target has no cells, collocation instead";
    return;
  }
  if (options.levels.count > 1)
    throw InvalidArgument("levels: quadrature cells runs on one level (levels 1; not yet more)");
  so->hausdorff.quadrature = Quadrature::cells;
  // An automatic β is the cell form's only one, the paper's 4 (the scan forms' 2 is
  // collocation's, measured there); a β given is the user's, refused by the objective if not 4.
  if (options.distance.params.beta == 0.0) so->hausdorff.params.beta = 4.0;
  if (scan_surface) {
    so->form.sides = Sides::scan_to_body;
    target->description +=
        "; quadrature cells: the body's cells against the scan's points "
        "and their weights";
    return;
  }
  so->target_cells = std::make_shared<const fe::Mesh>(*target->cells);
  target->description += "; quadrature cells";
}

}  // namespace

int tracking_levels(const Scene& scene, const TrackingRunOptions& options,
                    const SceneTarget& target) {
  if (options.levels.count > 0) return options.levels.count;
  // The cell quadrature runs on one level (its coarse levels are not built yet).
  if (run_quadrature(options, target) == Quadrature::cells) return 1;
  // A given start or a joint pose runs on one level (validate, TrackingRun refuse more).
  if (options.optimiser.initial_control || target.frame == TargetFrame::camera) return 1;
  // A cloud without a known map (a scan): one level. On noisy one-sided scans the coarse
  // start ends at a lower ρ̃ but a larger shape error (docs/formulation.md §4.8).
  if (!target.map_displacement) return 1;
  // Else every coarser level (fe::Halving::rounded) of at least 32 elements, the two-level
  // starts' smallest (fe::GridSequencingOptions::min_elements).
  return 1 + fe::coarser_levels(scene.body, fe::Halving::rounded,
                                fe::GridSequencingOptions{}.min_elements);
}

SceneTarget tracking_target(const Scene& scene, const fe::Mesh& mesh,
                            const TrackingRunOptions& options) {
  if (!options.target.file.empty()) return file_target(options.target.file, scene.body.dim());
  return scene_target(scene, mesh, options.memory_limit);
}

struct TrackingRun::Impl {
  Impl(const Scene& s, const fe::Assembler& a, const fe::ControlSpace& c, SceneTarget t,
       const TrackingRunOptions& o)
      : scene(s), assembler(a), control(c), options(o), target(std::move(t)) {
    options.validate();
    check_against_scene(scene, c, target, options);
    options.levels.count = tracking_levels(scene, options, target);
    if (target.cloud.dim() != scene.body.dim())
      throw InvalidArgument("the target cloud is " + std::to_string(target.cloud.dim()) +
                            "D but the scene's body is " + std::to_string(scene.body.dim()) + "D");
    ShapeObjectiveOptions so = options.objective();
    apply_target_settings(target, &so);
    so.hausdorff.params.beta = detail::run_beta(options, target);
    apply_quadrature(options, &target, &so);
    if (target.frame == TargetFrame::camera) {  // the pose joins the control (§8.10)
      if (options.levels.count > 1)
        throw InvalidArgument(
            "levels: a target in the camera's frame (joint pose) runs on one level (levels 1)");
      so.pose = start_pose(target, a, so, options.threads);
    }
    HausdorffOptions points = so.hausdorff;  // the target's points (fields): collocation
    points.quadrature = Quadrature::collocation;
    objective = std::make_unique<ShapeObjective>(
        a, c, HausdorffTarget(target.cloud, points), so,
        fe::state_solver_factory(scene.body, options.state.backend, &a, &c));
    if (options.distance.form) target.distance = *options.distance.form;
    detail::apply_target_form(*objective, target);
    if (options.state.coarse_levels == CoarseLevel::automatic &&
        fe::grid_levels(scene.body, fe::GridSequencingOptions{}) > 0) {
      const fe::Body level = fe::MeshHierarchy(scene.body, fe::Halving::nested, 1).level(1);
      coarse.emplace(level.make_assembler());
      objective->state_path().use_coarse_level(*coarse);
      setup.coarse_level = fe::describe_level(level);
    }
    if (options.levels.count > 1) levels = detail::coarse_problems(scene, target, options);
    setup.target = target.description;
    setup.target_points = static_cast<long>(target.cloud.size());
    setup.nodes = static_cast<long>(a.mesh().num_nodes());
    setup.controls = static_cast<long>(c.size());
  }

  /// summary.json's entries about the set-up.
  nlohmann::json summary_entries(int ranks) const {
    nlohmann::json sum;
    sum["scene"] = scene.source;
    sum["target"] = setup.target;
    sum["target_points"] = setup.target_points;
    sum["nodes"] = setup.nodes;
    sum["controls"] = setup.controls;
    sum["algorithm"] = to_string(options.optimiser.algorithm);
    sum["particles"] = to_string(objective->options().particles);  // the target's may differ
    sum["volumes"] = to_string(objective->options().volumes);
    sum["state_backend"] = to_string(options.state.backend);
    if (const std::optional<scan::Pose>& p = objective->options().pose) {
      sum["frame"] = "camera";
      sum["align"] = scan::to_string(objective->options().pose_kind);
      sum["pose_method"] = to_string(objective->options().pose_method);
      sum["pose_start"] = {{"matrix", detail::matrix_json(p->matrix())},
                           {"twist", detail::matrix_json(p->twist())}};
    }
    sum["ranks"] = ranks;
    return sum;
  }

  /// With options.output.folder: the folder (created, locked), the checkpoint's file and
  /// fingerprint, a resume checked before any output, and the run's files.
  void prepare_folder(ShapeTrackingOptions& to) {
    const fs::path dir(options.output.folder);
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec || !fs::is_directory(dir))
      throw FileError("cannot create the run's folder '" + dir.string() + "'" +
                      (ec ? " (" + ec.message() + ")" : ""));
    // Under mpiexec every rank runs on the same numbers; rank 0 alone writes.
    const bool writer = world_rank() == 0;
    if (writer) lock.emplace(dir.string());  // one run per folder
    to.write_checkpoint = writer;
    add_run_keys(to);
    const int ranks = options.share ? options.share->size() : 1;
    if (options.levels.count > 1) {
      if (!options.output.resume) {  // a fresh run: no finer level's checkpoint of an earlier run
        fs::remove(to.checkpoint, ec);
        for (const auto& p : levels) fs::remove(level_checkpoint(p->level), ec);
      }
    }
    // A multilevel run starts on its coarsest level, whose checkpoint a resume needs.
    const std::string first = levels.empty() ? to.checkpoint : level_checkpoint(levels[0]->level);
    if (options.output.resume && !fs::exists(first))
      throw FileError("resume: no checkpoint '" + first + "'");
    if (options.output.resume) read_run_log(first);  // a malformed one refused before output
    files.emplace(dir, *objective, control, options.output.vtu_every, writer,
                  summary_entries(ranks));
  }

  /// The fingerprint's entries of the run as a whole (track_shape adds the problem's): the
  /// scene file's content hash, and the state backend, the ranks and the levels where they
  /// differ from the serial single-level default.
  void add_run_keys(ShapeTrackingOptions& to) const {
    to.fingerprint["scene"] = file_hash(scene.source);
    // Another backend or partition gives other round-off: a resume must keep both (the keys
    // are absent for the serial default, so older checkpoints stay valid).
    const int ranks = options.share ? options.share->size() : 1;
    if (options.state.backend != fe::StateBackend::kCholmod)
      to.fingerprint["state"] = to_string(options.state.backend);
    if (ranks > 1) to.fingerprint["ranks"] = std::to_string(ranks);
    if (options.levels.count > 1) to.fingerprint["levels"] = std::to_string(options.levels.count);
  }

  /// Coarse level k's options from the user's mesh's `fine` (before its refined move limit):
  /// its iterations, its move limit (refined_move_limit when started from a coarser level), its
  /// fingerprint's "level"; the time limit and the checkpoint's file are run_coarse_levels'.
  ShapeTrackingOptions level_options(std::size_t k, const ShapeTrackingOptions& fine) const {
    ShapeTrackingOptions to = fine;
    // A level's iterations: coarse_iterations, and never more than the run's own limit.
    const int iterations =
        std::min(options.levels.coarse_iterations, options.optimiser.max_iterations);
    to.optimizer.max_iterations = iterations;
    to.optimizer.max_evaluations = 5 * iterations + 20;
    if (k > 0) to.optimizer.move_limit = options.levels.refined_move_limit;  // from a coarser level
    to.fingerprint["level"] = std::to_string(levels[k]->level) + ", at most " +
                              std::to_string(iterations) + " iterations, switch " +
                              exact_text(options.levels.switch_decrease);
    return to;
  }

  /// The checkpoint of coarse level `level` in the run's folder.
  std::string level_checkpoint(int level) const {
    return (fs::path(options.output.folder) / ("checkpoint_level" + std::to_string(level) + ".bin"))
        .string();
  }

  Eigen::VectorXd run_coarse_levels(const ShapeTrackingOptions& fine,
                                    const TrackingRunCallbacks& callbacks, TrackingRunSummary* s);
  bool caller_stopped = false;  // a StopRequest of the caller on a coarse level

  const Scene& scene;
  const fe::Assembler& assembler;
  const fe::ControlSpace& control;
  std::unique_ptr<fe::Assembler> own_assembler;  // the first constructor's body
  std::unique_ptr<fe::ControlSpace> own_control;
  TrackingRunOptions options;
  SceneTarget target;
  std::unique_ptr<ShapeObjective> objective;
  std::optional<fe::Assembler> coarse;
  std::vector<std::unique_ptr<detail::CoarseProblem>> levels;  // coarsest first
  TrackingRunSummary setup;
  std::optional<FolderLock> lock;
  std::optional<detail::RunFiles> files;
  bool ran = false;
};

namespace {

// The switch rule of a coarse level (docs/formulation.md §4.8): it ends once ρ̃ decreased by
// less than `decrease` relative, (ρ̃_{k−1} − ρ̃_k) / ρ̃_{k−1} < decrease, in two iterations
// in a row.
class SwitchRule {
 public:
  explicit SwitchRule(double decrease) : decrease_(decrease) {}
  /// After an accepted iteration with ρ̃ = rho: true if the level ends here.
  bool ends(double rho) {
    if (previous_ > 0.0) small_ = (previous_ - rho) / previous_ < decrease_ ? small_ + 1 : 0;
    previous_ = rho;
    return small_ >= 2;
  }

 private:
  double decrease_;
  double previous_ = 0.0;
  int small_ = 0;
};

}  // namespace

// Each coarse level from the control of the level below (the scene's start on the coarsest),
// with its own checkpoint, its rows in history.csv; returns the start of the user's mesh.
Eigen::VectorXd TrackingRun::Impl::run_coarse_levels(const ShapeTrackingOptions& fine,
                                                     const TrackingRunCallbacks& callbacks,
                                                     TrackingRunSummary* s) {
  Eigen::VectorXd m;
  double seconds = 0.0;  // of the levels so far
  for (std::size_t k = 0; k < levels.size(); ++k) {
    const detail::CoarseProblem& p = *levels[k];
    const Eigen::VectorXd lower = p.control->constant(p.scene.body.control_lower);
    const Eigen::VectorXd upper = p.control->constant(p.scene.body.control_upper);
    if (k == 0) m = p.control->constant(p.scene.body.control_initial);
    ShapeTrackingOptions to = level_options(k, fine);
    if (options.optimiser.max_seconds > 0.0)
      to.optimizer.max_seconds = std::max(1e-9, options.optimiser.max_seconds - seconds);
    if (!to.checkpoint.empty()) {
      to.checkpoint = level_checkpoint(p.level);
      to.resume = options.output.resume && fs::exists(to.checkpoint);
    }
    SwitchRule rule(options.levels.switch_decrease);
    bool switched = false;
    ShapeTrackingCallbacks cb;
    cb.on_failure = callbacks.on_failure;
    cb.on_iteration = [&](const TrackingIteration& it, const Eigen::VectorXd& mc) {
      TrackingIteration shown = it;
      shown.level = p.level;
      shown.seconds += seconds;
      if (files) files->level_iteration(shown);
      // The caller's StopRequest ends this level, and each later one after its first iteration.
      if (caller_stopped) throw StopRequest{};
      try {
        if (callbacks.on_iteration) callbacks.on_iteration(shown, mc);
      } catch (const StopRequest&) {
        caller_stopped = true;
        throw;
      }
      if (rule.ends(it.rho)) {
        switched = true;
        throw StopRequest{};
      }
    };
    ShapeTrackingSummary r =
        track_shape(*p.objective, lower, upper, m, p.target->map_displacement, to, cb);
    for (TrackingIteration it : r.history) {
      it.level = p.level;
      it.seconds += seconds;
      s->history.push_back(it);
    }
    LevelReport lr;
    lr.level = p.level;
    lr.nodes = static_cast<long>(p.assembler->mesh().num_nodes());
    lr.target_points = static_cast<long>(p.target->cloud.size());
    lr.iterations = r.iterations;
    lr.seconds = r.seconds;
    lr.rho_final = r.rho_final;
    lr.floor = r.floor();
    char rule_text[96];
    std::snprintf(rule_text, sizeof rule_text,
                  "switched: rho decreased by less than %g twice in a row",
                  options.levels.switch_decrease);
    lr.termination = switched ? rule_text : r.termination;
    s->levels.push_back(lr);
    seconds += r.seconds;
    // The next level's start: this level's best control at its controls.
    const bool last = k + 1 == levels.size();
    const fe::Mesh& finer = last ? assembler.mesh() : levels[k + 1]->assembler->mesh();
    const fe::ControlSpace& finer_control = last ? control : *levels[k + 1]->control;
    const std::vector<int>& regions =
        last ? scene.body.control_regions : levels[k + 1]->scene.body.control_regions;
    m = fe::prolongate_control(p.assembler->mesh(), *p.control, r.control, finer, finer_control,
                               regions);
    // ... and its state, the next level's first warm start (as the two-level starts do). The
    // level's state is bitwise the uninterrupted run's after any resume (track_shape), so the
    // next level's start is too.
    fe::State warm;
    warm.u = fe::prolongate(p.assembler->mesh(), r.displacement, finer);
    warm.m_qp = finer_control.to_quadrature(m);
    (last ? *objective : *levels[k + 1]->objective).state_path().remember(m, warm);
  }
  return m;
}

TrackingRun::TrackingRun(const Scene& scene, const TrackingRunOptions& options) {
  options.validate();
  auto assembler = std::make_unique<fe::Assembler>(scene.body.make_assembler());
  auto control = std::make_unique<fe::ControlSpace>(scene.body.make_control_space(*assembler));
  SceneTarget target = tracking_target(scene, assembler->mesh(), options);
  impl_ = std::make_unique<Impl>(scene, *assembler, *control, std::move(target), options);
  impl_->own_assembler = std::move(assembler);
  impl_->own_control = std::move(control);
}

TrackingRun::TrackingRun(const Scene& scene, const fe::Assembler& assembler,
                         const fe::ControlSpace& control, SceneTarget target,
                         const TrackingRunOptions& options)
    : impl_(std::make_unique<Impl>(scene, assembler, control, std::move(target), options)) {}

TrackingRun::~TrackingRun() = default;

TrackingRunSummary TrackingRun::run(const TrackingRunCallbacks& callbacks) {
  Impl& d = *impl_;
  if (d.ran) throw InvalidArgument("TrackingRun::run: a run is made once");
  d.ran = true;
  ShapeTrackingOptions to = d.options.tracking();
  if (!d.options.output.folder.empty()) d.prepare_folder(to);
  if (callbacks.on_begin) callbacks.on_begin(d.setup);
  if (d.files) d.files->begin(d.options.output.resume);

  TrackingRunSummary s = d.setup;
  // The scene's bounds and start where a control acts (0 where it touches none of its
  // regions); a multilevel run starts from its coarse levels' control.
  const Eigen::VectorXd m0 = !d.levels.empty() ? d.run_coarse_levels(to, callbacks, &s)
                             : d.options.optimiser.initial_control
                                 ? *d.options.optimiser.initial_control
                                 : d.control.constant(d.scene.body.control_initial);
  double offset = 0.0;  // the coarse levels' time
  for (const LevelReport& l : s.levels) offset += l.seconds;
  if (!d.levels.empty() && d.options.optimiser.max_seconds > 0.0)
    to.optimizer.max_seconds = std::max(1e-9, d.options.optimiser.max_seconds - offset);
  if (!d.levels.empty()) {
    to.optimizer.move_limit = d.options.levels.refined_move_limit;  // started from a coarser level
    // A multilevel run killed on a coarse level has no checkpoint of this level yet.
    if (to.resume) to.resume = fs::exists(to.checkpoint);
  }
  const Eigen::VectorXd lower = d.control.constant(d.scene.body.control_lower);
  const Eigen::VectorXd upper = d.control.constant(d.scene.body.control_upper);
  ShapeTrackingCallbacks cb;
  cb.on_start = [&](const ShapeTrackingSummary& start) {
    if (d.files)
      d.files->start(start, m0.cwiseMax(lower).cwiseMin(upper),
                     d.objective->state_path().last_state().u);
    if (callbacks.on_start) callbacks.on_start(start);
  };
  cb.on_failure = callbacks.on_failure;
  cb.on_iteration = [&](const TrackingIteration& it, const Eigen::VectorXd& m) {
    TrackingIteration shown = it;
    shown.seconds += offset;
    if (d.files) d.files->iteration(shown, m, d.objective->state_path().last_state().u);
    if (callbacks.on_iteration) callbacks.on_iteration(shown, m);
    if (d.caller_stopped) throw StopRequest{};  // asked for on a coarse level
  };
  ShapeTrackingSummary fine =
      track_shape(*d.objective, lower, upper, m0, d.target.map_displacement, to, cb);
  if (!d.levels.empty()) {
    LevelReport lr;
    lr.nodes = s.nodes;
    lr.target_points = s.target_points;
    lr.iterations = fine.iterations;
    lr.seconds = fine.seconds;
    lr.rho_final = fine.rho_final;
    lr.floor = fine.floor();
    lr.termination = fine.termination;
    s.levels.push_back(lr);
    fine.seconds += offset;
    for (TrackingIteration& it : fine.history) it.seconds += offset;
    fine.history.insert(fine.history.begin(), s.history.begin(), s.history.end());
  }
  const std::vector<LevelReport> reports = s.levels;
  static_cast<ShapeTrackingSummary&>(s) = std::move(fine);
  if (d.files && !reports.empty()) {
    nlohmann::json& j = d.files->summary()["levels"];
    j = nlohmann::json::array();
    for (const LevelReport& l : reports)
      j.push_back({{"level", l.level},
                   {"nodes", l.nodes},
                   {"target_points", l.target_points},
                   {"iterations", l.iterations},
                   {"seconds", l.seconds},
                   {"rho_final", l.rho_final},
                   {"rho_final_over_floor",
                    l.floor ? nlohmann::json(l.rho_final / *l.floor) : nlohmann::json(nullptr)},
                   {"termination", l.termination}});
  }
  if (d.files) d.files->finish(s, d.target.cloud);
  d.lock.reset();
  return s;
}

std::vector<RunFingerprint> TrackingRun::fingerprints() const {
  const Impl& d = *impl_;
  ShapeTrackingOptions to = d.options.tracking();
  d.add_run_keys(to);
  std::vector<RunFingerprint> out;
  for (std::size_t k = 0; k < d.levels.size(); ++k) {
    const detail::CoarseProblem& p = *d.levels[k];
    const fe::Body& body = p.scene.body;
    out.push_back(run_fingerprint(*p.objective, p.control->constant(body.control_lower),
                                  p.control->constant(body.control_upper),
                                  p.control->constant(body.control_initial),
                                  d.level_options(k, to)));
  }
  if (!d.levels.empty()) to.optimizer.move_limit = d.options.levels.refined_move_limit;
  const fe::Body& body = d.scene.body;
  const Eigen::VectorXd m0 = d.levels.empty() && d.options.optimiser.initial_control
                                 ? *d.options.optimiser.initial_control
                                 : d.control.constant(body.control_initial);
  out.push_back(run_fingerprint(*d.objective, d.control.constant(body.control_lower),
                                d.control.constant(body.control_upper), m0, to));
  return out;
}

TrackingRunSummary run_tracking(const Scene& scene, const TrackingRunOptions& options,
                                const TrackingRunCallbacks& callbacks) {
  return TrackingRun(scene, options).run(callbacks);
}

}  // namespace softhd
