// softhd optimise: track a target point cloud with the fiber tension m
// (docs/formulation.md §4, §5). Parses the options into TrackingRunOptions (whose defaults
// the help text shows), runs the library's TrackingRun, and prints a line per iteration.

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <sstream>

#include "cli.hpp"
#include "commands.hpp"
#include "softhd/control/run_fields.hpp"
#include "softhd/control/scene.hpp"
#include "softhd/control/tracking_run.hpp"
#include "softhd/parallel.hpp"
#include "softhd/work_share.hpp"

extern char** environ;

namespace softhd::cli {

namespace {

namespace fs = std::filesystem;

// {NAME} fields are TrackingRunOptions' defaults (usage()).
const char* kUsage = R"(usage: softhd optimise SCENE [options]

Finds the fiber tension m, within the scene's bounds, whose equilibrium shape best
matches the target cloud under the regularised Hausdorff distance
(docs/formulation.md section 4; the user's guide is docs/guide.md).

options:
  --out DIR          output directory (default results/<scene name>)
  --target FILE      target cloud (text or PLY) instead of the scene's own target
  --max-iter N       iterations (default {max_iter})
  --max-seconds S    wall-clock limit (default none)
  --rel-tol R        stop when J changes by less than R relative (default {rel_tol})
  --algorithm A      mma | ccsaq | lbfgs | slsqp | newton (default {algorithm}; newton:
                     trust-region Newton-CG with exact Hessian-vector products)
  --hessian H        newton's Hessian-vector product: full | gauss_newton (default
                     {hessian}; gauss_newton: its positive semi-definite part)
  --move-limit D     each round of 10 evaluations moves m by at most D times the
                     bound range (default {move_limit}; 0: no move limit); newton: its
                     trust radius is at most D times the bound range, root-mean-square
                     over the controls
  --particles P      nodes | quadrature | boundary: the moving cloud (default {particles};
                     boundary, 3D: the boundary nodes with their facet areas, which a
                     target block's "surface": true selects)
  --volumes V        reference | deformed particle volumes (default {volumes})
  --alpha A --beta B --gamma G --eps E   functional parameters (default {alpha} {beta} {gamma} {eps};
                     beta 0: automatic, 4 for the symmetric distance, 2 for scan_to_body
                     and visible)
  --method M         exact | tree: the distance's pair sums (default {method}; it sums
                     exactly wherever its far field would not be cheaper)
  --tol T            tree: relative error bound on every kernel sum (default {tol},
                     which ends the bending and torsion runs at exact's rho/floor)
  --quadrature Q     collocation | cells: where the distance is integrated (default: the
                     scene target's "quadrature", else collocation); cells: over the
                     body's cells and the target's (an arc, or a cloud with solved_on;
                     with scan_to_body, a cloud's points as a surface with its weights;
                     other targets fall back to collocation), one level, the default
                     alpha beta gamma, no cap, not with --algorithm newton
  --distance F       symmetric | scan_to_body: the distance's form (docs/formulation.md
                     section 8; default: the scene target's "distance", else symmetric);
                     --distance, --cap or --cap-q replace the target's form as a whole
  --cap C            soft cap of every field value, C > 0 a length (default: the
                     target's "cap", else none)
  --cap-q Q          the cap's sharpness (default 4)
  --tikhonov-mass M  (M/2) int m^2 (default {tikhonov_mass})
  --tikhonov-grad E  (E/2) int |grad m|^2 (default {tikhonov_grad})
  --vtu-every K      VTU output every K iterations (default {vtu_every}; 0: start and end only)
  --checkpoint-every K  save the warm-start states every K iterations (default {checkpoint_every}): a
                     resume recomputes at most the K-1 iterations after the last save
  --coarse-levels C  auto | 0: the state solves' coarse start (as softhd forward's, at
                     most one level here: two-level starts), a large control step solved
                     first on the mesh with half the cells along the even axes, or for a
                     mesh file of order 2 as P1/Q1 on its vertices (default {coarse_levels}:
                     when that mesh has >= 32 elements; 0: none)
  --levels N         multilevel optimisation: solve first on the box halved N-1 times
                     (along its even axes; with none, every axis of >= 4 cells to
                     (n+1)/2: 25x5x1 -> 13x3x1; a mesh file of order 2: N = 2, its P1/Q1
                     level first) with a coarse target and tree tolerance
                     max(--tol, --coarse-tol T (default {coarse_tol})), at most
                     --coarse-iterations K (default {coarse_iterations}; at most --max-iter)
                     iterations per coarse level, ending earlier once rho decreased by less
                     than --switch-decrease S (default {switch_decrease}; relative, in [0, 1))
                     twice in a row; then the next finer level from its control (default {levels}:
                     automatic, where the target has a known map (an arc, a manufactured
                     state) 1 + every coarser level of >= 32 elements (bending: 3), else 1:
                     the user's mesh alone; 1 for a cloud without a known map, e.g. a scan;
                     docs/guide.md section 5)
  --refined-move-limit D  the move limit of each level started from a coarser
                     level's control (default {refined_move_limit}; --move-limit is the
                     coarsest level's)
  --threads T        OpenMP threads (default: all)
  --max-memory GIB   refuse meshes whose estimated memory exceeds this (default {max_memory})
  --state-backend B  cholmod | petsc-mumps | petsc-gamg: the state solver (default
                     {state_backend}, the serial Newton); the PETSc ones need softhd built with
                     -DSOFTHD_WITH_MPI=ON and distribute the state over the ranks of
                     mpiexec (docs/scaling.md section 4); PETSc options go in the
                     environment variable PETSC_OPTIONS
  --resume           continue the run recorded in DIR/checkpoint.bin: the same run
                     as an uninterrupted one (limits count over all resumes); a
                     checkpoint of another scene, target or options is refused
  --json             print summary.json on stdout at the end
  --quiet            no progress lines
  --help             this text

The defaults are those of Python's softhd.optimise too (TrackingRunOptions,
softhd/control/tracking_run.hpp).

scene targets ("target" in the scene file):
  {"kind": "arc", "angle": RAD [, "cells": [n1, n2, n3]]}  the plate bent into a
      circular arc (docs/formulation.md section 5.2), sampled on its own
      cell-centred grid
  {"kind": "cloud", "file": PATH [, "solved_on": SCENE]}  a cloud file; with solved_on
      it holds the deformed nodes of a state solved on SCENE's mesh ('softhd forward
      --write-cloud'), which gives the known map for the matched floor and shape error
  either kind also takes the distance's form (docs/formulation.md section 8):
      "distance": "symmetric" | "scan_to_body" | "visible"   (scan_to_body: rho = A,
          for a partial scan; visible: the body-to-scan term only over the body's
          boundary points seen from "camera", which implies it)
      "camera": [x, y, z]   the camera's position in the body's frame (3D)
      "surface": true   the target is a surface scan: the moving cloud is the body's
          boundary with its current facet areas (--particles boundary --volumes deformed)
      "cap": C  or  "cap": {"quantile": Q, "factor": F}   soft cap of every field
          value, fixed or F x the Q-quantile of the scan's d~ to the body at rest
      "cap_q": Q   the cap's sharpness (default 4)
      "quadrature": "collocation" | "cells"   where the distance is integrated
          (--quadrature overrides it)
  a cloud target may be in the camera's frame (docs/formulation.md section 8.10):
      "frame": "camera"   the pose (scan -> body) is refined with the control (then no
          "camera": the visible distance's camera is the pose's; no clean.crop)
      "align": "rigid" | "similarity"   what the pose may change (default rigid)
      "pose": FILE   the start pose (softhd align's pose.txt); default: align at rest
      --pose-method joint|projection   how the pose is refined (default {pose_method}):
          joint: its six variables join the optimiser's; projection: every evaluation
          fits the pose to the scan on its state (from the last one's pose) and the
          optimiser moves the control alone (rigid poses only)
      --pose-move F   the joint pose's move limit as a fraction of the control's, in
          (0, 1] (default {pose_move})
      the final pose is printed and written to summary.json ("pose") and history.csv

writes: history.csv, control.csv (readable by 'softhd forward --control'),
body_NNNN.vtu, target.vtu, body.pvd, body_final.ply, target.ply, summary.json,
checkpoint.bin, and the pictures convergence.png and shape.png (the final body against the
target) when python3 with matplotlib is available.

exit status: 0 done (also when stopped by --max-iter or --max-seconds); 1 numerical
failure (the state solve at the start or at the best control failed); 2 bad input or
refused (one line on stderr names the file, key or flag; also when another run holds
the --out folder's lock). Ctrl-C or a kill ends the run at once (status 130 or the
signal's); the checkpoint, history and summary written so far are complete, and
--resume continues the same run.

MPI builds: under 'mpiexec -n K softhd optimise ...' every rank runs the optimiser
on the same numbers: the distance's pair sums are split across the ranks (as in
softhd distance), the state is distributed with a PETSc backend and solved by
every rank with cholmod; rank 0 alone prints and writes files. A run resumes
only with the same backend and number of ranks.
)";

// A default for the help text: the shortest of the %e and %g forms that read back as v (%e
// on a tie), the exponent without a + and leading zeros (0.1, 4, 1e-2, 1e-6).
std::string number_text(double v) {
  std::string best;
  for (int precision = 0; precision < 17 && best.empty(); ++precision) {
    for (const char* format : {"%.*e", "%.*g"}) {
      char s[40];
      std::snprintf(s, sizeof s, format, precision, v);
      std::string t = s;
      const size_t e = t.find('e');
      if (e != std::string::npos) {
        const bool negative = t[e + 1] == '-';
        size_t digits = e + 2;
        while (digits + 1 < t.size() && t[digits] == '0') ++digits;
        t = t.substr(0, e) + (negative ? "e-" : "e") + t.substr(digits);
      }
      if (std::strtod(t.c_str(), nullptr) == v && (best.empty() || t.size() < best.size()))
        best = t;
    }
  }
  return best;
}

// kUsage with its {NAME} fields replaced by the defaults of TrackingRunOptions.
std::string usage() {
  const TrackingRunOptions d;
  const std::map<std::string, std::string> fields{
      {"max_iter", std::to_string(d.optimiser.max_iterations)},
      {"rel_tol", number_text(d.optimiser.relative_change)},
      {"algorithm", to_string(d.optimiser.algorithm)},
      {"hessian", to_string(d.optimiser.hessian)},
      {"move_limit", number_text(d.optimiser.move_limit)},
      {"particles", to_string(d.distance.particles)},
      {"volumes", to_string(d.distance.volumes)},
      {"alpha", number_text(d.distance.params.alpha)},
      {"beta", number_text(d.distance.params.beta)},
      {"gamma", number_text(d.distance.params.gamma)},
      {"eps", number_text(d.distance.params.epsilon)},
      {"method", to_string(d.distance.method)},
      {"tol", number_text(d.distance.tolerance)},
      {"tikhonov_mass", number_text(d.tikhonov.mass)},
      {"tikhonov_grad", number_text(d.tikhonov.gradient)},
      {"vtu_every", std::to_string(d.output.vtu_every)},
      {"checkpoint_every", std::to_string(d.output.checkpoint_every)},
      {"coarse_levels", to_string(d.state.coarse_levels)},
      {"levels", std::to_string(d.levels.count)},
      {"coarse_iterations", std::to_string(d.levels.coarse_iterations)},
      {"switch_decrease", number_text(d.levels.switch_decrease)},
      {"pose_move", number_text(d.pose.move)},
      {"pose_method", to_string(d.pose.method)},
      {"coarse_tol", number_text(d.levels.coarse_tolerance)},
      {"refined_move_limit", number_text(d.levels.refined_move_limit)},
      {"max_memory", number_text(d.memory_limit / (1u << 30))},
      {"state_backend", to_string(d.state.backend)}};
  std::string text = kUsage;
  for (const auto& [name, value] : fields) {
    const std::string key = "{" + name + "}";
    for (size_t at = text.find(key); at != std::string::npos; at = text.find(key, at))
      text.replace(at, key.size(), value);
  }
  return text;
}

// Calls f; an InvalidArgument it throws names the fields of TrackingRunOptions by their flags
// ("levels.refined_move_limit must be in [0, 1]" -> "--refined-move-limit must be ...").
template <class F>
void with_flag_names(F&& f) {
  try {
    f();
  } catch (const InvalidArgument& e) {
    throw InvalidArgument(name_fields(e.what(), FrontEnd::cli));
  }
}

struct OptimiseArgs {
  std::optional<std::string> out;
  std::string scene_file;
  TrackingRunOptions run;  // out and resume set once the scene is read
  bool resume = false, json = false, quiet = false;
};

// from_string(text), its InvalidArgument naming `flag`: "--algorithm: unknown algorithm 'x' ...".
template <class F>
auto named(const std::string& flag, const std::string& text, F from_string) {
  try {
    return from_string(text);
  } catch (const InvalidArgument& e) {
    throw UsageError(flag + ": " + e.what());
  }
}

// The value of `flag` (`fallback` if not given) read by from_string, its error naming the flag.
template <class F>
auto choice(Args& args, const std::string& flag, const std::string& fallback, F from_string) {
  return named(flag, args.value(flag).value_or(fallback), from_string);
}

// The objective's flags (the moving cloud, the distance, the Tikhonov weights).
void parse_objective(Args& args, const TrackingRunOptions& d, TrackingRunOptions& o) {
  o.distance.particles =
      choice(args, "--particles", to_string(d.distance.particles), particles_from_string);
  o.distance.volumes =
      choice(args, "--volumes", to_string(d.distance.volumes), particle_volumes_from_string);
  o.distance.params.alpha = args.number("--alpha", d.distance.params.alpha);
  o.distance.params.beta = args.number("--beta", d.distance.params.beta);
  o.distance.params.gamma = args.number("--gamma", d.distance.params.gamma);
  o.distance.params.epsilon = args.number("--eps", d.distance.params.epsilon);
  o.distance.method = choice(args, "--method", to_string(d.distance.method), method_from_string);
  if (o.distance.method == Method::nearest)
    throw UsageError("--method: nearest has no gradient; expected exact or tree");
  o.distance.tolerance = args.number("--tol", d.distance.tolerance);
  if (const std::optional<std::string> q = args.value("--quadrature"))
    o.distance.quadrature = named("--quadrature", *q, quadrature_from_string);
  o.tikhonov.mass = args.number("--tikhonov-mass", d.tikhonov.mass);
  o.tikhonov.gradient = args.number("--tikhonov-grad", d.tikhonov.gradient);
  const std::optional<std::string> distance = args.value("--distance");
  const std::optional<std::string> cap = args.value("--cap"), cap_q = args.value("--cap-q");
  if (distance || cap || cap_q) {
    TargetDistance form;
    if (distance) {
      form.sides = named("--distance", *distance, sides_from_string);
      if (form.sides == Sides::visible)
        throw UsageError(
            "--distance visible needs the camera: give the scene target's \"camera\" "
            "(it selects visible); expected symmetric or scan_to_body");
    }
    if (cap) form.cap = parse_number(*cap, "--cap");
    if (cap_q) form.cap_q = parse_number(*cap_q, "--cap-q");
    o.distance.form = form;
  }
}

OptimiseArgs parse_optimise(Args& args) {
  const TrackingRunOptions d;  // the defaults
  OptimiseArgs a;
  TrackingRunOptions& o = a.run;
  a.out = args.value("--out");
  o.target.file = args.value("--target").value_or("");
  o.optimiser.max_iterations =
      static_cast<int>(args.integer("--max-iter", d.optimiser.max_iterations, 1, 1000000));
  o.optimiser.max_seconds = args.number("--max-seconds", d.optimiser.max_seconds);
  o.optimiser.relative_change = args.number("--rel-tol", d.optimiser.relative_change);
  o.optimiser.algorithm =
      choice(args, "--algorithm", to_string(d.optimiser.algorithm), algorithm_from_string);
  o.optimiser.hessian =
      choice(args, "--hessian", to_string(d.optimiser.hessian),
             [](const std::string& name) { return hessian_part_from_string(name, "hessian"); });
  o.optimiser.move_limit = args.number("--move-limit", d.optimiser.move_limit);
  parse_objective(args, d, o);
  o.threads = static_cast<int>(args.integer("--threads", d.threads, 0, kMaxThreads));
  set_threads(o.threads);  // the FE assembly too
  o.output.vtu_every =
      static_cast<int>(args.integer("--vtu-every", d.output.vtu_every, 0, 1000000000));
  o.output.checkpoint_every =
      static_cast<int>(args.integer("--checkpoint-every", d.output.checkpoint_every, 1, 1000000));
  if (args.value("--coarse-level"))  // the retired spelling
    throw UsageError("--coarse-level is now --coarse-levels (auto or 0)");
  const std::string coarse =
      args.value("--coarse-levels").value_or(to_string(d.state.coarse_levels));
  if (coarse != "auto" && coarse != "0")
    throw UsageError(
        "--coarse-levels: expected auto or 0 (softhd optimise's state solves start "
        "from at most one coarse level), got '" +
        coarse + "'");
  o.state.coarse_levels = coarse_level_from_string(coarse);
  o.levels.count = static_cast<int>(args.integer("--levels", d.levels.count, 0, 16));
  o.levels.coarse_iterations =
      static_cast<int>(args.integer("--coarse-iterations", d.levels.coarse_iterations, 1, 1000000));
  o.levels.switch_decrease = args.number("--switch-decrease", d.levels.switch_decrease);
  o.levels.coarse_tolerance = args.number("--coarse-tol", d.levels.coarse_tolerance);
  o.levels.refined_move_limit = args.number("--refined-move-limit", d.levels.refined_move_limit);
  o.pose.move = args.number("--pose-move", d.pose.move);
  o.pose.method = choice(args, "--pose-method", to_string(d.pose.method), pose_method_from_string);
  const double gib = args.number("--max-memory", d.memory_limit / (1u << 30));
  if (!(gib > 0.0 && gib <= 1e6)) throw UsageError("--max-memory: expected GiB in (0, 1e6]");
  o.memory_limit = gib * (1u << 30);
  const std::string backend = args.value("--state-backend").value_or(to_string(d.state.backend));
  try {
    o.state.backend = fe::parse_state_backend(backend);
  } catch (const InvalidArgument& e) {
    throw UsageError(std::string("--state-backend: ") + e.what());
  }
  if (o.state.backend != fe::StateBackend::kCholmod && !fe::petsc_backend_available())
    throw UsageError("--state-backend " + backend +
                     " needs softhd built with -DSOFTHD_WITH_MPI=ON (this build has cholmod only)");
  a.resume = args.flag("--resume");
  a.json = args.flag("--json");
  a.quiet = args.flag("--quiet");
  const std::vector<std::string> pos = args.finish();
  if (pos.size() != 1) throw UsageError("expected one scene file (see --help)");
  a.scene_file = pos[0];
  validate_naming_fields(o, FrontEnd::cli);
  return a;
}

void print_start(const ShapeTrackingSummary& start) {
  std::fprintf(
      stderr, "  rho start %.6g, floor self %s, floor matched %s\n", start.rho_start,
      start.floor_self      ? std::to_string(*start.floor_self).c_str()
      : start.floor_matched ? "at the end, if the target is small enough"
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
  if (s.pose) {  // a camera-frame target: the pose found with the control (scan -> body)
    const Eigen::Matrix<double, 7, 1> w = s.pose->twist();
    std::fprintf(stderr,
                 "\n  pose (scan -> body): rotation %.4g deg about (%.4g, %.4g, %.4g), "
                 "translation (%.6g, %.6g, %.6g), scale %.6g",
                 w.head<3>().norm() * 180.0 / M_PI, w[0], w[1], w[2], w[3], w[4], w[5], s.pose->s);
  }
  std::fprintf(stderr, "\n  results in %s\n", out.string().c_str());
}

// The progress lines (none with --quiet).
TrackingRunCallbacks progress(const softhd::Scene& scene, bool quiet) {
  TrackingRunCallbacks cb;
  if (quiet) return cb;
  cb.on_begin = [&scene](const TrackingRunSummary& s) {
    std::fprintf(stderr, "softhd optimise %s: %ld nodes, %ld controls, target %ld points (%s)\n",
                 scene.name.c_str(), s.nodes, s.controls, s.target_points, s.target.c_str());
    if (!s.coarse_level.empty())
      std::fprintf(stderr, "  two-level starts on the coarse level (%s)\n", s.coarse_level.c_str());
  };
  cb.on_start = print_start;
  cb.on_failure = [](const std::string& report) {
    std::fprintf(stderr, "  state solve failed (step rejected): %s\n", report.c_str());
  };
  cb.on_iteration = [](const TrackingIteration& it, const Eigen::VectorXd&) {
    char level[32] = "";
    if (it.level > 0) std::snprintf(level, sizeof level, " (level %d)", it.level);
    std::fprintf(stderr, "  %5d %12.6g %12.6g %10.4g %10.3g %7d %8.1f%s%s\n", it.iteration, it.J,
                 it.rho, it.rho_over_floor, it.projected_gradient_norm, it.newton_iterations,
                 it.seconds, level, it.replayed ? " (from the checkpoint)" : "");
  };
  return cb;
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

// --out (or results/<scene name>), created here so that its error names the flag.
fs::path output_directory(const OptimiseArgs& a, const softhd::Scene& scene) {
  const fs::path out = a.out ? fs::path(*a.out) : fs::path("results") / scene.name;
  std::error_code ec;
  fs::create_directories(out, ec);
  if (ec || !fs::is_directory(out))
    throw FileError("--out: cannot create the directory '" + out.string() + "'" +
                    (ec ? " (" + ec.message() + ")" : ""));
  return out;
}

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace

int run_optimise(const std::vector<std::string>& tokens) {
  // Under mpiexec every rank runs all of this on the same numbers; rank 0 writes and prints.
  const bool writer = world_rank() == 0;
  Args args(tokens);
  if (args.flag("--help")) {
    if (writer) std::cout << usage();
    return 0;
  }
  OptimiseArgs a = parse_optimise(args);
  a.run.share = world_share();  // null unless started by mpiexec with K > 1 ranks
  if (!writer) a.quiet = true;

  const softhd::Scene scene = softhd::load_scene(a.scene_file, a.run.memory_limit);
  a.run.output.folder = (a.out ? fs::path(*a.out) : fs::path("results") / scene.name).string();
  a.run.output.resume = a.resume;
  std::unique_ptr<TrackingRun> run;  // the body, the target and the objective
  with_flag_names([&] { run = std::make_unique<TrackingRun>(scene, a.run); });
  const fs::path out = output_directory(a, scene);
  const TrackingRunSummary s = run->run(progress(scene, a.quiet));
  if (!writer) return 0;
#ifdef SOFTHD_PLOT_SCRIPT
  // No shell: the folder is one argument, whatever characters it holds.
  const int status = run_quietly({"/usr/bin/python3", SOFTHD_PLOT_SCRIPT, out.string()});
  if (status != 0 && !a.quiet)
    std::fprintf(stderr, "  (convergence.png and shape.png not drawn: %s)\n",
                 status == 3    ? "needs python3-matplotlib"
                 : status == -1 ? "cannot run /usr/bin/python3"
                                : "scripts/plot_run.py failed");
#endif
  if (!a.quiet) {
    for (const LevelReport& l : s.levels) std::fprintf(stderr, "  %s\n", l.BriefReport().c_str());
    print_end(s, out);
  }
  if (a.json) std::cout << read_text(out / "summary.json");
  return 0;
}

}  // namespace softhd::cli
