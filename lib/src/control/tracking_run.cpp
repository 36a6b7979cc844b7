#include "softhd/control/tracking_run.hpp"

#include <algorithm>
#include <climits>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <system_error>

#include "run_files.hpp"
#include "softhd/control/run_log.hpp"
#include "softhd/enum_names.hpp"
#include "softhd/error.hpp"
#include "softhd/fe/grid_sequencing.hpp"
#include "softhd/fe/state_equation.hpp"
#include "softhd/io/folder_lock.hpp"

namespace softhd {

namespace fs = std::filesystem;

namespace {

constexpr EnumNames<CoarseLevel, 2> kCoarseLevelNames{
    {{CoarseLevel::automatic, "auto"}, {CoarseLevel::off, "off"}}};

// The content hash of a file's bytes (empty if it cannot be read): the fingerprint's "scene".
std::string file_hash(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  const std::string bytes = s.str();
  return content_hash(bytes.data(), bytes.size());
}

}  // namespace

std::string to_string(CoarseLevel level) { return enum_name(kCoarseLevelNames, level); }

CoarseLevel coarse_level_from_string(const std::string& name) {
  return enum_from_name(kCoarseLevelNames, name, "coarse_level");
}

void TrackingRunOptions::validate() const {
  if (max_iterations < 1)
    throw InvalidArgument("max_iterations must be >= 1, got " + std::to_string(max_iterations));
  if (max_evaluations < 0)
    throw InvalidArgument("max_evaluations must be >= 0 (0: 5 x max_iterations + 20), got " +
                          std::to_string(max_evaluations));
  if (method == Method::nearest)
    throw InvalidArgument("method: nearest has no gradient; expected exact or tree");
  if (vtu_every < 0) throw InvalidArgument("vtu_every must be >= 0");
  if (!(memory_limit > 0.0)) throw InvalidArgument("memory_limit must be > 0");
  if (resume && out.empty())
    throw InvalidArgument("resume needs the run's folder (the out field is empty)");
  objective().validate();
  tracking().validate();
}

ShapeObjectiveOptions TrackingRunOptions::objective() const {
  ShapeObjectiveOptions o;
  o.hausdorff.params = params;
  o.hausdorff.method = method;
  o.hausdorff.tolerance = tolerance;
  o.hausdorff.threads = threads;
  o.hausdorff.share = share;
  o.particles = particles;
  o.volumes = volumes;
  o.tikhonov_mass = tikhonov_mass;
  o.tikhonov_gradient = tikhonov_gradient;
  return o;
}

ShapeTrackingOptions TrackingRunOptions::tracking() const {
  ShapeTrackingOptions t;
  BoundedOptimizerOptions& o = t.optimizer;
  o.algorithm = algorithm;
  o.max_iterations = max_iterations;
  const long evaluations = 5L * max_iterations + 20;  // a failed or repeated one per step, and more
  o.max_evaluations = max_evaluations > 0 ? max_evaluations
                                          : static_cast<int>(std::min<long>(INT_MAX, evaluations));
  o.max_seconds = max_seconds;
  o.relative_change = relative_change;
  o.move_limit = move_limit;
  t.checkpoint_every = checkpoint_every;
  if (!out.empty()) t.checkpoint = (fs::path(out) / "checkpoint.bin").string();
  t.resume = resume;
  return t;
}

SceneTarget tracking_target(const fe::Scene& scene, const fe::Mesh& mesh,
                            const TrackingRunOptions& options) {
  if (!options.target_file.empty()) return file_target(options.target_file, scene.dim());
  return scene_target(scene, mesh, options.memory_limit);
}

struct TrackingRun::Impl {
  Impl(const fe::Scene& s, const fe::Assembler& a, const fe::ControlSpace& c, SceneTarget t,
       const TrackingRunOptions& o)
      : scene(s), assembler(a), control(c), options(o), target(std::move(t)) {
    options.validate();
    if (target.cloud.dim() != scene.dim())
      throw InvalidArgument("the target cloud is " + std::to_string(target.cloud.dim()) +
                            "D but the scene's body is " + std::to_string(scene.dim()) + "D");
    const ShapeObjectiveOptions so = options.objective();
    objective = std::make_unique<ShapeObjective>(
        a, c, HausdorffTarget(target.cloud, so.hausdorff), so,
        fe::state_solver_factory(scene, options.state_backend, &a, &c));
    if (options.coarse_level == CoarseLevel::automatic &&
        fe::grid_levels(scene, fe::GridSequencingOptions{}) > 0) {
      coarse.emplace(fe::coarsened(scene).make_assembler());
      objective->use_coarse_level(*coarse);
    }
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
    sum["algorithm"] = to_string(options.algorithm);
    sum["particles"] = to_string(options.particles);
    sum["volumes"] = to_string(options.volumes);
    sum["state_backend"] = to_string(options.state_backend);
    sum["ranks"] = ranks;
    return sum;
  }

  /// With options.out: the folder (created, locked), the checkpoint's file and fingerprint,
  /// a resume checked before any output, and the run's files.
  void prepare_folder(ShapeTrackingOptions& to) {
    const fs::path dir(options.out);
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec || !fs::is_directory(dir))
      throw FileError("cannot create the run's folder '" + dir.string() + "'" +
                      (ec ? " (" + ec.message() + ")" : ""));
    // Under mpiexec every rank runs on the same numbers; rank 0 alone writes.
    const bool writer = world_rank() == 0;
    if (writer) lock.emplace(dir.string());  // one run per folder
    to.write_checkpoint = writer;
    to.fingerprint["scene"] = file_hash(scene.source);
    // Another backend or partition gives other round-off: a resume must keep both (the keys
    // are absent for the serial default, so older checkpoints stay valid).
    const int ranks = options.share ? options.share->size() : 1;
    if (options.state_backend != fe::StateBackend::kCholmod)
      to.fingerprint["state"] = to_string(options.state_backend);
    if (ranks > 1) to.fingerprint["ranks"] = std::to_string(ranks);
    if (options.resume && !fs::exists(to.checkpoint))
      throw FileError("resume: no checkpoint '" + to.checkpoint + "'");
    if (options.resume) read_run_log(to.checkpoint);  // a malformed one refused before output
    files.emplace(dir, *objective, control, options.vtu_every, writer, summary_entries(ranks));
  }

  const fe::Scene& scene;
  const fe::Assembler& assembler;
  const fe::ControlSpace& control;
  std::unique_ptr<fe::Assembler> own_assembler;  // the first constructor's body
  std::unique_ptr<fe::ControlSpace> own_control;
  TrackingRunOptions options;
  SceneTarget target;
  std::unique_ptr<ShapeObjective> objective;
  std::optional<fe::Assembler> coarse;
  TrackingRunSummary setup;
  std::optional<FolderLock> lock;
  std::optional<detail::RunFiles> files;
  bool ran = false;
};

TrackingRun::TrackingRun(const fe::Scene& scene, const TrackingRunOptions& options) {
  options.validate();
  auto assembler = std::make_unique<fe::Assembler>(scene.make_assembler());
  auto control = std::make_unique<fe::ControlSpace>(scene.make_control_space(*assembler));
  SceneTarget target = tracking_target(scene, assembler->mesh(), options);
  impl_ = std::make_unique<Impl>(scene, *assembler, *control, std::move(target), options);
  impl_->own_assembler = std::move(assembler);
  impl_->own_control = std::move(control);
}

TrackingRun::TrackingRun(const fe::Scene& scene, const fe::Assembler& assembler,
                         const fe::ControlSpace& control, SceneTarget target,
                         const TrackingRunOptions& options)
    : impl_(std::make_unique<Impl>(scene, assembler, control, std::move(target), options)) {}

TrackingRun::~TrackingRun() = default;

TrackingRunSummary TrackingRun::run(const TrackingRunCallbacks& callbacks) {
  Impl& d = *impl_;
  if (d.ran) throw InvalidArgument("TrackingRun::run: a run is made once");
  d.ran = true;
  ShapeTrackingOptions to = d.options.tracking();
  if (!d.options.out.empty()) d.prepare_folder(to);
  if (callbacks.on_begin) callbacks.on_begin(d.setup);
  if (d.files) d.files->begin(d.options.resume);

  // The scene's bounds and start where a control acts (0 where it touches none of its regions).
  const Eigen::VectorXd m0 = d.control.constant(d.scene.control_initial);
  const Eigen::VectorXd lower = d.control.constant(d.scene.control_lower);
  const Eigen::VectorXd upper = d.control.constant(d.scene.control_upper);
  ShapeTrackingCallbacks cb;
  cb.on_start = [&](const ShapeTrackingSummary& start) {
    if (d.files)
      d.files->start(start, m0.cwiseMax(lower).cwiseMin(upper), d.objective->last_state().u);
    if (callbacks.on_start) callbacks.on_start(start);
  };
  cb.on_failure = callbacks.on_failure;
  cb.on_iteration = [&](const TrackingIteration& it, const Eigen::VectorXd& m) {
    if (d.files) d.files->iteration(it, m, d.objective->last_state().u);
    if (callbacks.on_iteration) callbacks.on_iteration(it, m);
  };
  TrackingRunSummary s = d.setup;
  static_cast<ShapeTrackingSummary&>(s) =
      track_shape(*d.objective, lower, upper, m0, d.target.map_displacement, to, cb);
  if (d.files) d.files->finish(s, d.target.cloud);
  d.lock.reset();
  return s;
}

TrackingRunSummary run_tracking(const fe::Scene& scene, const TrackingRunOptions& options,
                                const TrackingRunCallbacks& callbacks) {
  return TrackingRun(scene, options).run(callbacks);
}

}  // namespace softhd
