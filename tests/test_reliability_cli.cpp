// Issue 29's reproducers through the softhd tool: a scene cannot run a shell command, the
// plot step takes any folder name, two runs cannot share a folder, write errors are
// reported, and the small input checks (each named after the issue's item).

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

namespace {

namespace fs = std::filesystem;

const char* kScene = R"({
  "name": "NAME",
  "mesh": { "type": "box", "lower": [0, 0, 0], "upper": [2, 0.4, 0.2], "cells": [4, 1, 1], "order": 1 },
  "material": { "model": "mooney_rivlin", "a": 1e5, "b": 2e4, "c": 3e5 },
  "fibers": [1, 0, 0],
  "clamp": ["x0"],
  "control": { "space": "vertex", "lower": -1e5, "upper": 0, "initial": 0 },
  "target": { "kind": "arc", "angle": 0.6, "cells": [8, 2, 2] }
})";

std::string read_text(const fs::path& p) {
  std::stringstream s;
  s << std::ifstream(p).rdbuf();
  return s.str();
}

class Reliability : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::path(::testing::TempDir()) /
           ("softhd_rel_" +
            std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  std::string scene(const std::string& name) const {
    std::string text = kScene;
    text.replace(text.find("NAME"), 4, name);
    const fs::path p = dir_ / "scene.json";
    std::ofstream(p) << text;
    return p.string();
  }
  // Runs `softhd ARGS` in dir_ (the working directory), returns the exit status.
  int run(const std::string& args, std::string* err = nullptr) const {
    const std::string e = (dir_ / "stderr").string();
    const std::string cmd = "cd '" + dir_.string() + "' && " + SOFTHD_CLI + " " + args + " >" +
                            (dir_ / "stdout").string() + " 2>" + e;
    const int raw = std::system(cmd.c_str());
    if (err) *err = read_text(e);
    return WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  }
  void expect_refused(const std::string& args, const std::string& needle, int code = 2) const {
    std::string err;
    EXPECT_EQ(run(args, &err), code) << args << "\n" << err;
    EXPECT_NE(err.find(needle), std::string::npos) << args << "\n" << err;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  }
  fs::path dir_;
};

// Item 1: the scene's name made the default folder and went unquoted into a shell command.
TEST_F(Reliability, ASceneNameCannotRunAShellCommand) {
  expect_refused("optimise " + scene("x;touch PWNED;#") + " --max-iter 1 --quiet",
                 "must be a plain file name");
  EXPECT_FALSE(fs::exists(dir_ / "PWNED"));
  expect_refused("optimise " + scene("../outside") + " --max-iter 1 --quiet", "plain file name");
  EXPECT_FALSE(fs::exists(dir_ / "outside"));
}

// Items 1 and 10: the plot runs without a shell, so an --out with spaces and shell
// characters is one argument (it used to say python3-matplotlib was missing, or run them).
TEST_F(Reliability, ThePlotTakesAnyFolderName) {
  const fs::path out = dir_ / "a b;touch PWNED2;#";
  std::string err;
  ASSERT_EQ(run("optimise " + scene("plot") + " --max-iter 1 --out '" + out.string() + "'", &err),
            0)
      << err;
  EXPECT_FALSE(fs::exists(dir_ / "PWNED2"));
  EXPECT_EQ(err.find("not drawn"), std::string::npos) << err;
  EXPECT_TRUE(fs::exists(out / "convergence.png")) << err;
  EXPECT_TRUE(fs::exists(out / "shape.png")) << err;  // every run draws its final shape
}

// Item 4: a second run in the folder of a running one is refused, naming the process.
TEST_F(Reliability, TwoRunsCannotShareAFolder) {
  const std::string sc = scene("lock");
  const fs::path out = dir_ / "out";
  const pid_t first = fork();
  ASSERT_GE(first, 0);
  if (first == 0) {
    const std::string cli = SOFTHD_CLI;
    execl(cli.c_str(), cli.c_str(), "optimise", sc.c_str(), "--out", out.c_str(), "--max-iter",
          "100000", "--rel-tol", "0", "--max-seconds", "60", "--quiet",
          static_cast<char*>(nullptr));
    _exit(127);
  }
  const auto t0 = std::chrono::steady_clock::now();
  while (!fs::exists(out / "history.csv") &&
         std::chrono::steady_clock::now() - t0 < std::chrono::seconds(60))
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  ASSERT_TRUE(fs::exists(out / "history.csv"));
  // Frozen while it holds the lock (this small run ends by itself within seconds, and a
  // loaded machine could let it end before the second run tries the folder).
  int status = 0;
  ASSERT_EQ(waitpid(first, &status, WNOHANG), 0) << "the first run ended before the check";
  kill(first, SIGSTOP);
  expect_refused("optimise " + sc + " --out " + out.string() + " --max-iter 2 --quiet",
                 "is in use by another softhd run (process " + std::to_string(first) + ")");
  kill(first, SIGKILL);
  waitpid(first, &status, 0);
  // The kernel released the lock with the process: the killed run resumes.
  std::string err;
  EXPECT_EQ(run("optimise " + sc + " --out " + out.string() + " --max-iter 2 --quiet", &err), 0)
      << err;
}

// Item 7: write errors at close (a full device) are reported, not lost.
TEST_F(Reliability, WriteErrorsAreReported) {
  std::ofstream(dir_ / "a.txt") << "0 0 0\n1 0 0\n";
  std::ofstream(dir_ / "b.txt") << "0 1 0\n1 1 0\n";
  expect_refused("distance a.txt b.txt --grad /dev/full", "/dev/full");
  expect_refused("forward " + scene("w") + " --write-control-nodes /dev/full", "/dev/full");
}

// Item 10: the small ones.
TEST_F(Reliability, SmallInputChecks) {
  const std::string sc = scene("small");
  expect_refused("forward " + sc + " --coarse-levels -1", "--coarse-levels");
  std::ofstream(dir_ / "control.csv") << "0 0 0 -1\n0 0 0 -2\n";
  expect_refused("forward " + sc + " --control control.csv", "lines 1 and 2 give different values");
  std::ofstream(dir_ / "far.txt") << "0 0 0\n1e151 0 0\n";
  std::ofstream(dir_ / "b.txt") << "0 1 0\n";
  expect_refused("distance far.txt b.txt", "far.txt cloud: point 2 has a coordinate of magnitude");
}

// A body that nothing holds and volumes that share no nodes are refused before any solve,
// by forward and optimise alike: one tetrahedron clamped at a vertex (free to turn about it),
// and two Gmsh boxes meshed without BooleanFragments.
TEST_F(Reliability, UnheldAndNonConformingBodiesAreRefused) {
  std::ofstream(dir_ / "tet.msh") << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n2\n"
                                     "0 1 \"tip\"\n3 2 \"body\"\n$EndPhysicalNames\n$Nodes\n4\n"
                                     "1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n$EndNodes\n$Elements\n2\n"
                                     "1 15 2 1 1 1\n2 4 2 2 2 1 2 3 4\n$EndElements\n";
  const std::string body = R"(
    "material": {"model": "mooney_rivlin", "a": 1, "b": 0.2, "c": 3}, "fibers": [1, 0, 0],
    "control": {"space": "vertex", "lower": -1, "upper": 0}})";
  std::ofstream(dir_ / "tet.json") << R"({"mesh": {"type": "gmsh", "file": "tet.msh"},
    "clamp": ["tip"],)" << body;
  const std::string needle =
      "key 'clamp/constraints' does not hold the body: 'tip' leaves region 'body' free to move "
      "rigidly (3 of its 6 rigid motions";
  expect_refused("forward tet.json", needle);
  expect_refused("optimise tet.json --max-iter 1 --quiet", needle);
  const std::string mesh =
      std::string(SOFTHD_SOURCE_DIR) + "/tests/data/meshes/two_boxes_nonconforming.msh";
  std::ofstream(dir_ / "two.json")
      << R"({"mesh": {"type": "gmsh", "file": ")" << mesh << R"("}, "clamp": ["base"],)" << body;
  expect_refused("forward two.json", "regions 'left' and 'right' touch at");
}

// Mesh files: --max-memory guards a Gmsh mesh as it guards a box (forward and optimise),
// from the file's counts; a device given as mesh.file is refused, not read.
TEST_F(Reliability, MeshFileChecks) {
  const std::string mesh = std::string(SOFTHD_SOURCE_DIR) + "/tests/data/meshes/cube_tet4_v41.msh";
  std::string text = kScene;
  const std::size_t from = text.find("{ \"type\": \"box\"");
  text.replace(from, text.find('}', from) + 1 - from,
               "{ \"type\": \"gmsh\", \"file\": \"" + mesh + "\" }");
  text.replace(text.find("NAME"), 4, "file");
  text.replace(text.find("[\"x0\"]"), 6, "[\"base\"]");
  std::ofstream(dir_ / "file.json") << text;
  const std::string refused = mesh + ": the mesh has 166 nodes and 481 elements: it needs about ";
  expect_refused("forward file.json --max-memory 1e-6", refused);
  expect_refused("optimise file.json --max-memory 1e-6", refused);
  text.replace(text.find(mesh), mesh.size(), "/dev/zero");
  std::ofstream(dir_ / "zero.json") << text;
  expect_refused("forward zero.json", "'/dev/zero' is not a regular file");
}

}  // namespace
