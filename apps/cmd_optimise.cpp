// softhd optimise: track a target point cloud with the fiber tension m
// (docs/formulation.md §4, §5). Progress one line per iteration; history.csv, summary.json
// (status "interrupted" until the end) and the checkpoint log kept up to date as the run
// goes (resumable with --resume).

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

#include "cli.hpp"
#include "commands.hpp"
#include "softhd/control/bounded_optimizer.hpp"
#include "softhd/control/run_log.hpp"
#include "softhd/control/scene_target.hpp"
#include "softhd/control/shape_objective.hpp"
#include "softhd/control/shape_tracking.hpp"
#include "softhd/fe/grid_sequencing.hpp"
#include "softhd/fe/output.hpp"
#include "softhd/fe/scene.hpp"
#include "softhd/fe/state_backend.hpp"
#include "softhd/fe/state_equation.hpp"
#include "softhd/io/cloud_io.hpp"
#include "softhd/io/folder_lock.hpp"
#include "softhd/io/vtu.hpp"
#include "softhd/parallel.hpp"
#include "softhd/work_share.hpp"

extern char** environ;

namespace softhd::cli {

namespace {

namespace fs = std::filesystem;

const char* kUsage = R"(usage: softhd optimise SCENE [options]

Finds the fiber tension m, within the scene's bounds, whose equilibrium shape best
matches the target cloud under the regularised Hausdorff distance
(docs/formulation.md section 4; the user's guide is docs/guide.md).

options:
  --out DIR          output directory (default results/<scene name>)
  --target FILE      target cloud (text or PLY) instead of the scene's own target
  --max-iter N       iterations (default 200)
  --max-seconds S    wall-clock limit (default none)
  --rel-tol R        stop when J changes by less than R relative (default 1e-6)
  --algorithm A      mma | ccsaq | lbfgs | slsqp (default mma)
  --move-limit D     each round of 10 evaluations moves m by at most D times the
                     bound range (default 0.1; 0: no move limit)
  --particles P      nodes | quadrature: the moving cloud (default nodes)
  --volumes V        reference | deformed particle volumes (default reference)
  --alpha A --beta B --gamma G --eps E   functional parameters (default 4 4 2 1e-3)
  --method M         exact | tree: the distance's pair sums (default tree; it sums
                     exactly wherever its far field would not be cheaper)
  --tol T            tree: relative error bound on every kernel sum (default 1e-2,
                     which ends the bending and torsion runs at exact's rho/floor)
  --tikhonov-mass M  (M/2) int m^2 (default 0)
  --tikhonov-grad E  (E/2) int |grad m|^2 (default 0)
  --vtu-every K      VTU output every K iterations (default 10; 0: start and end only)
  --checkpoint-every K  save the warm-start states every K iterations (default 5): a
                     resume recomputes at most the K-1 iterations after the last save
  --coarse-level C   auto | off: two-level starts, a large control step solved first on
                     the mesh with half the cells along the even axes (default auto: when
                     that mesh has >= 32 elements)
  --threads T        OpenMP threads (default: all)
  --max-memory GIB   refuse meshes whose estimated memory exceeds this (default 8)
  --state-backend B  cholmod | petsc-mumps | petsc-gamg: the state solver (default
                     cholmod, the serial Newton); the PETSc ones need softhd built with
                     -DSOFTHD_WITH_MPI=ON and distribute the state over the ranks of
                     mpiexec (docs/scaling.md section 4); PETSc options go in the
                     environment variable PETSC_OPTIONS
  --resume           continue the run recorded in DIR/checkpoint.bin: the same run
                     as an uninterrupted one (limits count over all resumes); a
                     checkpoint of another scene, target or options is refused
  --json             print summary.json on stdout at the end
  --quiet            no progress lines
  --help             this text

scene targets ("target" in the scene file):
  {"kind": "arc", "angle": RAD [, "cells": [n1, n2, n3]]}  the plate bent into a
      circular arc (docs/formulation.md section 5.2), sampled on its own
      cell-centred grid
  {"kind": "cloud", "file": PATH [, "solved_on": SCENE]}  a cloud file; with solved_on
      it holds the deformed nodes of a state solved on SCENE's mesh ('softhd forward
      --write-cloud'), which gives the known map for the matched floor and shape error

writes: history.csv, control.csv (readable by 'softhd forward --control'),
body_NNNN.vtu, target.vtu, body.pvd, body_final.ply, target.ply, summary.json,
checkpoint.bin, and convergence.png when python3 with matplotlib is available.

exit status: 0 done (also when stopped by --max-iter or --max-seconds); 1 numerical
failure (the state solve at the start or at the
best control failed); 2 bad input or refused (one line on stderr names the file, key or
flag; also when another run holds the --out folder's lock). Ctrl-C or a kill ends the
run at once (status 130 or the signal's); the checkpoint, history and summary written so
far are complete, and --resume continues the same run.

MPI builds: under 'mpiexec -n K softhd optimise ...' every rank runs the optimiser
on the same numbers: the distance's pair sums are split across the ranks (as in
softhd distance), the state is distributed with a PETSc backend and solved by
every rank with cholmod; rank 0 alone prints and writes files. A run resumes
only with the same backend and number of ranks.
)";

nlohmann::json optional_json(const std::optional<double>& v) {
  return v ? nlohmann::json(*v) : nlohmann::json(nullptr);
}

std::string csv_row(const std::vector<double>& v) {
  std::ostringstream s;
  s.precision(10);
  for (size_t k = 0; k < v.size(); ++k) {
    if (k) s << ',';
    if (std::isfinite(v[k])) s << v[k];  // a ratio without a floor stays empty
  }
  return s.str();
}

bool vtu_due(long every, int iteration) { return every > 0 && iteration % every == 0; }

const char* kHistoryHeader =
    "iteration,evaluation,J,rho,A,B,rho_over_floor,projected_gradient_norm,newton_iterations,"
    "factorizations,seconds_state,seconds_distance,seconds_adjoint,seconds";

}  // namespace

namespace {

struct OptimiseArgs {
  std::optional<std::string> out, target_file;
  std::string scene_file;
  ShapeTrackingOptions tracking;
  ShapeObjectiveOptions objective;
  double memory_limit = fe::kDefaultMemoryLimit;
  fe::StateBackend backend = fe::StateBackend::kCholmod;
  long vtu_every = 10;
  bool resume = false, json = false, quiet = false;
  bool coarse_level = true;
};

OptimiseArgs parse_optimise(Args& args) {
  OptimiseArgs a;
  a.out = args.value("--out");
  a.target_file = args.value("--target");
  BoundedOptimizerOptions& opt = a.tracking.optimizer;
  opt.max_iterations = static_cast<int>(args.integer("--max-iter", 200, 1, 1000000));
  opt.max_evaluations = 5 * opt.max_iterations + 20;
  opt.max_seconds = args.number("--max-seconds", 0.0);
  opt.relative_change = args.number("--rel-tol", 1e-6);
  opt.algorithm = algorithm_from_string(args.value("--algorithm").value_or("mma"));
  opt.move_limit = args.number("--move-limit", 0.1);
  ShapeObjectiveOptions& so = a.objective;
  so.particles = particles_from_string(args.value("--particles").value_or("nodes"));
  so.volumes = particle_volumes_from_string(args.value("--volumes").value_or("reference"));
  so.hausdorff.params.alpha = args.number("--alpha", so.hausdorff.params.alpha);
  so.hausdorff.params.beta = args.number("--beta", so.hausdorff.params.beta);
  so.hausdorff.params.gamma = args.number("--gamma", so.hausdorff.params.gamma);
  so.hausdorff.params.epsilon = args.number("--eps", so.hausdorff.params.epsilon);
  so.hausdorff.method = method_from_string(args.value("--method").value_or("tree"));
  if (so.hausdorff.method == Method::nearest)
    throw UsageError("--method: nearest has no gradient; expected exact or tree");
  // τ = 1e-2 ends the bending and torsion optimisations at the exact method's ρ̃/floor
  // (docs/guide.md section 5); the tree's cost model sums exactly where that is cheaper.
  so.hausdorff.tolerance = args.number("--tol", 1e-2);
  so.tikhonov_mass = args.number("--tikhonov-mass", 0.0);
  so.tikhonov_gradient = args.number("--tikhonov-grad", 0.0);
  so.hausdorff.threads = static_cast<int>(args.integer("--threads", 0, 0, kMaxThreads));
  set_threads(so.hausdorff.threads);  // the FE assembly too
  a.vtu_every = args.integer("--vtu-every", 10, 0, 1000000000);
  a.tracking.checkpoint_every = static_cast<int>(args.integer("--checkpoint-every", 5, 1, 1000000));
  const std::string coarse = args.value("--coarse-level").value_or("auto");
  if (coarse != "auto" && coarse != "off")
    throw UsageError("--coarse-level: expected auto or off, got '" + coarse + "'");
  a.coarse_level = coarse == "auto";
  const double gib = args.number("--max-memory", a.memory_limit / (1u << 30));
  if (!(gib > 0.0 && gib <= 1e6)) throw UsageError("--max-memory: expected GiB in (0, 1e6]");
  a.memory_limit = gib * (1u << 30);
  const std::string backend = args.value("--state-backend").value_or("cholmod");
  try {
    a.backend = fe::parse_state_backend(backend);
  } catch (const InvalidArgument& e) {
    throw UsageError(std::string("--state-backend: ") + e.what());
  }
  if (a.backend != fe::StateBackend::kCholmod && !fe::petsc_backend_available())
    throw UsageError("--state-backend " + backend +
                     " needs softhd built with -DSOFTHD_WITH_MPI=ON (this build has cholmod only)");
  a.resume = args.flag("--resume");
  a.json = args.flag("--json");
  a.quiet = args.flag("--quiet");
  const std::vector<std::string> pos = args.finish();
  if (pos.size() != 1) throw UsageError("expected one scene file (see --help)");
  a.scene_file = pos[0];
  a.tracking.validate();
  so.validate();
  return a;
}

std::string file_hash(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  const std::string bytes = s.str();
  return content_hash(bytes.data(), bytes.size());
}

std::string body_name(int iteration) {
  char name[32];
  std::snprintf(name, sizeof name, "body_%04d.vtu", iteration);
  return name;
}

// The files of a run in its directory: body VTUs and their PVD, and history.csv and
// summary.json, rewritten as the run goes.
class RunFiles {
 public:
  /// `writes` false: the fields are computed (collective with a shared distance) but no
  /// file is written (ranks other than 0).
  RunFiles(fs::path dir, const ShapeObjective& objective, const fe::ControlSpace& space,
           bool writes)
      : dir_(std::move(dir)), objective_(objective), space_(space), writes_(writes) {}
  const fs::path& dir() const { return dir_; }

  HausdorffResult write_body(int iteration, const Eigen::VectorXd& m, const Eigen::VectorXd& u) {
    const fe::Assembler& a = objective_.assembler();
    const HausdorffResult r = objective_.fields(u);
    if (!writes_) return r;
    std::vector<VtuField> point{{"m", fe::control_at_nodes(a.mesh(), space_, m)}};
    std::vector<VtuField> cell;
    if (objective_.options().particles == Particles::nodes)
      point.push_back({"d_tilde", r.field_moving});
    cell.push_back({"J", a.jacobians(u).rowwise().mean()});
    if (space_.kind() == fe::ControlKind::kElement) cell.push_back({"m", m});
    write_vtu_mesh((dir_ / body_name(iteration)).string(), a.mesh(), u, point, cell);
    list_body(iteration);
    return r;
  }
  /// Lists a body VTU in body.pvd (once), e.g. one an earlier process of the run wrote.
  void list_body(int iteration) {
    if (!writes_) return;
    if (!pvd_.empty() && pvd_.back().second == body_name(iteration)) return;
    if (!fs::exists(dir_ / body_name(iteration))) return;
    pvd_.emplace_back(iteration, body_name(iteration));
    write_pvd((dir_ / "body.pvd").string(), pvd_);
  }
  void add_row(const TrackingIteration& it) {
    rows_.push_back(csv_row(
        {double(it.iteration), double(it.evaluation), it.J, it.rho, it.A, it.B, it.rho_over_floor,
         it.projected_gradient_norm, double(it.newton_iterations), double(it.factorizations),
         it.seconds_state, it.seconds_distance, it.seconds_adjoint, it.seconds}));
  }
  void write_history() const {
    if (!writes_) return;
    std::ostringstream h;
    h << kHistoryHeader << '\n';
    for (const std::string& r : rows_) h << r << '\n';
    write_file_atomically((dir_ / "history.csv").string(), h.str());
  }
  void write_summary(const nlohmann::json& sum) const {
    if (!writes_) return;
    write_file_atomically((dir_ / "summary.json").string(), sum.dump(2) + "\n");
  }

 private:
  fs::path dir_;
  const ShapeObjective& objective_;
  const fe::ControlSpace& space_;
  bool writes_;
  std::vector<std::string> rows_;
  std::vector<std::pair<double, std::string>> pvd_;
};

// summary.json's entries about the end of the run.
void add_final(const ShapeTrackingSummary& s, nlohmann::json& sum) {
  sum["floor_self"] = optional_json(s.floor_self);  // with a known map, made at the end
  sum["floor_matched"] = optional_json(s.floor_matched);
  sum["rho_final"] = s.rho_final;
  sum["J_final"] = s.J_final;
  sum["rho_final_over_floor"] =
      optional_json(s.floor() ? std::optional<double>(s.rho_final / *s.floor()) : std::nullopt);
  sum["iterations"] = s.iterations;
  sum["evaluations"] = s.evaluations;
  sum["replayed_evaluations"] = s.replayed_evaluations;
  sum["failed_evaluations"] = s.failed_evaluations;
  sum["termination"] = s.termination;
  sum["converged"] = s.converged();
  sum["shape_error_max"] = optional_json(s.shape_error_max);
  sum["shape_error_rms"] = optional_json(s.shape_error_rms);
  sum["seconds"] = s.seconds;
  sum["newton_iterations"] = s.newton_iterations;
  sum["factorizations"] = s.factorizations;
  sum["seconds_state"] = s.seconds_state;
  sum["seconds_distance"] = s.seconds_distance;
  sum["seconds_adjoint"] = s.seconds_adjoint;
  sum["seconds_optimizer"] = s.seconds_optimizer;
}

void print_start(const ShapeTrackingSummary& start) {
  std::fprintf(
      stderr, "  rho start %.6g, floor self %s, floor matched %s\n", start.rho_start,
      start.floor_self      ? std::to_string(*start.floor_self).c_str()
      : start.floor_matched ? "computed at the end"
                            : "n/a (skipped: target too large)",
      start.floor_matched ? std::to_string(*start.floor_matched).c_str() : "n/a (no known map)");
  std::fprintf(stderr, "  %5s %12s %12s %10s %10s %7s %8s\n", "iter", "J", "rho", "rho/floor",
               "|P grad|", "newton", "seconds");
}

void print_end(const ShapeTrackingSummary& s, const fs::path& out) {
  std::fprintf(stderr, "  %s after %d iterations, %.1f s\n", s.termination.c_str(), s.iterations,
               s.seconds);
  std::fprintf(stderr, "  rho %.6g -> %.6g (%.3g x floor)", s.rho_start, s.rho_final,
               s.floor() ? s.rho_final / *s.floor() : std::nan(""));
  if (s.shape_error_max)
    std::fprintf(stderr, ", shape error max %.4g rms %.4g", *s.shape_error_max, *s.shape_error_rms);
  std::fprintf(stderr, "\n  results in %s\n", out.string().c_str());
}

// Runs argv[0] with the arguments, without a shell, its output discarded; returns its exit
// status, or -1 if it could not be started or did not exit normally.
int run_quietly(const std::vector<std::string>& argv) {
  std::vector<char*> args;
  for (const std::string& s : argv) args.push_back(const_cast<char*>(s.c_str()));
  args.push_back(nullptr);
  posix_spawn_file_actions_t io;
  posix_spawn_file_actions_init(&io);
  posix_spawn_file_actions_addopen(&io, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&io, 2, "/dev/null", O_WRONLY, 0);
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, args[0], &io, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&io);
  if (rc != 0) return -1;
  int status = 0;
  while (waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) return -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

fs::path output_directory(const OptimiseArgs& a, const fe::Scene& scene) {
  const fs::path out = a.out ? fs::path(*a.out) : fs::path("results") / scene.name;
  std::error_code ec;
  fs::create_directories(out, ec);
  if (ec || !fs::is_directory(out))
    throw FileError("--out: cannot create the directory '" + out.string() + "'" +
                    (ec ? " (" + ec.message() + ")" : ""));
  return out;
}

}  // namespace

int run_optimise(const std::vector<std::string>& tokens) {
  // Under mpiexec every rank runs all of this on the same numbers; rank 0 writes and prints.
  const bool writer = world_rank() == 0;
  Args args(tokens);
  if (args.flag("--help")) {
    if (writer) std::cout << kUsage;
    return 0;
  }
  OptimiseArgs a = parse_optimise(args);
  ShapeObjectiveOptions& so = a.objective;
  so.hausdorff.share = world_share();  // null unless started by mpiexec with K > 1 ranks
  const int ranks = so.hausdorff.share ? so.hausdorff.share->size() : 1;
  if (!writer) a.quiet = true;

  // The problem: scene, mesh, control space, target.
  const fe::Scene scene = fe::load_scene(a.scene_file, a.memory_limit);
  const fe::Assembler assembler = scene.make_assembler();
  const fe::Mesh& mesh = assembler.mesh();
  const fe::ControlSpace space = scene.make_control_space(assembler);
  if (!a.target_file && scene.target_json.empty())
    throw InvalidArgument(scene.source + ": the scene has no \"target\"; give --target FILE");
  const SceneTarget target = a.target_file ? file_target(*a.target_file, scene.dim())
                                           : scene_target(scene, mesh, a.memory_limit);
  if (target.cloud.dim() != scene.dim())
    throw InvalidArgument("the target cloud is " + std::to_string(target.cloud.dim()) +
                          "D but the scene's body is " + std::to_string(scene.dim()) + "D");
  const fs::path out = output_directory(a, scene);
  // One run per folder (rank 0 writes; the other ranks' files are not written).
  std::optional<FolderLock> lock;
  if (writer) lock.emplace(out.string());
  ShapeTrackingOptions& to = a.tracking;
  to.checkpoint = (out / "checkpoint.bin").string();
  to.write_checkpoint = writer;
  to.resume = a.resume;
  to.fingerprint["scene"] = file_hash(a.scene_file);
  // Another backend or partition gives other round-off: a resume must keep both (the
  // keys are absent for the serial default, so older checkpoints stay valid).
  if (a.backend != fe::StateBackend::kCholmod) to.fingerprint["state"] = to_string(a.backend);
  if (ranks > 1) to.fingerprint["ranks"] = std::to_string(ranks);
  if (a.resume && !fs::exists(to.checkpoint))
    throw FileError("--resume: no checkpoint '" + to.checkpoint + "'");
  if (a.resume) read_run_log(to.checkpoint);  // a malformed one refused before any output

  ShapeObjective objective(assembler, space, HausdorffTarget(target.cloud, so.hausdorff), so,
                           fe::state_solver_factory(scene, a.backend, &assembler, &space));
  std::optional<fe::Assembler> coarse;
  if (a.coarse_level && fe::grid_levels(scene, fe::GridSequencingOptions{}) > 0) {
    coarse.emplace(fe::coarsened(scene).make_assembler());
    objective.use_coarse_level(*coarse);
  }
  const Eigen::VectorXd m0 = space.constant(scene.control_initial);
  const Eigen::VectorXd lower = space.constant(scene.control_lower);
  const Eigen::VectorXd upper = space.constant(scene.control_upper);
  RunFiles files(out, objective, space, writer);
  nlohmann::json sum;
  sum["scene"] = a.scene_file;
  sum["target"] = target.description;
  sum["target_points"] = target.cloud.size();
  sum["nodes"] = mesh.num_nodes();
  sum["controls"] = space.size();
  sum["algorithm"] = to_string(to.optimizer.algorithm);
  sum["particles"] = to_string(so.particles);
  sum["volumes"] = to_string(so.volumes);
  sum["state_backend"] = to_string(a.backend);
  sum["ranks"] = ranks;
  if (!a.quiet)
    std::fprintf(stderr, "softhd optimise %s: %ld nodes, %ld controls, target %ld points (%s)\n",
                 scene.name.c_str(), static_cast<long>(mesh.num_nodes()),
                 static_cast<long>(space.size()), static_cast<long>(target.cloud.size()),
                 target.description.c_str());

  // From here on the directory always holds history.csv and summary.json; a resumed run
  // keeps the earlier process's until it has new rows.
  sum["status"] = "interrupted";  // until the run ends: a killed run leaves this
  if (!a.resume || !fs::exists(out / "history.csv")) files.write_history();
  if (!a.resume || !fs::exists(out / "summary.json")) files.write_summary(sum);

  ShapeTrackingCallbacks cb;
  cb.on_start = [&](const ShapeTrackingSummary& start) {
    sum["rho_start"] = start.rho_start;
    sum["floor_self"] = optional_json(start.floor_self);
    sum["floor_matched"] = optional_json(start.floor_matched);
    if (!a.quiet) print_start(start);
    files.write_body(0, m0.cwiseMax(lower).cwiseMin(upper), objective.last_state().u);
  };
  cb.on_failure = [&](const std::string& report) {
    if (!a.quiet)
      std::fprintf(stderr, "  state solve failed (step rejected): %s\n", report.c_str());
  };
  cb.on_iteration = [&](const TrackingIteration& it, const Eigen::VectorXd& m) {
    files.add_row(it);
    if (!a.quiet)
      std::fprintf(stderr, "  %5d %12.6g %12.6g %10.4g %10.3g %7d %8.1f%s\n", it.iteration, it.J,
                   it.rho, it.rho_over_floor, it.projected_gradient_norm, it.newton_iterations,
                   it.seconds, it.replayed ? " (from the checkpoint)" : "");
    // A replayed iteration's VTU was written by the process that made it.
    if (vtu_due(a.vtu_every, it.iteration)) {
      if (it.replayed)
        files.list_body(it.iteration);
      else
        files.write_body(it.iteration, m, objective.last_state().u);
    }
    if (it.replayed) return;
    files.write_history();
    nlohmann::json now = sum;
    now["iterations"] = it.iteration;
    now["evaluations"] = it.evaluation;
    now["J"] = it.J;
    now["rho"] = it.rho;
    now["seconds"] = it.seconds;
    files.write_summary(now);
  };

  const ShapeTrackingSummary s =
      track_shape(objective, lower, upper, m0, target.map_displacement, to, cb);
  const HausdorffResult fields = files.write_body(s.iterations, s.control, s.displacement);
  if (!writer) return 0;
  write_vtu_cloud((out / "target.vtu").string(), target.cloud, {{"d_tilde", fields.field_target}});
  write_ply_cloud((out / "target.ply").string(), target.cloud);
  write_ply_cloud((out / "body_final.ply").string(), objective.particles(s.displacement));
  files.write_history();
  fe::write_control_file((out / "control.csv").string(), space.positions(mesh), s.control);
  sum["status"] = "finished";
  add_final(s, sum);
  files.write_summary(sum);
#ifdef SOFTHD_PLOT_SCRIPT
  // No shell: the folder is one argument, whatever characters it holds.
  const int status = run_quietly({"/usr/bin/python3", SOFTHD_PLOT_SCRIPT, out.string()});
  if (status != 0 && !a.quiet)
    std::fprintf(stderr, "  (convergence.png not drawn: %s)\n",
                 status == 3    ? "needs python3-matplotlib"
                 : status == -1 ? "cannot run /usr/bin/python3"
                                : "scripts/plot_convergence.py failed");
#endif
  if (!a.quiet) print_end(s, out);
  if (a.json) std::cout << sum.dump(2) << '\n';
  return 0;
}

}  // namespace softhd::cli
