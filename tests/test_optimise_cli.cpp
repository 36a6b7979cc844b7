// softhd optimise end to end on a small plate: it lowers ρ̃, writes every promised
// file, resumed after kills it is the uninterrupted run, and bad input gets exit code 2.

#include <fcntl.h>
#include <gtest/gtest.h>
#include <spawn.h>
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <tuple>
#include <utility>
#include <vector>

#include "softhd/control/pose_file.hpp"
#include "softhd/fe/state_backend.hpp"
#include "softhd/io/cloud_io.hpp"
#include "softhd/scan/pose.hpp"

extern char** environ;

namespace {

namespace fs = std::filesystem;

const char* kScene = R"({
  "name": "small_bend",
  "mesh": { "type": "box", "lower": [0, 0, 0], "upper": [2, 0.4, 0.2], "cells": [6, 1, 2], "order": 1 },
  "material": { "model": "mooney_rivlin", "a": 1e5, "b": 2e4, "c": 3e5 },
  "fibers": [1, 0, 0],
  "clamp": ["x0"],
  "control": { "space": "vertex", "lower": -1e5, "upper": 0, "initial": 0 },
  "target": { "kind": "arc", "angle": 0.6, "cells": [12, 2, 4] }
})";

class OptimiseCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::path(::testing::TempDir()) /
           ("softhd_opt_" +
            std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    std::ofstream(scene()) << kScene;
  }
  std::string scene() const { return (dir_ / "scene.json").string(); }
  std::string out() const { return (dir_ / "out").string(); }
  int run(const std::string& args, std::string* err = nullptr) const {
    const std::string e = (dir_ / "stderr").string();
    const std::string cmd = std::string(SOFTHD_CLI) + " optimise " + args + " >" +
                            (dir_ / "stdout").string() + " 2>" + e;
    const int raw = std::system(cmd.c_str());
    if (err) {
      std::stringstream s;
      s << std::ifstream(e).rdbuf();
      *err = s.str();
    }
    return WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  }
  nlohmann::json summary() const {
    return nlohmann::json::parse(std::ifstream(fs::path(out()) / "summary.json"));
  }
  /// `softhd forward SCENE --control-uniform -3e4 --write-cloud CLOUD` (a manufactured target
  /// on the scene's own mesh), run with an argument vector, no shell; its exit status.
  int write_forward_cloud(const fs::path& cloud) const {
    const std::string fwd = (dir_ / "fwd").string(), c = cloud.string(), sc = scene();
    std::vector<std::string> args = {
        SOFTHD_CLI, "forward", sc, "--control-uniform", "-3e4", "--write-cloud", c, "--out", fwd};
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t quiet;
    posix_spawn_file_actions_init(&quiet);
    posix_spawn_file_actions_addopen(&quiet, 1, "/dev/null", O_WRONLY, 0);
    posix_spawn_file_actions_addopen(&quiet, 2, "/dev/null", O_WRONLY, 0);
    pid_t pid = 0;
    const int spawned = posix_spawn(&pid, argv[0], &quiet, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&quiet);
    int raw = 0;
    if (spawned != 0 || waitpid(pid, &raw, 0) != pid) return -1;
    return WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  }
  fs::path dir_;
};

TEST_F(OptimiseCli, LowersTheDistanceAndWritesEveryFile) {
  std::string err;
  ASSERT_EQ(run(scene() + " --out " + out() + " --max-iter 6 --quiet", &err), 0) << err;
  const nlohmann::json s = summary();
  for (const char* key : {"rho_start", "floor_self", "floor_matched", "rho_final", "iterations",
                          "evaluations", "termination", "shape_error_max", "shape_error_rms",
                          "seconds", "seconds_state", "seconds_distance", "seconds_adjoint"})
    EXPECT_TRUE(s.contains(key)) << key;
  EXPECT_LT(s["rho_final"].get<double>(), s["rho_start"].get<double>());
  EXPECT_GT(s["floor_matched"].get<double>(), 0.0);
  EXPECT_EQ(s["iterations"].get<int>(), 6);
  EXPECT_EQ(s["status"], "finished");
  for (const char* f :
       {"history.csv", "control.csv", "body.pvd", "body_0000.vtu", "target.vtu", "checkpoint.bin"})
    EXPECT_TRUE(fs::exists(fs::path(out()) / f)) << f;
  // control.csv: one row per vertex control (7 x 2 x 3 vertices), 4 columns.
  std::ifstream c(fs::path(out()) / "control.csv");
  std::string line;
  int rows = 0;
  while (std::getline(c, line))
    if (!line.empty() && line[0] != '#') ++rows;
  EXPECT_EQ(rows, 7 * 2 * 3);
  // ... in the format 'softhd forward --control' reads.
  const std::string forward = std::string(SOFTHD_CLI) + " forward " + scene() + " --control " +
                              (fs::path(out()) / "control.csv").string() + " --out " +
                              (dir_ / "fwd").string() + " >/dev/null 2>&1";
  const int raw = std::system(forward.c_str());
  EXPECT_TRUE(WIFEXITED(raw) && WEXITSTATUS(raw) == 0) << forward;
}

// --algorithm newton: the trust-region Newton–CG with the exact Hessian-vector product, or its
// Gauss–Newton part, lowers ρ̃; history.csv gets its CG iterations, products and trust radius.
TEST_F(OptimiseCli, NewtonLowersTheDistanceAndRecordsItsSteps) {
  for (const char* part : {"full", "gauss_newton"}) {
    std::string err;
    ASSERT_EQ(run(scene() + " --out " + out() + " --max-iter 3 --quiet --algorithm newton " +
                      "--hessian " + part,
                  &err),
              0)
        << part << ": " << err;
    const nlohmann::json s = summary();
    EXPECT_LT(s["rho_final"].get<double>(), s["rho_start"].get<double>()) << part;
    EXPECT_GE(s["iterations"].get<int>(), 1) << part;
    std::ifstream h(fs::path(out()) / "history.csv");
    std::string header, row;
    std::getline(h, header);
    EXPECT_NE(header.find(",level,cg_iterations,hessian_products,trust_radius"), std::string::npos)
        << header;
    ASSERT_TRUE(std::getline(h, row)) << part;
    // The first iteration made products (the last three columns: CG, products, radius > 0).
    const std::string tail = row.substr(row.find_last_of(',') + 1);
    EXPECT_GT(std::stod(tail), 0.0) << row;
    fs::remove_all(out());
  }
}

std::string read_text(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// history.csv without the timing columns (seconds_state, seconds_distance, seconds_adjoint,
// seconds: the 11th to the 14th; the level column after them is kept).
std::string history_without_timings(const fs::path& dir) {
  std::istringstream in(read_text(dir / "history.csv"));
  std::string line, out;
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    std::string field, kept;
    for (int k = 0; std::getline(fields, field, ','); ++k)
      if (k < 10 || k > 13) kept += (kept.empty() ? "" : ",") + field;
    out += kept + "\n";
  }
  return out;
}

// A run killed (SIGKILL) at random moments and resumed until it finishes is the
// uninterrupted run: the same history (timings aside), bitwise the same final body, and
// body.pvd lists every step. Ten trials with seeded random delays.
TEST_F(OptimiseCli, KilledAndResumedRunsAreTheUninterruptedRun) {
  const std::string common = " --max-iter 30 --rel-tol 0 --threads 1 --vtu-every 4 --quiet";
  const fs::path ref = dir_ / "ref";
  ASSERT_EQ(run(scene() + " --out " + ref.string() + common), 0);
  std::mt19937 rng(2024);
  std::uniform_real_distribution<double> delay(0.05, 0.6);
  int kills_total = 0;
  for (int trial = 0; trial < 10; ++trial) {
    SCOPED_TRACE("trial " + std::to_string(trial));
    const fs::path out = dir_ / ("trial" + std::to_string(trial));
    int rc = -1, kills = 0;
    for (int attempt = 0; attempt < 40 && rc != 0; ++attempt) {
      const bool resume = fs::exists(out / "checkpoint.bin");
      if (resume && kills > 0) {  // what a killed run leaves behind
        EXPECT_TRUE(fs::exists(out / "history.csv"));
        EXPECT_TRUE(fs::exists(out / "summary.json"));
      }
      // The first attempts are killed; from the sixth on the run may finish.
      // --foreground: timeout kills softhd alone and waits for it, so its folder lock is free
      // when the next attempt starts (without it, timeout also kills itself and returns while
      // a loaded machine may still be tearing softhd down, its lock held).
      const std::string limit =
          attempt < 5 ? "timeout --foreground -s KILL " + std::to_string(delay(rng)) + " " : "";
      const std::string cmd = limit + SOFTHD_CLI + " optimise " + scene() + " --out " +
                              out.string() + common + (resume ? " --resume" : "") +
                              " >/dev/null 2>" + (dir_ / "stderr").string();
      const int raw = std::system(cmd.c_str());
      rc = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
      if (rc == 137 || rc == -1) ++kills;
      ASSERT_TRUE(rc == 0 || rc == 137 || rc == -1) << read_text(dir_ / "stderr");
    }
    ASSERT_EQ(rc, 0);
    kills_total += kills;
    EXPECT_EQ(history_without_timings(out), history_without_timings(ref));
    EXPECT_EQ(read_text(out / "body_final.ply"), read_text(ref / "body_final.ply"));
    EXPECT_EQ(read_text(out / "control.csv"), read_text(ref / "control.csv"));
    EXPECT_EQ(read_text(out / "body.pvd"), read_text(ref / "body.pvd"));
    EXPECT_EQ(nlohmann::json::parse(read_text(out / "summary.json"))["status"], "finished");
  }
  EXPECT_GE(kills_total, 10);  // the trials did interrupt runs
}

// The limit counts over the whole run, and a finished run resumed stays finished.
TEST_F(OptimiseCli, IterationLimitIsATotalOverResumes) {
  ASSERT_EQ(run(scene() + " --out " + out() + " --max-iter 3 --quiet --rel-tol 0"), 0);
  ASSERT_EQ(run(scene() + " --out " + out() + " --max-iter 6 --quiet --rel-tol 0 --resume"), 0);
  EXPECT_EQ(summary()["iterations"].get<int>(), 6);
  const std::string finished = history_without_timings(out());
  ASSERT_EQ(run(scene() + " --out " + out() + " --max-iter 6 --quiet --rel-tol 0 --resume"), 0);
  const nlohmann::json s = summary();
  EXPECT_EQ(s["iterations"].get<int>(), 6);
  // Replayed up to the last scheduled save (iteration 5), iteration 6 recomputed: the same.
  EXPECT_GT(s["replayed_evaluations"].get<int>(), 0);
  EXPECT_EQ(history_without_timings(out()), finished);
  std::ifstream h(fs::path(out()) / "history.csv");
  std::string line;
  int rows = -1;  // header
  while (std::getline(h, line)) ++rows;
  EXPECT_EQ(rows, 6);
}

// Issue 29 item 9: a finished run continued with a larger limit is the run given that limit
// from the start, also when it ended between two scheduled saves (12 is not a multiple of
// --checkpoint-every 5; the end-of-run save used to renew the solver there).
TEST_F(OptimiseCli, ContinuingAFinishedRunIsTheUninterruptedRun) {
  const std::string common = " --rel-tol 0 --threads 1 --quiet";
  const fs::path ref = dir_ / "ref";
  ASSERT_EQ(run(scene() + " --out " + ref.string() + " --max-iter 30" + common), 0);
  ASSERT_EQ(run(scene() + " --out " + out() + " --max-iter 12" + common), 0);
  ASSERT_EQ(run(scene() + " --out " + out() + " --max-iter 30 --resume" + common), 0);
  EXPECT_EQ(history_without_timings(out()), history_without_timings(ref));
  EXPECT_EQ(read_text(fs::path(out()) / "control.csv"), read_text(ref / "control.csv"));
}

// The same with --algorithm newton: its Hessian-vector products are in the checkpoint too, so a
// run continued after its end (between two saves) is the uninterrupted one, bitwise.
TEST_F(OptimiseCli, ContinuingAFinishedNewtonRunIsTheUninterruptedRun) {
  const std::string common =
      " --rel-tol 0 --threads 1 --quiet --algorithm newton --checkpoint-every 2";
  const fs::path ref = dir_ / "ref";
  ASSERT_EQ(run(scene() + " --out " + ref.string() + " --max-iter 6" + common), 0);
  ASSERT_EQ(run(scene() + " --out " + out() + " --max-iter 3" + common), 0);
  std::string err;
  ASSERT_EQ(run(scene() + " --out " + out() + " --max-iter 6 --resume" + common, &err), 0) << err;
  EXPECT_GT(summary()["replayed_evaluations"].get<int>(), 0);
  EXPECT_EQ(history_without_timings(out()), history_without_timings(ref));
  EXPECT_EQ(read_text(fs::path(out()) / "control.csv"), read_text(ref / "control.csv"));
}

// Multilevel runs (--levels 2, docs/guide.md section 5): the coarse level's rows come first in
// history.csv with level 1, and a run killed at random moments, on either level, and resumed
// until it finishes is the uninterrupted one.
TEST_F(OptimiseCli, MultilevelKilledAndResumedRunsAreTheUninterruptedRun) {
  const std::string common =
      " --levels 2 --max-iter 12 --rel-tol 0 --threads 1 --vtu-every 4 --quiet";
  const fs::path ref = dir_ / "ref";
  ASSERT_EQ(run(scene() + " --out " + ref.string() + common), 0);
  const nlohmann::json s = nlohmann::json::parse(read_text(ref / "summary.json"));
  ASSERT_EQ(s["levels"].size(), 2u);
  EXPECT_EQ(s["levels"][0]["level"], 1);
  EXPECT_EQ(s["levels"][1]["level"], 0);
  EXPECT_EQ(s["levels"][1]["iterations"], 12);
  // history.csv: level 1 rows, then the 12 of the user's mesh.
  std::istringstream h(read_text(ref / "history.csv"));
  std::string line;
  std::getline(h, line);
  EXPECT_EQ(line.substr(line.rfind(',') + 1), "level");
  std::string levels;
  while (std::getline(h, line)) levels += line.substr(line.rfind(',') + 1);
  const int coarse = s["levels"][0]["iterations"].get<int>();
  ASSERT_GE(coarse, 1);
  EXPECT_EQ(levels, std::string(coarse, '1') + std::string(12, '0'));

  // A run killed on the coarse level for sure: as soon as its checkpoint appears, before the
  // user's mesh has one (the random delays below hit the coarse level only by chance).
  // The coarse level lasts about 10 ms here, so a kill can still land after it: up to 8 tries.
  {
    const fs::path out = dir_ / "coarse_kill";
    bool on_coarse = false;
    for (int attempt = 0; attempt < 8 && !on_coarse; ++attempt) {
      fs::remove_all(out);
      const std::string cmd = "(" + std::string(SOFTHD_CLI) + " optimise " + scene() + " --out " +
                              out.string() + common + " >/dev/null 2>&1 & p=$!; while [ ! -e " +
                              (out / "checkpoint_level1.bin").string() +
                              " ] && kill -0 $p 2>/dev/null; do sleep 0.002; done; kill -9 $p "
                              "2>/dev/null; wait $p; exit 0)";
      ASSERT_EQ(std::system(cmd.c_str()), 0);
      ASSERT_TRUE(fs::exists(out / "checkpoint_level1.bin"));
      on_coarse = !fs::exists(out / "checkpoint.bin");  // the user's mesh had not started
    }
    ASSERT_TRUE(on_coarse) << "no kill in 8 landed on the coarse level";
    ASSERT_EQ(run(scene() + " --out " + out.string() + common + " --resume"), 0);
    EXPECT_EQ(history_without_timings(out), history_without_timings(ref));
    EXPECT_EQ(read_text(out / "control.csv"), read_text(ref / "control.csv"));
  }

  std::mt19937 rng(31);
  std::uniform_real_distribution<double> delay(0.02, 0.4);
  int kills_total = 0, coarse_resumes = 0;
  for (int trial = 0; trial < 6; ++trial) {
    SCOPED_TRACE("trial " + std::to_string(trial));
    const fs::path out = dir_ / ("trial" + std::to_string(trial));
    int rc = -1, kills = 0;
    for (int attempt = 0; attempt < 40 && rc != 0; ++attempt) {
      const bool resume = fs::exists(out / "checkpoint_level1.bin");
      // Killed on the coarse level: the user's mesh has no checkpoint yet.
      if (resume && !fs::exists(out / "checkpoint.bin")) ++coarse_resumes;
      const std::string limit =  // --foreground: as above
          attempt < 4 ? "timeout --foreground -s KILL " + std::to_string(delay(rng)) + " " : "";
      const std::string cmd = limit + SOFTHD_CLI + " optimise " + scene() + " --out " +
                              out.string() + common + (resume ? " --resume" : "") +
                              " >/dev/null 2>" + (dir_ / "stderr").string();
      const int raw = std::system(cmd.c_str());
      rc = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
      if (rc == 137 || rc == -1) ++kills;
      ASSERT_TRUE(rc == 0 || rc == 137 || rc == -1) << read_text(dir_ / "stderr");
    }
    ASSERT_EQ(rc, 0);
    kills_total += kills;
    EXPECT_EQ(history_without_timings(out), history_without_timings(ref));
    EXPECT_EQ(read_text(out / "body_final.ply"), read_text(ref / "body_final.ply"));
    EXPECT_EQ(read_text(out / "control.csv"), read_text(ref / "control.csv"));
  }
  EXPECT_GE(kills_total, 6);  // the trials did interrupt runs
  std::cout << "coarse-level resumes in the random trials: " << coarse_resumes << "\n";
}

// --switch-decrease and --coarse-tol reach the coarse level of --levels 2. With S = 0 the
// coarse level runs its min(--coarse-iterations, --max-iter) = 6 iterations; with S = 0.9 (ρ̃
// decreasing by less than 90 % twice ends it) it switches before. Its checkpoint records its
// tree tolerance max(--tol, --coarse-tol): a resume with another --coarse-tol is refused naming
// the distance, one with the same continues.
TEST_F(OptimiseCli, SwitchDecreaseAndCoarseTolActOnTheCoarseLevel) {
  const std::string common =
      " --levels 2 --max-iter 6 --rel-tol 0 --threads 1 --vtu-every 0 --quiet";
  std::string err;
  auto coarse_level = [&](const std::string& name, const std::string& flags) {
    const fs::path o = dir_ / name;
    EXPECT_EQ(run(scene() + " --out " + o.string() + common + flags, &err), 0) << flags << err;
    return nlohmann::json::parse(read_text(o / "summary.json"))["levels"][0];
  };
  const nlohmann::json all = coarse_level("all", " --switch-decrease 0");
  EXPECT_EQ(all["iterations"].get<int>(), 6) << all.dump();
  const nlohmann::json early = coarse_level("early", " --switch-decrease 0.9");
  EXPECT_LT(early["iterations"].get<int>(), 6) << early.dump();
  EXPECT_NE(early["termination"].get<std::string>().find("less than 0.9 twice"), std::string::npos)
      << early.dump();

  const std::string tol = scene() + " --out " + (dir_ / "tol").string() + common;
  ASSERT_EQ(run(tol + " --coarse-tol 0.1", &err), 0) << err;
  EXPECT_EQ(run(tol + " --coarse-tol 0.2 --resume", &err), 2);
  EXPECT_NE(err.find("checkpoint_level1.bin was written for another run: distance differs"),
            std::string::npos)
      << err;
  EXPECT_EQ(run(tol + " --coarse-tol 0.1 --resume", &err), 0) << err;
}

// --coarse-levels: the state solves' coarse start. On a box of 16 x 4 x 4 cells the coarse
// level (8 x 2 x 2, 32 elements) is used by default (auto) and named in the progress lines;
// --coarse-levels 0 solves on the user's mesh alone.
TEST_F(OptimiseCli, CoarseLevelsZeroTurnsTheCoarseStartOff) {
  nlohmann::json j = nlohmann::json::parse(kScene);
  j["mesh"]["cells"] = {16, 4, 4};
  j["target"]["cells"] = {16, 4, 4};
  const std::string path = (dir_ / "fine.json").string();
  std::ofstream(path) << j.dump();
  const std::string line = "two-level starts on the coarse level (cells 8 2 2)";
  std::string err;
  const std::string common = " --max-iter 1 --levels 1 --threads 1 --vtu-every 0 --out ";
  ASSERT_EQ(run(path + common + (dir_ / "auto").string(), &err), 0) << err;
  EXPECT_NE(err.find(line), std::string::npos) << err;
  ASSERT_EQ(run(path + common + (dir_ / "off").string() + " --coarse-levels 0", &err), 0) << err;
  EXPECT_EQ(err.find("two-level starts"), std::string::npos) << err;
}

// --levels asks for more halvings than the box allows ((6, 1, 2) -> (3, 1, 1) -> none): bad
// input naming the option.
TEST_F(OptimiseCli, TooManyLevelsIsBadInput) {
  std::string err;
  EXPECT_EQ(run(scene() + " --out " + out() + " --levels 3 --quiet", &err), 2);
  EXPECT_NE(err.find("--levels: 3: 2 coarser levels asked for, but the body has 1"),
            std::string::npos)
      << err;
}

// --target FILE is the run of a scene whose target is {"kind": "cloud", "file": FILE}
// (history.csv equal but for timings), not the scene's own arc's; a missing file is exit 2.
TEST_F(OptimiseCli, TargetFlagIsTheScenesCloudTargetOfThatFile) {
  ASSERT_EQ(write_forward_cloud(dir_ / "t.ply"), 0);
  nlohmann::json cloud = nlohmann::json::parse(kScene);
  cloud["target"] = {{"kind", "cloud"}, {"file", "t.ply"}};
  const std::string cloud_scene = (dir_ / "cloud.json").string();
  std::ofstream(cloud_scene) << cloud.dump();
  const std::string common = " --max-iter 2 --threads 1 --quiet";
  std::string err;
  ASSERT_EQ(run(cloud_scene + " --out " + (dir_ / "a").string() + common, &err), 0) << err;
  ASSERT_EQ(run(scene() + " --out " + (dir_ / "b").string() + common + " --target " +
                    (dir_ / "t.ply").string(),
                &err),
            0)
      << err;
  ASSERT_EQ(run(scene() + " --out " + (dir_ / "c").string() + common, &err), 0) << err;
  EXPECT_EQ(history_without_timings(dir_ / "b"), history_without_timings(dir_ / "a"));
  EXPECT_NE(history_without_timings(dir_ / "b"), history_without_timings(dir_ / "c"));
  EXPECT_EQ(run(scene() + " --target " + (dir_ / "missing.ply").string(), &err), 2);
  EXPECT_NE(err.find("missing.ply"), std::string::npos) << err;
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
}

// history.csv's rho per level (column 4, level the last column), in row order.
std::vector<std::pair<int, double>> rho_by_level(const fs::path& dir) {
  std::istringstream in(read_text(dir / "history.csv"));
  std::string line;
  std::getline(in, line);  // header
  std::vector<std::pair<int, double>> rows;
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    std::string field;
    for (int i = 0; i < 4; ++i) std::getline(fields, field, ',');
    rows.emplace_back(std::stoi(line.substr(line.rfind(',') + 1)), std::stod(field));
  }
  return rows;
}

// --levels 2: --coarse-iterations 2 caps the coarse level (level 1) at 2 rows of history.csv
// (8 without it, --max-iter); --refined-move-limit 1e-3 leaves the coarse rows as they were
// and makes the fine level's steps small: its rho decreases by under a tenth of the default's.
TEST_F(OptimiseCli, CoarseIterationsAndRefinedMoveLimitActOnTheirLevels) {
  const std::string common = " --levels 2 --max-iter 8 --rel-tol 0 --threads 1 --quiet";
  std::string err;
  ASSERT_EQ(run(scene() + " --out " + (dir_ / "d").string() + common, &err), 0) << err;
  ASSERT_EQ(
      run(scene() + " --out " + (dir_ / "k").string() + common + " --coarse-iterations 2", &err), 0)
      << err;
  ASSERT_EQ(run(scene() + " --out " + (dir_ / "m").string() + common + " --refined-move-limit 1e-3",
                &err),
            0)
      << err;
  const auto count = [](const std::vector<std::pair<int, double>>& rows, int level) {
    return std::count_if(rows.begin(), rows.end(), [&](const auto& r) { return r.first == level; });
  };
  const auto def = rho_by_level(dir_ / "d"), capped = rho_by_level(dir_ / "k"),
             slow = rho_by_level(dir_ / "m");
  ASSERT_EQ(count(def, 1), 8);
  EXPECT_EQ(count(capped, 1), 2);
  EXPECT_EQ(count(capped, 0), 8);
  ASSERT_EQ(slow.size(), def.size());
  for (std::size_t i = 0; i < 8; ++i) EXPECT_EQ(slow[i], def[i]) << "coarse row " << i;
  ASSERT_EQ(count(def, 0), 8);
  const double fine_drop = def[8].second - def.back().second;
  const double slow_drop = slow[8].second - slow.back().second;
  ASSERT_GT(fine_drop, 0.0);
  EXPECT_LT(slow_drop, 0.1 * fine_drop);
  for (const auto& [args, needle] : std::vector<std::pair<std::string, std::string>>{
           {" --coarse-iterations 0", "--coarse-iterations"},
           {" --refined-move-limit -1", "--refined-move-limit must be in [0, 1]"},
           {" --refined-move-limit 2", "--refined-move-limit must be in [0, 1]"}}) {
    EXPECT_EQ(run(scene() + args, &err), 2) << args;
    EXPECT_NE(err.find(needle), std::string::npos) << args << "\n" << err;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  }
}

// A manufactured target (forward --write-cloud) solved on the body's own mesh: the known map
// puts every node on its target point with the same deformed volume, so with deformed
// volumes the matched floor is the self floor.
TEST_F(OptimiseCli, ManufacturedTargetOnTheSameMeshHasTheSelfFloorAsMatchedFloor) {
  const std::string target = (dir_ / "target.ply").string();
  ASSERT_EQ(write_forward_cloud(target), 0);
  nlohmann::json scene2 = nlohmann::json::parse(kScene);
  scene2["target"] = {{"kind", "cloud"}, {"file", "target.ply"}, {"solved_on", "scene.json"}};
  const std::string path2 = (dir_ / "manufactured.json").string();
  std::ofstream(path2) << scene2.dump();
  std::string err;
  ASSERT_EQ(run(path2 + " --out " + out() + " --max-iter 2 --volumes deformed --quiet", &err), 0)
      << err;
  const nlohmann::json s = summary();
  ASSERT_TRUE(s["floor_matched"].is_number()) << s.dump();
  EXPECT_NEAR(s["floor_matched"].get<double>(), s["floor_self"].get<double>(),
              1e-12 * s["floor_self"].get<double>());
  EXPECT_GT(s["shape_error_max"].get<double>(), 0.0);
  // The same cloud claimed to be solved on a mesh with other nodes is refused.
  scene2["target"]["solved_on"] = (dir_ / "other.json").string();
  nlohmann::json other = nlohmann::json::parse(kScene);
  other["mesh"]["cells"] = {3, 1, 1};
  std::ofstream((dir_ / "other.json").string()) << other.dump();
  std::ofstream(path2) << scene2.dump();
  EXPECT_EQ(run(path2 + " --out " + out() + " --max-iter 1 --quiet", &err), 2);
  EXPECT_NE(err.find("the mesh it was solved on has 16 nodes"), std::string::npos) << err;
}

// Every user error: exit 2 and one line naming the file, key or flag.
// The distance form (docs/formulation.md §8) from the scene's target keys (the run's summary
// names the form it used; the flags replacing it are tested on TrackingRunOptions::distance in
// test_target_forms.cpp), and the flags' misuse.
TEST_F(OptimiseCli, DistanceFormFromTheSceneOrTheFlags) {
  nlohmann::json j = nlohmann::json::parse(kScene);
  j["target"]["distance"] = "scan_to_body";
  j["target"]["cap"] = {{"quantile", 0.9}, {"factor", 3}};
  const std::string one_sided = (dir_ / "one_sided.json").string();
  std::ofstream(one_sided) << j.dump();
  std::string err;
  ASSERT_EQ(run(one_sided + " --out " + out() + " --max-iter 1 --quiet", &err), 0) << err;
  const std::string target = summary()["target"].get<std::string>();
  EXPECT_NE(target.find("distance scan_to_body, cap c = "), std::string::npos) << target;
  for (const auto& [args, needle] : std::vector<std::pair<std::string, std::string>>{
           {" --distance visible", "--distance visible needs the camera"},
           {" --distance both", "unknown distance 'both'"},
           {" --cap -1", "--cap must be"},
           {" --cap-q 0", "--cap-q must be"}}) {
    EXPECT_EQ(run(scene() + args, &err), 2) << args;
    EXPECT_NE(err.find(needle), std::string::npos) << args << "\n" << err;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  }
  j["target"]["distance"] = "visible";
  std::ofstream(one_sided) << j.dump();
  EXPECT_EQ(run(one_sided, &err), 2);
  EXPECT_NE(err.find("target.distance \"visible\" needs the camera"), std::string::npos) << err;
}

TEST_F(OptimiseCli, BadInputGivesExitCode2AndOneLine) {
  auto expect_refused = [&](const std::string& args, const std::string& needle) {
    std::string err;
    EXPECT_EQ(run(args, &err), 2) << args << "\n" << err;
    EXPECT_NE(err.find(needle), std::string::npos) << args << "\n" << err;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  };
  auto scene_with = [&](const std::string& name, const std::function<void(nlohmann::json&)>& f) {
    nlohmann::json j = nlohmann::json::parse(kScene);
    f(j);
    const std::string path = (dir_ / name).string();
    std::ofstream(path) << j.dump();
    return path;
  };
  expect_refused((dir_ / "missing.json").string(), "missing.json");
  expect_refused(scene() + " --algorithm gcmma", "unknown algorithm 'gcmma'");
  expect_refused(scene() + " --hessian gauss_newton",
                 "--hessian gauss_newton is a setting of --algorithm newton");
  expect_refused(scene() + " --algorithm newton --hessian x", "--hessian: unknown hessian 'x'");
  expect_refused(scene() + " --algorithm newton --volumes deformed",
                 "supports reference volumes only");
  expect_refused(scene() + " --method nearest", "--method: nearest has no gradient");
  expect_refused(scene() + " --method fast", "unknown method 'fast'");
  expect_refused(scene() + " --method tree --tol 2", "tolerance");
  expect_refused(scene() + " --coarse-levels off", "--coarse-levels: expected auto or 0");
  // The retired spelling names the new one.
  expect_refused(scene() + " --coarse-level off",
                 "--coarse-level is now --coarse-levels (auto or 0)");
  // The flags reach the run's validation (TrackingRunOptions::validate).
  expect_refused(scene() + " --switch-decrease 1", "--switch-decrease must be in [0, 1)");
  expect_refused(scene() + " --coarse-tol 0", "--coarse-tol must be in (0, 1)");
  expect_refused(scene() + " --pose-move 0", "--pose-move must be in (0, 1]");
  expect_refused(scene() + " --pose-move 0.5",
                 "--pose-move moves the pose of a target in the camera");
  expect_refused(scene() + " --pose-method projection",
                 "--pose-method finds the pose of a target in the camera");
  expect_refused(scene() + " --pose-method both", "--pose-method: unknown");
  expect_refused(scene() + " --quadrature points", "--quadrature: unknown quadrature 'points'");
  expect_refused(scene() + " --quadrature cells --algorithm newton",
                 "quadrature cells has no Hessian-vector product");
  expect_refused(scene_with("quadrature.json",
                            [](nlohmann::json& j) { j["target"]["quadrature"] = "points"; }),
                 "target.quadrature must be \"collocation\" or \"cells\"");
  // Every bad value names its flag first, also where the objective's or the optimiser's own
  // check refuses it.
  for (const auto& [args, start] : std::vector<std::pair<std::string, std::string>>{
           {" --max-seconds -1", "--max-seconds: "},
           {" --rel-tol -1", "--rel-tol: "},
           {" --move-limit 2", "--move-limit: "},
           {" --algorithm x", "--algorithm: unknown algorithm 'x'"},
           {" --particles x", "--particles: unknown particles 'x'"},
           {" --volumes x", "--volumes: unknown volumes 'x'"},
           {" --alpha 0", "--alpha: "},
           {" --beta -1", "--beta: "},
           {" --gamma 0", "--gamma: "},
           {" --eps 0", "--eps: "},
           {" --method x", "--method: unknown method 'x'"},
           {" --tol 2", "--tol: "},
           {" --distance x", "--distance: unknown distance 'x'"},
           {" --tikhonov-mass -1", "--tikhonov-mass: "},
           {" --tikhonov-grad -1", "--tikhonov-grad: "}})
    expect_refused(scene() + args, "error: " + start);
  expect_refused(scene() + " --state-backend petsc", "--state-backend: unknown state backend");
  if (!softhd::fe::petsc_backend_available())  // an MPI build runs it (tests/mpi/cli_mpi.py)
    expect_refused(scene() + " --state-backend petsc-mumps", "-DSOFTHD_WITH_MPI=ON");
  expect_refused(scene() + " --checkpoint-every 0", "--checkpoint-every");
  expect_refused(scene() + " --out " + out() + " --resume", "checkpoint.bin");
  expect_refused(scene() + " --max-iter 0", "--max-iter");
  expect_refused(scene() + " --max-iter 4294967297", "--max-iter: expected an integer from 1");
  expect_refused(scene() + " --threads 99999", "--threads: expected an integer from 0 to 1024");
  expect_refused(scene() + " --eps 1e-320", "epsilon must be at least 1e-300, got 9.99989e-321");
  expect_refused(scene_with("kind5.json", [](auto& j) { j["target"]["kind"] = 5; }),
                 "target.kind must be");
  expect_refused(scene_with("target5.json", [](auto& j) { j["target"] = 5; }),
                 "key 'target' must be an object");
  expect_refused(scene_with("cells.json",
                            [](auto& j) {
                              j["target"]["cells"] = {1e20, 2, 2};
                            }),
                 "target.cells must hold integers");
  expect_refused(scene_with("comp.json",
                            [](auto& j) {
                              j["constraints"] = {{{"face", "z0"}, {"components", {2.5}}}};
                            }),
                 "constraints[].components");
  {
    const std::string path = (dir_ / "huge_number.json").string();
    std::string text = kScene;
    text.replace(text.find("\"initial\": 0"), 12, "\"initial\": 1e400");
    std::ofstream(path) << text;
    expect_refused(path, "huge_number.json: not valid JSON");
  }
  // Meshes beyond int or the memory limit: refused before anything is allocated.
  expect_refused(scene_with("int.json",
                            [](auto& j) {
                              j["mesh"]["cells"] = {65535, 65535, 1};
                            }),
                 "above the memory limit of 8 GiB");
  expect_refused(scene_with("big.json",
                            [](auto& j) {
                              j["mesh"]["cells"] = {1000, 1000, 1000};
                            }),
                 "above the memory limit of 8 GiB");
  expect_refused(scene() + " --max-memory 0.0001 --out " + out(), "above the memory limit of");
  expect_refused(scene_with("int2.json",
                            [](auto& j) {
                              j["mesh"]["cells"] = {1290, 1290, 1290};
                            }) +
                     " --max-memory 1e6",
                 "more than the 2147483647");
  // An --out that cannot be a directory, a checkpoint that is one.
  std::ofstream(dir_ / "file") << "x";
  expect_refused(scene() + " --out " + (dir_ / "file").string(), "--out: cannot create");
  fs::create_directories(fs::path(out()) / "checkpoint.bin");
  expect_refused(scene() + " --out " + out() + " --resume", "is a directory");
}

// A checkpoint is refused for another scene, target or options, naming what differs.
TEST_F(OptimiseCli, ACheckpointOfAnotherRunIsRefused) {
  ASSERT_EQ(run(scene() + " --out " + out() + " --max-iter 2 --quiet --threads 1"), 0);
  nlohmann::json other = nlohmann::json::parse(kScene);
  other["target"]["angle"] = 0.7;
  const std::string path = (dir_ / "other.json").string();
  std::ofstream(path) << other.dump();
  std::string err;
  EXPECT_EQ(run(path + " --out " + out() + " --max-iter 4 --resume --threads 1", &err), 2);
  EXPECT_NE(err.find("was written for another run: scene differs"), std::string::npos) << err;
  EXPECT_EQ(run(scene() + " --out " + out() + " --max-iter 4 --resume --threads 1 --alpha 5", &err),
            2);
  EXPECT_NE(err.find("distance differs"), std::string::npos) << err;
  EXPECT_EQ(run(scene() + " --out " + out() + " --max-iter 4 --resume --threads 2", &err), 2);
  EXPECT_NE(err.find("threads differs"), std::string::npos) << err;
  EXPECT_EQ(run(scene() + " --out " + out() + " --max-iter 4 --resume --threads 1 --quiet", &err),
            0)
      << err;
}

// A scan in the camera's frame (docs/formulation.md §8.10): the body's nodes at rest moved by a
// rigid motion G, the start pose G⁻¹ 0.1 rad off. The run recovers the pose (to 0.01 rad) with
// the control, prints it and writes it to summary.json and history.csv; bad "frame", "align" and
// pose files are refused.
TEST_F(OptimiseCli, CameraFrameTargetRefinesThePoseWithTheControl) {
  std::string err;
  Eigen::MatrixXd rest(7 * 2 * 3, 3);  // the nodes of kScene's box mesh
  int n = 0;
  for (int k = 0; k < 3; ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 7; ++i) rest.row(n++) << 2.0 * i / 6, 0.4 * j, 0.1 * k;
  Eigen::Matrix<double, 7, 1> g, off;
  g << 0.3, 0.5, -0.4, 1.0, -2.0, 3.0, 0.0;
  off << 0.05, -0.06, 0.05, 0.02, 0.01, -0.02, 0.0;
  const softhd::scan::Pose G = softhd::scan::Pose::from_twist(g), truth = G.inverse();
  const softhd::scan::Pose start =
      softhd::scan::compose(truth, softhd::scan::Pose::from_twist(off));
  softhd::write_ply_cloud((dir_ / "seen.ply").string(), G.apply(softhd::PointCloud(rest), false));
  softhd::write_pose((dir_ / "start.txt").string(), start);
  auto scene_with = [&](const std::string& name, const nlohmann::json& target) {
    nlohmann::json j = nlohmann::json::parse(kScene);
    j["target"] = target;
    const std::string path = (dir_ / name).string();
    std::ofstream(path) << j.dump();
    return path;
  };
  const nlohmann::json seen = {
      {"kind", "cloud"}, {"file", "seen.ply"}, {"frame", "camera"}, {"pose", "start.txt"}};
  const std::string joint = scene_with("joint.json", seen);
  const std::string out2 = (dir_ / "joint").string();
  ASSERT_EQ(run(joint + " --out " + out2 + " --max-iter 12", &err), 0) << err;
  EXPECT_NE(err.find("pose (scan -> body): rotation"), std::string::npos) << err;
  const nlohmann::json sum = nlohmann::json::parse(std::ifstream(fs::path(out2) / "summary.json"));
  ASSERT_TRUE(sum.contains("pose") && sum.contains("pose_start")) << sum.dump();
  EXPECT_EQ(sum["frame"], "camera");
  EXPECT_LT(sum["rho_final"].get<double>(), 0.5 * sum["rho_start"].get<double>());
  Eigen::Matrix4d M;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) M(r, c) = sum["pose"]["matrix"][r][c].get<double>();
  const softhd::scan::Pose P = softhd::scan::Pose::from_matrix(M);
  EXPECT_LT(softhd::scan::rotation_angle_between(P.R, truth.R), 0.01);
  // The translation where the body is (t itself is the camera's position, 3.7 away: a rotation
  // error moves it by that lever arm).
  const Eigen::Vector3d centre = G.apply(softhd::PointCloud(rest), false).points().colwise().mean();
  EXPECT_LT((P.R * centre + P.t - truth.R * centre - truth.t).norm(), 0.01);
  std::string header;
  std::getline(std::ifstream(fs::path(out2) / "history.csv"), header);
  EXPECT_NE(header.find(",pose_w1,pose_w2,pose_w3,pose_t1,pose_t2,pose_t3,pose_log_s"),
            std::string::npos)
      << header;
  EXPECT_TRUE(fs::exists(fs::path(out2) / "target_aligned.ply"));
  // --pose-method projection: every evaluation fits the pose on its state; the target is the
  // rest body moved, so the pose is recovered where the control is still at rest.
  const std::string out3 = (dir_ / "projection").string();
  ASSERT_EQ(run(joint + " --out " + out3 + " --max-iter 2 --pose-method projection", &err), 0)
      << err;
  const nlohmann::json sum3 = nlohmann::json::parse(std::ifstream(fs::path(out3) / "summary.json"));
  EXPECT_EQ(sum3["pose_method"], "projection");
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) M(r, c) = sum3["pose"]["matrix"][r][c].get<double>();
  EXPECT_LT(softhd::scan::rotation_angle_between(softhd::scan::Pose::from_matrix(M).R, truth.R),
            1e-6);
  EXPECT_EQ(run(joint + " --pose-method projection --pose-move 0.5", &err), 2);
  EXPECT_NE(err.find("--pose-move is the joint pose's move limit"), std::string::npos) << err;

  // --pose-move F: the pose's move limit is F times the control's, so with 0.05 the first
  // iteration moves the pose (its twist, rotation and translation) less than with the default 1.
  auto first_pose_step = [&](const std::string& name, const std::string& flags) {
    const fs::path o = dir_ / name;
    EXPECT_EQ(run(joint + " --out " + o.string() + " --max-iter 1 --quiet" + flags, &err), 0)
        << err;
    const nlohmann::json s = nlohmann::json::parse(std::ifstream(o / "summary.json"));
    double step = 0.0;
    for (int k = 0; k < 6; ++k) {
      const double d =
          s["pose"]["twist"][k].get<double>() - s["pose_start"]["twist"][k].get<double>();
      step += d * d;
    }
    return std::sqrt(step);
  };
  const double full = first_pose_step("move1", ""),
               small = first_pose_step("move005", " --pose-move 0.05");
  std::cout << "first pose step: --pose-move 1 " << full << ", 0.05 " << small << "\n";
  EXPECT_GT(full, 0.0);
  EXPECT_LT(small, 0.5 * full);

  std::ofstream(dir_ / "bad_pose.txt") << "1 0 0 0\n0 2 0 0\n0 0 1 0\n0 0 0 1\n";
  std::ofstream(dir_ / "tiny_pose.txt") << "1e-100 0 0 0\n0 1e-100 0 0\n0 0 1e-100 0\n0 0 0 1\n";
  for (const auto& [key, value, needle] :
       std::vector<std::tuple<std::string, nlohmann::json, std::string>>{
           {"frame", "world", "target.frame must be \"body\" or \"camera\""},
           {"align", "affine", "target.align must be \"rigid\" or \"similarity\""},
           {"pose", "bad_pose.txt", "not a scaled rotation"},
           {"pose", "tiny_pose.txt", "tiny_pose.txt' has scale 1e-100, but a rigid pose"},
           {"pose", "no_such_pose.txt", "cannot open the pose file"},
           {"pose_uncertainty",
            {{"degrees", -1}, {"length", 0.01}},
            "target.pose_uncertainty.degrees must be a number > 0, got -1"},
           {"pose_uncertainty",
            {{"degrees", 1}, {"length", "NaN"}},
            "target.pose_uncertainty.length must be a number > 0, got \"NaN\""},
           // a valid uncertainty bounds the pose by projection: refused with the joint method
           {"pose_uncertainty",
            {{"degrees", 1}, {"length", 0.01}},
            "target.pose_uncertainty bounds the pose found by projection: give --pose-method "
            "projection"},
           {"fixture",
            {{"normal", {0, 0, 0}}, {"offset", 0}},
            "target.fixture.normal has zero length"},
           // a valid fixture keeps the projection's tilt: refused with the joint method
           {"fixture",
            {{"normal", {0, 0, 1}}, {"offset", 0}},
            "target.fixture constrains the pose found by projection: give --pose-method "
            "projection"}}) {
    nlohmann::json t = seen;
    t[key] = value;
    EXPECT_EQ(run(scene_with("bad.json", t), &err), 2) << key;
    EXPECT_NE(err.find(needle), std::string::npos) << key << "\n" << err;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  }
}

}  // namespace
