// The table of TrackingRunOptions' fields (tracking_run_fields) against the options and the
// command line: every field of every group has a row; every row's flag is in `softhd optimise
// --help` and every flag there is a row's or a CLI-only one; every flag is used by a test; a
// row without a flag or keyword says why; name_fields rewrites paths to the front end's names;
// every field changes the checkpoint's fingerprint or its row says why it may not.
// The Python keywords are checked against the same table in tests/python/test_optimise.py.

#include <gtest/gtest.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "softhd/control/run_fields.hpp"
#include "softhd/control/scene.hpp"
#include "softhd/control/tracking_run.hpp"
#include "softhd/error.hpp"
#include "softhd/scan/pose.hpp"
#include "softhd/work_share.hpp"

extern char** environ;

namespace {

namespace fs = std::filesystem;
using softhd::FrontEnd;
using softhd::name_fields;
using softhd::RunField;
using softhd::tracking_run_fields;
using softhd::TrackingRunOptions;

// The distinct names that follow `prefix` ("" for the top level, "levels." for a group) in the
// table's paths: the fields of that struct the table covers.
std::set<std::string> fields_under(const std::string& prefix) {
  std::set<std::string> names;
  for (const RunField& f : tracking_run_fields()) {
    const std::string path = f.path;
    if (path.compare(0, prefix.size(), prefix) != 0) continue;
    const std::string rest = path.substr(prefix.size());
    names.insert(rest.substr(0, rest.find('.')));
  }
  return names;
}

// Each structured binding below lists the struct's fields and stops compiling when a field is
// added or removed: then add or remove its row in tracking_run_fields() (and the flag and the
// keyword, or the reason for none) and update the binding.
TEST(RunFields, EveryFieldOfTheOptionsHasARow) {
  TrackingRunOptions o;
  [[maybe_unused]] auto& [optimiser, distance, tikhonov, target, state, levels, pose, output,
                          threads, share, memory_limit] = o;
  EXPECT_EQ(fields_under("").size(), 11u);
  [[maybe_unused]] auto& [algorithm, hessian, max_iterations, max_evaluations, max_seconds,
                          relative_change, move_limit, initial_control] = o.optimiser;
  EXPECT_EQ(fields_under("optimiser.").size(), 8u);
  [[maybe_unused]] auto& [particles, volumes, params, method, tolerance, form, quadrature] =
      o.distance;
  EXPECT_EQ(fields_under("distance.").size(), 7u);
  [[maybe_unused]] auto& [alpha, beta, gamma, epsilon] = o.distance.params;
  EXPECT_EQ(fields_under("distance.params.").size(), 4u);
  softhd::TargetDistance d;
  [[maybe_unused]] auto& [sides, cap, cap_quantile, cap_factor, cap_q] = d;
  EXPECT_EQ(fields_under("distance.form.").size(), 5u);
  [[maybe_unused]] auto& [mass, gradient] = o.tikhonov;
  EXPECT_EQ(fields_under("tikhonov.").size(), 2u);
  [[maybe_unused]] auto& [file] = o.target;
  EXPECT_EQ(fields_under("target.").size(), 1u);
  [[maybe_unused]] auto& [backend, coarse_levels] = o.state;
  EXPECT_EQ(fields_under("state.").size(), 2u);
  [[maybe_unused]] auto& [count, coarse_iterations, switch_decrease, coarse_tolerance,
                          refined_move_limit] = o.levels;
  EXPECT_EQ(fields_under("levels.").size(), 5u);
  [[maybe_unused]] auto& [pose_method, move] = o.pose;
  EXPECT_EQ(fields_under("pose.").size(), 2u);
  [[maybe_unused]] auto& [folder, resume, checkpoint_every, vtu_every] = o.output;
  EXPECT_EQ(fields_under("output.").size(), 4u);
  // No path twice, and the groups by the names the header gives them.
  std::set<std::string> paths;
  for (const RunField& f : tracking_run_fields())
    EXPECT_TRUE(paths.insert(f.path).second) << f.path;
  EXPECT_EQ(fields_under(""),
            (std::set<std::string>{"optimiser", "distance", "tikhonov", "target", "state", "levels",
                                   "pose", "output", "threads", "share", "memory_limit"}));
}

// A row names the field on both front ends, or says why one (or both) has no name for it.
TEST(RunFields, EveryRowWithoutAFlagOrKeywordSaysWhy) {
  for (const RunField& f : tracking_run_fields()) {
    const bool both = *f.flag != '\0' && *f.keyword != '\0';
    EXPECT_EQ(both, *f.why_not == '\0') << f.path << ": " << f.why_not;
    if (*f.flag != '\0') {
      EXPECT_EQ(std::string(f.flag).rfind("--", 0), 0u) << f.path;
    }
  }
}

// The standard output of the program argv[0] run with the arguments argv (no shell).
std::string program_output(const std::vector<std::string>& argv) {
  int fds[2];
  if (pipe(fds) != 0) return "";
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, fds[1], 1);
  posix_spawn_file_actions_addclose(&actions, fds[0]);
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  pid_t pid = 0;
  const int spawned = posix_spawn(&pid, args[0], &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  close(fds[1]);
  std::string out;
  char buffer[4096];
  for (ssize_t n; (n = read(fds[0], buffer, sizeof buffer)) > 0;)
    out.append(buffer, static_cast<size_t>(n));
  close(fds[0]);
  if (spawned == 0) waitpid(pid, nullptr, 0);
  return out;
}

// The flags `softhd optimise --help` names (those of other commands, quoted as 'softhd forward
// --control', left out).
std::set<std::string> help_flags() {
  const std::string help = std::regex_replace(program_output({SOFTHD_CLI, "optimise", "--help"}),
                                              std::regex("'softhd [^']*'"), "");
  std::set<std::string> flags;
  const std::regex flag("--[a-z][a-z0-9-]*");
  for (auto it = std::sregex_iterator(help.begin(), help.end(), flag); it != std::sregex_iterator();
       ++it)
    flags.insert(it->str());
  return flags;
}

TEST(RunFields, TheHelpNamesEveryFlagOfTheTableAndNoOther) {
  const std::set<std::string> help = help_flags();
  ASSERT_GT(help.size(), 20u) << "the help text was not read";
  std::set<std::string> known;
  for (const RunField& f : tracking_run_fields()) {
    if (*f.flag == '\0') continue;
    known.insert(f.flag);
    EXPECT_EQ(help.count(f.flag), 1u) << f.flag << " (" << f.path << ") is not in --help";
  }
  for (const softhd::CliOnlyFlag& f : softhd::optimise_cli_only_flags()) {
    known.insert(f.flag);
    EXPECT_EQ(help.count(f.flag), 1u) << f.flag << " is not in --help";
  }
  for (const std::string& f : help)
    EXPECT_EQ(known.count(f), 1u) << f << " in --help sets no field of the table";
}

// Every flag of softhd optimise appears in a test of the command line or of Python (which runs
// the command line for its comparisons).
TEST(RunFields, EveryFlagIsUsedByATest) {
  std::string tests;
  for (const char* dir : {"tests", "tests/python", "tests/mpi"}) {
    for (const auto& entry : fs::directory_iterator(fs::path(SOFTHD_SOURCE_DIR) / dir)) {
      const std::string ext = entry.path().extension().string();
      if (entry.path().filename() == "test_run_fields.cpp" || (ext != ".cpp" && ext != ".py"))
        continue;
      std::ifstream in(entry.path());
      std::stringstream s;
      s << in.rdbuf();
      tests += s.str();
    }
  }
  auto used = [&](const std::string& flag) {
    // As written in a C++ test ("--flag ...") or in a Python argument list ("--flag", ...).
    return tests.find(flag + " ") != std::string::npos ||
           tests.find(flag + "\"") != std::string::npos;
  };
  for (const RunField& f : tracking_run_fields())
    if (*f.flag != '\0') {
      EXPECT_TRUE(used(f.flag)) << f.flag << " (" << f.path << ")";
    }
  for (const softhd::CliOnlyFlag& f : softhd::optimise_cli_only_flags())
    EXPECT_TRUE(used(f.flag)) << f.flag;
}

TEST(RunFields, MessagesNameTheFieldsByTheFrontEndsNames) {
  EXPECT_EQ(name_fields("levels.refined_move_limit must be in [0, 1]", FrontEnd::cli),
            "--refined-move-limit must be in [0, 1]");
  EXPECT_EQ(name_fields("levels.refined_move_limit must be in [0, 1]", FrontEnd::python),
            "refined_move_limit must be in [0, 1]");
  EXPECT_EQ(name_fields("levels.count: 3 asks for 2 coarser levels", FrontEnd::cli),
            "--levels: 3 asks for 2 coarser levels");
  // A path inside a longer one is the longer one's: distance.form.cap_q is not --cap + "_q".
  EXPECT_EQ(name_fields("distance.form.cap_q must be finite", FrontEnd::cli),
            "--cap-q must be finite");
  EXPECT_EQ(name_fields("distance.form.cap must be 0", FrontEnd::cli), "--cap must be 0");
  // Every occurrence, and one at a sentence's end; an index stays with its name.
  EXPECT_EQ(name_fields("optimiser.initial_control: a multilevel run (levels.count > 1) starts "
                        "there; give levels.count 1.",
                        FrontEnd::python),
            "initial: a multilevel run (levels > 1) starts there; give levels 1.");
  EXPECT_EQ(name_fields("optimiser.initial_control[3] = 5 is outside", FrontEnd::python),
            "initial[3] = 5 is outside");
  // A field the front end cannot set keeps its path; other words stay.
  EXPECT_EQ(name_fields("optimiser.initial_control[3] = 5", FrontEnd::cli),
            "optimiser.initial_control[3] = 5");
  EXPECT_EQ(name_fields("xlevels.count and levels.counts and pose.move", FrontEnd::cli),
            "xlevels.count and levels.counts and --pose-move");
}

// What each front end says for an invalid field: validate() names the path, the front end its
// own name for it.
TEST(RunFields, ValidateNamesTheNestedPath) {
  TrackingRunOptions o;
  o.levels.refined_move_limit = 2.0;
  try {
    o.validate();
    FAIL() << "not refused";
  } catch (const softhd::InvalidArgument& e) {
    EXPECT_EQ(std::string(e.what()), "levels.refined_move_limit must be in [0, 1]");
  }
  o = TrackingRunOptions{};
  o.optimiser.max_iterations = 0;
  try {
    o.validate();
    FAIL() << "not refused";
  } catch (const softhd::InvalidArgument& e) {
    EXPECT_EQ(std::string(e.what()).rfind("optimiser.max_iterations must be >= 1", 0), 0u)
        << e.what();
  }
}

// A check of the objective's or the optimiser's own names no path: the field to blame is the
// first that is invalid on its own, by the front end's name.
TEST(RunFields, ValidateNamingFieldsBlamesTheFieldByItsName) {
  TrackingRunOptions o;
  o.optimiser.max_iterations = 7;  // valid: not blamed
  o.tikhonov.gradient = -1.0;
  auto message = [&](FrontEnd front_end) {
    try {
      softhd::validate_naming_fields(o, front_end);
    } catch (const softhd::InvalidArgument& e) {
      return std::string(e.what());
    }
    return std::string("not refused");
  };
  EXPECT_EQ(message(FrontEnd::cli).rfind("--tikhonov-grad: tikhonov_gradient", 0), 0u)
      << message(FrontEnd::cli);
  EXPECT_EQ(message(FrontEnd::python).rfind("tikhonov_grad: tikhonov_gradient", 0), 0u)
      << message(FrontEnd::python);
  // A path in the message is replaced, not prefixed.
  o = TrackingRunOptions{};
  o.levels.switch_decrease = 1.0;
  EXPECT_EQ(message(FrontEnd::cli), "--switch-decrease must be in [0, 1)");
  EXPECT_EQ(message(FrontEnd::python), "switch_decrease must be in [0, 1)");
  o = TrackingRunOptions{};
  EXPECT_EQ(message(FrontEnd::cli), "not refused");
}

}  // namespace

// The checkpoint's fingerprint against the table: every field, set to another valid value,
// changes the fingerprint of some checkpoint of the run (TrackingRun::fingerprints, built from
// the options without running), or its row says why it may not (fingerprint_free: a limit, an
// output setting) and then it changes none. A field matters only in some runs (the levels'
// with levels.count > 1, pose.move with a pose, optimiser.hessian with newton, a cap's q with a
// cap, the two-level starts on a mesh with a coarse level): each is varied from a run of its
// group.
namespace {

using softhd::RunFingerprint;
using softhd::TrackingRun;

// A 3D box with an arc target: (6, 1, 2) cells halve once for levels.count 2 (to (3, 1, 1));
// (16, 4, 4) has the two-level starts' coarse level (8, 2, 2), 32 elements.
softhd::Scene box_scene(const std::string& cells) {
  return softhd::parse_scene(R"({
    "mesh": { "type": "box", "lower": [0, 0, 0], "upper": [3, 0.6, 0.3], "cells": )" +
                                 cells + R"(, "order": 1 },
    "material": { "model": "mooney_rivlin", "a": 1e5, "b": 2e4, "c": 3e5 },
    "fibers": [1, 0, 0], "clamp": ["x0"],
    "control": { "space": "element", "lower": -1e5, "upper": 0, "initial": -10 },
    "target": { "kind": "arc", "angle": 0.5 } })",
                             "fingerprint.json");
}

enum class Group { single, newton, levels, pose, cap, cap_rule, two_level };

struct Variant {
  Group group;
  std::function<void(TrackingRunOptions&)> change;  // to another valid value
};

// The base run of each group: one level, MMA, one thread, the scene's target.
TrackingRunOptions base_options(Group g) {
  TrackingRunOptions o;
  o.levels.count = g == Group::levels ? 2 : 1;
  o.threads = 1;
  if (g == Group::newton) o.optimiser.algorithm = softhd::Algorithm::newton;
  if (g == Group::cap) o.distance.form = softhd::TargetDistance{};
  if (g == Group::cap) o.distance.form->cap = 0.1;
  if (g == Group::cap_rule) o.distance.form = softhd::TargetDistance{};
  if (g == Group::cap_rule) o.distance.form->cap_quantile = 0.5;
  if (g == Group::cap_rule) o.distance.form->cap_factor = 2.0;
  return o;
}

// The fingerprints of a run of `options` in group g (the pose's: the scene's target in the
// camera's frame, from the identity pose).
std::vector<RunFingerprint> fingerprints(Group g, const TrackingRunOptions& options) {
  static const softhd::Scene small = box_scene("[6, 1, 2]"), large = box_scene("[16, 4, 4]");
  const softhd::Scene& scene = g == Group::two_level ? large : small;
  if (g != Group::pose) return TrackingRun(scene, options).fingerprints();
  const softhd::fe::Assembler a = scene.body.make_assembler();
  const softhd::fe::ControlSpace c = scene.body.make_control_space(a);
  softhd::SceneTarget target = softhd::tracking_target(scene, a.mesh(), options);
  target.frame = softhd::TargetFrame::camera;
  target.pose = softhd::scan::Pose{};
  return TrackingRun(scene, a, c, std::move(target), options).fingerprints();
}

// A target cloud file of four points (the target.file variant).
std::string cloud_file() {
  const std::string path = (fs::path(::testing::TempDir()) / "softhd_fingerprint.xyz").string();
  std::ofstream(path) << "0 0 0\n1 0 0\n2 0.1 0\n3 0.2 0.1\n";
  return path;
}

// A share of two processes (the CLI's ranks under mpiexec); its sums are never called here.
struct TwoRanks : softhd::WorkShare {
  int size() const override { return 2; }
  int rank() const override { return 0; }
  void sum(double*, std::size_t) const override {}
  void sum(std::int64_t*, std::size_t) const override {}
};

std::map<std::string, Variant> variants() {
  using O = TrackingRunOptions;
  const Group s = Group::single, l = Group::levels;
  return {
      {"optimiser.algorithm", {s, [](O& o) { o.optimiser.algorithm = softhd::Algorithm::newton; }}},
      {"optimiser.hessian",
       {Group::newton, [](O& o) { o.optimiser.hessian = softhd::HessianPart::gauss_newton; }}},
      {"optimiser.max_iterations", {s, [](O& o) { o.optimiser.max_iterations = 7; }}},
      {"optimiser.max_evaluations", {s, [](O& o) { o.optimiser.max_evaluations = 99; }}},
      {"optimiser.max_seconds", {s, [](O& o) { o.optimiser.max_seconds = 5.0; }}},
      {"optimiser.relative_change", {s, [](O& o) { o.optimiser.relative_change = 3e-4; }}},
      {"optimiser.move_limit", {s, [](O& o) { o.optimiser.move_limit = 0.05; }}},
      // The scene's 12 element controls, inside their bounds [-1e5, 0].
      {"optimiser.initial_control",
       {s, [](O& o) { o.optimiser.initial_control = Eigen::VectorXd::Constant(12, -5.0); }}},
      {"distance.particles",
       {s, [](O& o) { o.distance.particles = softhd::Particles::quadrature; }}},
      {"distance.volumes",
       {s, [](O& o) { o.distance.volumes = softhd::ParticleVolumes::deformed; }}},
      {"distance.params.alpha", {s, [](O& o) { o.distance.params.alpha = 5.0; }}},
      {"distance.params.beta", {s, [](O& o) { o.distance.params.beta = 5.0; }}},
      {"distance.params.gamma", {s, [](O& o) { o.distance.params.gamma = 3.0; }}},
      {"distance.params.epsilon", {s, [](O& o) { o.distance.params.epsilon = 2e-3; }}},
      {"distance.method", {s, [](O& o) { o.distance.method = softhd::Method::exact; }}},
      {"distance.tolerance", {s, [](O& o) { o.distance.tolerance = 2e-2; }}},
      // The scene's arc has cells.
      {"distance.quadrature", {s, [](O& o) { o.distance.quadrature = softhd::Quadrature::cells; }}},
      {"distance.form.sides",
       {s, [](O& o) { o.distance.form.emplace().sides = softhd::Sides::scan_to_body; }}},
      {"distance.form.cap", {s, [](O& o) { o.distance.form.emplace().cap = 0.1; }}},
      {"distance.form.cap_q", {Group::cap, [](O& o) { o.distance.form->cap_q = 8.0; }}},
      {"distance.form.cap_quantile",
       {Group::cap_rule, [](O& o) { o.distance.form->cap_quantile = 0.9; }}},
      {"distance.form.cap_factor",
       {Group::cap_rule, [](O& o) { o.distance.form->cap_factor = 3.0; }}},
      {"tikhonov.mass", {s, [](O& o) { o.tikhonov.mass = 1e-6; }}},
      {"tikhonov.gradient", {s, [](O& o) { o.tikhonov.gradient = 1e-6; }}},
      {"target.file", {s, [](O& o) { o.target.file = cloud_file(); }}},
      {"state.backend", {s, [](O& o) { o.state.backend = softhd::fe::StateBackend::kPetscMumps; }}},
      {"state.coarse_levels",
       {Group::two_level, [](O& o) { o.state.coarse_levels = softhd::CoarseLevel::off; }}},
      {"levels.count", {s, [](O& o) { o.levels.count = 2; }}},
      {"levels.coarse_iterations", {l, [](O& o) { o.levels.coarse_iterations = 3; }}},
      {"levels.switch_decrease", {l, [](O& o) { o.levels.switch_decrease = 0.05; }}},
      {"levels.coarse_tolerance", {l, [](O& o) { o.levels.coarse_tolerance = 0.1; }}},
      {"levels.refined_move_limit", {l, [](O& o) { o.levels.refined_move_limit = 0.05; }}},
      {"pose.method", {Group::pose, [](O& o) { o.pose.method = softhd::PoseMethod::projection; }}},
      {"pose.move", {Group::pose, [](O& o) { o.pose.move = 0.5; }}},
      {"output.folder", {s, [](O& o) { o.output.folder = "elsewhere"; }}},
      // (resume needs a folder, itself free)
      {"output.resume", {s, [](O& o) { o.output.folder = "elsewhere", o.output.resume = true; }}},
      {"output.checkpoint_every", {s, [](O& o) { o.output.checkpoint_every = 3; }}},
      {"output.vtu_every", {s, [](O& o) { o.output.vtu_every = 3; }}},
      {"threads", {s, [](O& o) { o.threads = 2; }}},
      {"share", {s, [](O& o) { o.share = std::make_shared<TwoRanks>(); }}},
      {"memory_limit", {s, [](O& o) { o.memory_limit = 1e10; }}},
  };
}

TEST(RunFields, EveryFieldChangesTheFingerprintOrIsDeclaredFree) {
  const std::map<std::string, Variant> all = variants();
  std::map<Group, std::vector<RunFingerprint>> bases;
  for (const RunField& f : tracking_run_fields()) {
    const auto it = all.find(f.path);
    if (it == all.end()) {
      ADD_FAILURE() << f.path << ": no variant here; add one (its group and another value)";
      continue;
    }
    const Group g = it->second.group;
    if (!bases.count(g)) bases[g] = fingerprints(g, base_options(g));
    TrackingRunOptions o = base_options(g);
    it->second.change(o);
    std::vector<RunFingerprint> changed;
    try {
      changed = fingerprints(g, o);
    } catch (const softhd::Error& e) {
      // A PETSc backend is made under mpiexec only (PETSc initialised; an MPI build):
      // tests/mpi/cli_mpi.py resumes a petsc-mumps run with cholmod and expects it refused.
      if (f.path == std::string("state.backend")) {
        std::printf("state.backend: not varied here (%s); tests/mpi/cli_mpi.py checks it\n",
                    e.what());
        continue;
      }
      ADD_FAILURE() << f.path << ": the variant is refused: " << e.what();
      continue;
    }
    if (f.fingerprint_free) {
      EXPECT_TRUE(changed == bases[g]) << f.path << " is declared free of the fingerprint ("
                                       << f.fingerprint_free << ") but changes it";
    } else {
      EXPECT_TRUE(changed != bases[g])
          << f.path << " changes no checkpoint's fingerprint: a resume with another value "
          << "would be accepted; record it (run_fingerprint) or say in its row why it is free";
    }
  }
  EXPECT_EQ(all.size(), tracking_run_fields().size()) << "a variant of a field the table lacks";
}

// The β a fingerprint records ("alpha … beta B gamma …", B in C's %a, which strtod reads).
double fingerprint_beta(const RunFingerprint& f) {
  const std::string& d = f.at("distance");
  const std::size_t at = d.find(" beta ");
  EXPECT_NE(at, std::string::npos) << d;
  return std::strtod(d.c_str() + at + 6, nullptr);
}

// β 0 (the default) is automatic: the paper's 4 for the symmetric distance, 2 for the scan
// forms, on every level; a β given is used for every form. The run's objective is what the
// fingerprint records (the β its distance is evaluated with).
TEST(RunFields, TheScanFormsTakeBetaTwoUnlessBetaIsGiven) {
  EXPECT_EQ(TrackingRunOptions{}.distance.params.beta, 0.0);
  for (const double given : {0.0, 3.0}) {
    for (const auto sides : {softhd::Sides::symmetric, softhd::Sides::scan_to_body}) {
      TrackingRunOptions o = base_options(Group::levels);  // two levels
      o.distance.params.beta = given;
      o.distance.form.emplace().sides = sides;
      const double expected = given != 0.0                        ? given
                              : sides == softhd::Sides::symmetric ? 4.0
                                                                  : softhd::kScanFormBeta;
      const std::vector<RunFingerprint> f = fingerprints(Group::levels, o);
      ASSERT_EQ(f.size(), 2u);
      for (const RunFingerprint& level : f)
        EXPECT_EQ(fingerprint_beta(level), expected) << softhd::to_string(sides) << " " << given;
    }
  }
  EXPECT_EQ(softhd::kScanFormBeta, 2.0);
  // The target block's form (distance.form unset), on both levels; a target block's camera
  // (with its visible form, as the scene's reader sets it).
  const softhd::Scene scene = box_scene("[6, 1, 2]");
  const softhd::fe::Assembler a = scene.body.make_assembler();
  const softhd::fe::ControlSpace c = scene.body.make_control_space(a);
  for (const bool camera : {false, true}) {
    TrackingRunOptions o = base_options(camera ? Group::single : Group::levels);
    softhd::SceneTarget target = softhd::tracking_target(scene, a.mesh(), o);
    target.distance.sides = camera ? softhd::Sides::visible : softhd::Sides::scan_to_body;
    if (camera) target.camera = Eigen::Vector3d(3.0, 0.5, 20.0);
    const std::vector<RunFingerprint> f =
        TrackingRun(scene, a, c, std::move(target), o).fingerprints();
    ASSERT_EQ(f.size(), camera ? 1u : 2u);
    for (const RunFingerprint& level : f)
      EXPECT_EQ(fingerprint_beta(level), softhd::kScanFormBeta) << "camera " << camera;
  }
}

}  // namespace
