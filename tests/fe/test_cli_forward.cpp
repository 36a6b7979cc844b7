// The `softhd forward` subcommand (apps/cmd_forward.cpp), called in-process.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "commands.hpp"

namespace {

const std::string kDir = std::string(SOFTHD_BINARY_DIR) + "/test_cli_forward";

// Runs `forward args...`, returns the exit code; stdout/stderr captured.
int run(std::vector<std::string> args, std::string* out = nullptr, std::string* err = nullptr) {
  args.insert(args.begin(), "forward");
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  testing::internal::CaptureStdout();
  testing::internal::CaptureStderr();
  const int rc = run_forward(static_cast<int>(argv.size()), argv.data());
  const std::string o = testing::internal::GetCapturedStdout();
  const std::string e = testing::internal::GetCapturedStderr();
  if (out) *out = o;
  if (err) *err = e;
  return rc;
}

// A small plate scene (the bending scene's material and bounds on a coarse mesh).
std::string small_scene(const std::string& cells = "[6, 1, 1]") {
  std::ifstream in(std::string(SOFTHD_SOURCE_DIR) + "/data/scenes/bending.json");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string from = "\"cells\": [50, 5, 2]";
  text.replace(text.find(from), from.size(), "\"cells\": " + cells);
  std::string tag;
  for (char c : cells)
    if (c >= '0' && c <= '9') tag += c;
  const std::string path = kDir + "_scene" + tag + ".json";
  std::ofstream(path) << text;
  return path;
}

}  // namespace

TEST(CliForward, SolvesAndReportsJson) {
  std::string out;
  ASSERT_EQ(run({small_scene(), "--control-uniform", "-2000", "--probe", "10,1,0.05", "--probe",
                 "4.3,0.2,0.1", "--json", "--out", kDir},
                &out),
            0);
  const nlohmann::json j = nlohmann::json::parse(out);
  for (const char* key : {"probes", "energy", "volume", "newton_iterations", "dofs", "seconds"})
    EXPECT_TRUE(j.contains(key)) << key;
  ASSERT_EQ(j["probes"].size(), 2u);
  EXPECT_EQ(j["probes"][1]["X"][0].get<double>(), 4.3);
  // Uniform contraction along X1: the free end moves back, the body shrinks.
  EXPECT_LT(j["probes"][0]["u"][0].get<double>(), 0.0);
  EXPECT_LT(j["volume"].get<double>(), 2.0);
  EXPECT_TRUE(j["converged"].get<bool>());
  std::ifstream vtu(kDir + "/forward.vtu");
  EXPECT_TRUE(vtu.good());
}

TEST(CliForward, ControlNodesRoundTrip) {
  const std::string scene = small_scene(), nodes = kDir + "_nodes.txt";
  ASSERT_EQ(run({scene, "--write-control-nodes", nodes, "--control-uniform", "-1500"}), 0);
  std::string uniform, from_file;
  ASSERT_EQ(
      run({scene, "--control-uniform", "-1500", "--probe", "10,2,0.1", "--json", "--out", kDir},
          &uniform),
      0);
  ASSERT_EQ(
      run({scene, "--control", nodes, "--probe", "10,2,0.1", "--json", "--out", kDir}, &from_file),
      0);
  EXPECT_EQ(nlohmann::json::parse(uniform)["probes"], nlohmann::json::parse(from_file)["probes"]);
  std::remove(nodes.c_str());
}

// Grid sequencing changes the starting point of Newton, not the equilibrium it finds; and
// --write-cloud writes the deformed nodes whose volumes sum to the deformed volume.
TEST(CliForward, CoarseLevelsReachTheSameStateAndTheCloudHasTheDeformedVolume) {
  const std::string scene = small_scene("[6, 2, 2]"), cloud = kDir + "_cloud.txt";
  std::string cold, sequenced, err;
  ASSERT_EQ(run({scene, "--control-uniform", "-30000", "--probe", "10,2,0.1", "--json", "--out",
                 kDir, "--write-cloud", cloud, "--coarse-levels", "0"},
                &cold),
            0);
  ASSERT_EQ(run({scene, "--control-uniform", "-30000", "--probe", "10,2,0.1", "--json", "--out",
                 kDir, "--coarse-levels", "1"},
                &sequenced, &err),
            0);
  EXPECT_NE(err.find("coarse level (cells 3 1 1)"), std::string::npos) << err;
  const nlohmann::json a = nlohmann::json::parse(cold), b = nlohmann::json::parse(sequenced);
  for (int k = 0; k < 3; ++k)
    EXPECT_NEAR(a["probes"][0]["u"][k].get<double>(), b["probes"][0]["u"][k].get<double>(), 1e-8);
  // Rows 'x y z V' of the 13 x 5 x 5 Q2 nodes.
  std::ifstream in(cloud);
  std::string line;
  int rows = 0;
  double volume = 0.0;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream ls(line);
    double x, y, z, v;
    ASSERT_TRUE(ls >> x >> y >> z >> v) << line;
    volume += v;
    ++rows;
  }
  EXPECT_EQ(rows, 13 * 5 * 5);
  EXPECT_NEAR(volume, a["volume"].get<double>(), 1e-12 * volume);
  // 3 x 1 x 1 has no even cell count to halve.
  EXPECT_EQ(run({scene, "--coarse-levels", "2", "--out", kDir}, nullptr, &err), 2);
  EXPECT_NE(err.find("can be halved"), std::string::npos) << err;
  std::remove(cloud.c_str());
}

// A curved P2 file mesh is p-sequenced by default (P1 on its vertices first, the progress
// line says so), to the state of the start from rest; it has no second coarse level.
TEST(CliForward, FileMeshesOfOrderTwoStartFromTheirVertices) {
  const std::string scene = kDir + "_cylinder.json";
  std::ofstream(scene) << R"({"name": "cylinder", "mesh": {"type": "gmsh", "file": ")"
                       << SOFTHD_SOURCE_DIR << R"(/tests/data/meshes/cylinder_tet10_v41.msh"},
    "material": {"model": "mooney_rivlin", "a": 1, "b": 0.2, "c": 3}, "fibers": [1, 0, 0],
    "clamp": ["base"], "control": {"space": "vertex", "lower": -1, "upper": 0}})";
  std::string cold, sequenced, err;
  const std::vector<std::string> args = {
      scene, "--control-uniform", "-0.4", "--probe", "2,0,0", "--json", "--out", kDir};
  std::vector<std::string> rest = args;
  rest.insert(rest.end(), {"--coarse-levels", "0"});
  ASSERT_EQ(run(rest, &cold), 0);
  ASSERT_EQ(run(args, &sequenced, &err), 0);
  EXPECT_NE(err.find("coarse level (P1 on the vertices: tet4, 50 nodes)"), std::string::npos)
      << err;
  const nlohmann::json a = nlohmann::json::parse(cold), b = nlohmann::json::parse(sequenced);
  EXPECT_TRUE(a["coarse_levels"].empty());
  ASSERT_EQ(b["coarse_levels"].size(), 1u);
  EXPECT_EQ(b["coarse_levels"][0]["cell"], "tet4");
  EXPECT_EQ(b["coarse_levels"][0]["nodes"], 50);
  for (int k = 0; k < 3; ++k)
    EXPECT_NEAR(a["probes"][0]["u"][k].get<double>(), b["probes"][0]["u"][k].get<double>(), 1e-8);
  EXPECT_EQ(run({scene, "--coarse-levels", "2", "--out", kDir}, nullptr, &err), 2);
  EXPECT_NE(err.find("2 coarser levels asked for, but the body has 1"), std::string::npos) << err;
  EXPECT_NE(err.find("is of order 1 at this level"), std::string::npos) << err;
  std::remove(scene.c_str());
}

TEST(CliForward, BadInputExitsWithTwoAndOneLine) {
  const std::string scene = small_scene();
  std::string err;
  for (const std::vector<std::string>& args :
       std::vector<std::vector<std::string>>{{"/nonexistent.json"},
                                             {scene, "--probe", "11,0,0"},
                                             {scene, "--probe", "a,b"},
                                             {scene, "--control-uniform", "1e9"},
                                             {scene, "--control", "/nonexistent.txt"},
                                             {scene, "--frobnicate"},
                                             {}}) {
    EXPECT_EQ(run(args, nullptr, &err), 2) << (args.empty() ? "" : args.back());
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  }
  std::string out;
  EXPECT_EQ(run({"--help"}, &out), 0);
  EXPECT_NE(out.find("usage"), std::string::npos);
}
