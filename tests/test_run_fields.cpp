// The table of TrackingRunOptions' fields (tracking_run_fields) against the options and the
// command line: every field of every group has a row; every row's flag is in `softhd optimise
// --help` and every flag there is a row's or a CLI-only one; every flag is used by a test; a
// row without a flag or keyword says why; name_fields rewrites paths to the front end's names.
// The Python keywords are checked against the same table in tests/python/test_optimise.py.

#include <gtest/gtest.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "softhd/control/run_fields.hpp"
#include "softhd/control/tracking_run.hpp"
#include "softhd/error.hpp"

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
  [[maybe_unused]] auto& [particles, volumes, params, method, tolerance, form] = o.distance;
  EXPECT_EQ(fields_under("distance.").size(), 6u);
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
  [[maybe_unused]] auto& [move] = o.pose;
  EXPECT_EQ(fields_under("pose.").size(), 1u);
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
