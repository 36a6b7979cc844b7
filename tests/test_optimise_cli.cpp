// softhd optimise end to end on a small plate: it lowers ρ̃, writes every promised
// file, resumes from its checkpoint, and rejects bad input with exit code 2.

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

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
  for (const char* f :
       {"history.csv", "control.csv", "body.pvd", "body_0000.vtu", "target.vtu", "checkpoint.json"})
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

TEST_F(OptimiseCli, ResumesFromTheCheckpoint) {
  ASSERT_EQ(run(scene() + " --out " + out() + " --max-iter 3 --quiet --rel-tol 0"), 0);
  const double first = summary()["rho_final"].get<double>();
  ASSERT_EQ(run(scene() + " --out " + out() + " --max-iter 3 --quiet --rel-tol 0 --resume"), 0);
  const nlohmann::json s = summary();
  EXPECT_EQ(s["iterations"].get<int>(), 6);
  EXPECT_LE(s["rho_final"].get<double>(), first);
  std::ifstream h(fs::path(out()) / "history.csv");
  std::string line;
  int rows = -1;  // header
  while (std::getline(h, line)) ++rows;
  EXPECT_EQ(rows, 6);
}

// A manufactured target (forward --write-cloud) solved on the body's own mesh: the known map
// puts every node on its target point with the same deformed volume, so with deformed
// volumes the matched floor is the self floor.
TEST_F(OptimiseCli, ManufacturedTargetOnTheSameMeshHasTheSelfFloorAsMatchedFloor) {
  const std::string target = (dir_ / "target.ply").string();
  const std::string forward = std::string(SOFTHD_CLI) + " forward " + scene() +
                              " --control-uniform -3e4 --write-cloud " + target + " --out " +
                              (dir_ / "fwd").string() + " >/dev/null 2>&1";
  ASSERT_EQ(std::system(forward.c_str()), 0);
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

TEST_F(OptimiseCli, BadInputGivesExitCode2) {
  std::string err;
  EXPECT_EQ(run((dir_ / "missing.json").string(), &err), 2);
  EXPECT_NE(err.find("missing.json"), std::string::npos) << err;
  EXPECT_EQ(run(scene() + " --algorithm newton", &err), 2);
  EXPECT_NE(err.find("unknown algorithm 'newton'"), std::string::npos) << err;
  EXPECT_EQ(run(scene() + " --out " + out() + " --resume", &err), 2);
  EXPECT_NE(err.find("checkpoint.json"), std::string::npos) << err;
  EXPECT_EQ(run(scene() + " --max-iter 0", &err), 2);
  EXPECT_NE(err.find("max_iterations"), std::string::npos) << err;
}

}  // namespace
