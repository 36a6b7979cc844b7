// The softhd command-line tool, run as a user runs it: exit codes, one-line errors that
// name the problem, JSON output equal to the library's numbers.

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <sstream>

#include "hausdorff_reference.hpp"
#include "softhd/control/pose_file.hpp"
#include "softhd/hausdorff.hpp"
#include "softhd/io/cloud_io.hpp"
#include "softhd/io/msh.hpp"
#include "softhd/scan/surface_weights.hpp"

namespace softhd::test {
namespace {

namespace fs = std::filesystem;

struct Outcome {
  int status = -1;
  std::string out, err;
};

class Cli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::path(::testing::TempDir()) /
           ("softhd_cli_" +
            std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  std::string write(const std::string& name, const std::string& text) const {
    std::ofstream(path(name)) << text;
    return path(name);
  }
  // `env`: assignments put before the command, e.g. "OMP_NUM_THREADS=4".
  Outcome run(const std::string& args, const std::string& env = "") const {
    const std::string out = path("stdout"), err = path("stderr");
    const std::string cmd =
        env + " " + std::string(SOFTHD_CLI) + " " + args + " >" + out + " 2>" + err;
    Outcome r;
    const int raw = std::system(cmd.c_str());
    r.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
    std::stringstream o, e;
    o << std::ifstream(out).rdbuf();
    e << std::ifstream(err).rdbuf();
    r.out = o.str();
    r.err = e.str();
    return r;
  }
  // Bad input: exit code 2 and exactly one line on stderr containing `needle`.
  void expect_bad_input(const std::string& args, const std::string& needle) const {
    const Outcome r = run(args);
    EXPECT_EQ(r.status, 2) << args;
    EXPECT_NE(r.err.find(needle), std::string::npos) << args << " -> " << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
  // "x y z\n" of one point, as the text cloud files hold it.
  static std::string xyz_line(const Eigen::Vector3d& x) {
    return std::to_string(x.x()) + " " + std::to_string(x.y()) + " " + std::to_string(x.z()) + "\n";
  }
  // The pose.json (--json output) of `align CLOUDS --out al FLAGS`, expected to succeed.
  nlohmann::json align_json(const std::string& clouds, const std::string& flags) const {
    const Outcome r = run("align " + clouds + " --out " + path("al") + flags);
    EXPECT_EQ(r.status, 0) << flags << ": " << r.err;
    return r.status == 0 ? nlohmann::json::parse(r.out) : nlohmann::json::object();
  }
  // A scene on the Gmsh file `mesh` (clamped on "base", vertex control in [-1, 0]) with
  // the "fibers" value `fibers` (JSON text).
  std::string fibre_scene(const std::string& name, const std::string& mesh,
                          const std::string& fibers) const {
    return write(name, R"({"mesh": {"type": "gmsh", "file": ")" + mesh + R"("},
      "material": {"model": "mooney_rivlin", "a": 1, "b": 0.2, "c": 3}, "fibers": )" +
                           fibers + R"(, "clamp": ["base"],
      "control": {"space": "vertex", "lower": -1, "upper": 0}})");
  }
  // forward under m = -0.3 gives the same energy and probe displacement, bitwise, with the
  // fibres `fibers` as with the constant "fibers": [1, 0, 0].
  void expect_constant_fibre_state(const std::string& mesh, const std::string& fibers) const {
    const std::string args =
        " --coarse-levels 0 --control-uniform -0.3 --json --probe 1,0.1,0.9 --out " + path("o");
    const Outcome c = run("forward " + fibre_scene("c.json", mesh, "[1, 0, 0]") + args);
    const Outcome f = run("forward " + fibre_scene("f.json", mesh, fibers) + args);
    ASSERT_EQ(c.status, 0) << c.err;
    ASSERT_EQ(f.status, 0) << fibers << ": " << f.err;
    const nlohmann::json jc = nlohmann::json::parse(c.out), jf = nlohmann::json::parse(f.out);
    EXPECT_EQ(jf["energy"].get<double>(), jc["energy"].get<double>()) << fibers;
    for (int i = 0; i < 3; ++i)
      EXPECT_EQ(jf["probes"][0]["u"][i].get<double>(), jc["probes"][0]["u"][i].get<double>())
          << fibers << " " << i;
  }
  fs::path dir_;
};

TEST_F(Cli, JsonMatchesTheLibrary) {
  const PointCloud X = random_cloud(40, 3, 1), Y = random_cloud(90, 3, 2, 0.3, 1.2);
  write_text_cloud(path("x.txt"), X);
  write_ply_cloud(path("y.ply"), Y);
  const Outcome r = run("distance " + path("x.txt") + " " + path("y.ply") + " --json --alpha 6");
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  HausdorffOptions o;
  o.params.alpha = 6;
  const HausdorffResult ref = hausdorff(X, Y, o);
  EXPECT_EQ(j["rho"].get<double>(), ref.rho);
  EXPECT_EQ(j["A"].get<double>(), ref.A);
  EXPECT_EQ(j["B"].get<double>(), ref.B);
  EXPECT_EQ(j["N"].get<int>(), 40);
  EXPECT_EQ(j["M"].get<int>(), 90);
  EXPECT_EQ(j["method"].get<std::string>(), "exact");
  EXPECT_GE(j["seconds"].get<double>(), 0.0);
}

TEST_F(Cli, TreeReportsItsToleranceAndStaysWithinIt) {
  const PointCloud X = random_cloud(400, 3, 5), Y = random_cloud(500, 3, 6, 0.3, 1.2);
  write_text_cloud(path("x.txt"), X);
  write_text_cloud(path("y.txt"), Y);
  const Outcome r =
      run("distance " + path("x.txt") + " " + path("y.txt") + " --method tree --tol 1e-3 --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["method"].get<std::string>(), "tree");
  EXPECT_EQ(j["tolerance"].get<double>(), 1e-3);
  EXPECT_GT(j["kernel_evaluations"].get<long>(), 0);
  // |Δρ̃| ≤ e (ρ̃ + ε), e = (1 − τ)^(−1/α) − 1 (docs/tree_tolerance.md).
  const double rho = hausdorff(X, Y).rho, e = std::pow(1 - 1e-3, -1.0 / 4) - 1;
  EXPECT_LE(std::fabs(j["rho"].get<double>() - rho), e * (rho + 1e-3));
  expect_bad_input("distance " + path("x.txt") + " " + path("y.txt") + " --method tree --tol 2",
                   "tolerance");
}

TEST_F(Cli, NearestGivesTheHausdorffDistance) {
  write("x.txt", "0 0 0\n1 0 0\n");
  write("y.txt", "0 0 0.5\n1 0 0.5\n0.5 0.5 0.5\n");
  const Outcome r =
      run("distance " + path("x.txt") + " " + path("y.txt") + " --method nearest --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  // By hand: y = (0.5, 0.5, 0.5) is √0.75 from both x; each x is 0.5 from a y.
  EXPECT_DOUBLE_EQ(j["A"].get<double>(), std::sqrt(0.75));
  EXPECT_DOUBLE_EQ(j["B"].get<double>(), 0.5);
  EXPECT_DOUBLE_EQ(j["rho"].get<double>(), std::sqrt(0.75));
}

TEST_F(Cli, GradientFileHasOneRowPerMovingPoint) {
  const PointCloud X = random_cloud(7, 2, 3), Y = random_cloud(9, 2, 4);
  write_text_cloud(path("x.txt"), X, false);
  write_text_cloud(path("y.txt"), Y, false);
  const Outcome r =
      run("distance " + path("x.txt") + " " + path("y.txt") + " --grad " + path("g.txt"));
  ASSERT_EQ(r.status, 0) << r.err;
  HausdorffRequest req;
  req.gradient_points = req.gradient_volumes = true;
  const HausdorffResult ref = hausdorff(PointCloud(X.points()), PointCloud(Y.points()), {}, req);
  std::ifstream g(path("g.txt"));
  std::string line;
  std::getline(g, line);
  EXPECT_EQ(line[0], '#');
  for (Eigen::Index i = 0; i < 7; ++i) {
    double x, y, gx, gy, gv;
    ASSERT_TRUE(g >> x >> y >> gx >> gy >> gv) << "row " << i;
    EXPECT_EQ(gx, ref.gradient_points(i, 0));
    EXPECT_EQ(gy, ref.gradient_points(i, 1));
    EXPECT_EQ(gv, ref.gradient_volumes[i]);
  }
  double extra;
  EXPECT_FALSE(g >> extra);
}

TEST_F(Cli, BadInputGivesExitCode2AndOneLine) {
  const std::string good = write("good.txt", "0 0 0\n1 0 0\n");
  expect_bad_input("distance " + good + " " + path("missing.txt"), "cannot open");
  expect_bad_input("distance " + good + " " + write("m.txt", "0 0 0\n1 zero 0\n"), "m.txt:2");
  expect_bad_input("distance " + good + " " + write("n.txt", "0 0 0\nnan 0 0\n"), "n.txt:2");
  expect_bad_input("distance " + good + " " + write("v.txt", "0 0 0 1\n1 0 0 0\n"), "v.txt:2");
  expect_bad_input("distance " + good + " " + write("w.txt", "0 0 0 -2\n"), "w.txt:1");
  expect_bad_input("distance " + good + " " + write("d.txt", "0 0 0\n1 0\n"), "d.txt:2");
  expect_bad_input("distance " + good + " " + write("e.txt", "# nothing\n"), "e.txt");
  expect_bad_input("distance " + good + " " + write("two.txt", "0 0\n1 1\n"), "mixed dimensions");
  expect_bad_input("distance " + good + " " + good + " --alpha 0", "alpha must be finite and > 0");
  expect_bad_input("distance " + good + " " + good + " --beta -1", "beta must be finite and > 0");
  expect_bad_input("distance " + good + " " + good + " --gamma nan", "--gamma");
  expect_bad_input("distance " + good + " " + good + " --eps 0", "epsilon must be finite and > 0");
  expect_bad_input("distance " + good + " " + good + " --method fast", "unknown method 'fast'");
  expect_bad_input("distance " + good + " " + good + " --dim 4", "--dim must be 2 or 3");
  expect_bad_input("distance " + good + " " + good + " --frobnicate", "unknown option");
  expect_bad_input("distance " + good, "expected two cloud files");
  expect_bad_input("launch", "unknown command 'launch'");
  // Coordinates whose squares overflow: refused naming the limit, never rho = 0 or NaN.
  const std::string far = write("far.txt", "1e155 0 0\n");
  const std::string origin = write("origin.txt", "0 0 0\n");
  for (const char* method : {"exact", "tree", "nearest"}) {
    expect_bad_input("distance " + far + " " + origin + " --method " + method,
                     "above the limit of 1e+150");
    expect_bad_input(
        "distance " + origin + " " + write("huge.txt", "1e308 0 0\n") + " --method " + method,
        "huge.txt cloud: point 1 has a coordinate of magnitude 1e+308");
  }
  // Issue 29: the library's bound, not "use 0" (0 is refused too).
  expect_bad_input("distance " + good + " " + good + " --eps 1e-320",
                   "epsilon must be at least 1e-300, got 9.99989e-321");
  expect_bad_input("distance " + good + " " + good + " --eps 1e-400",
                   "--eps: 1e-400 underflows to 0 in double precision");
  expect_bad_input(
      "distance " + good + " " + good + " --alpha 1e-320",
      "alpha must be at least 2.22507e-308, got 9.99989e-321 (the smallest normal double)");
  expect_bad_input("distance " + good + " " + good + " --eps 1e400",
                   "--eps: 1e400 is not a finite");
  expect_bad_input("distance " + good + " " + good + " --threads 99999",
                   "--threads: expected an integer from 0 to 1024, got '99999'");
  // A binary PLY declaring 2 vertices but holding 3: refused, not cut to 2.
  std::string ply =
      "ply\nformat binary_little_endian 1.0\nelement vertex 2\n"
      "property double x\nproperty double y\nproperty double z\nend_header\n";
  const double xyz[9] = {0, 0, 0, 1, 0, 0, 2, 0, 0};
  ply.append(reinterpret_cast<const char*>(xyz), sizeof xyz);
  expect_bad_input("distance " + good + " " + write("three.ply", ply), "three.ply");
}

// softhd align (issue 32): an exactly moved copy of a body is put back (pose.txt read by
// the library's own reader), every output is written, and bad input is exit 2 and one line.
TEST_F(Cli, AlignRecoversAMovedCopyAndRefusesBadInput) {
  std::string body_text, scan_text;
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(2.0, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const Eigen::Vector3d t(0.5, -1.0, 2.0);
  for (int i = 0; i < 120; ++i) {  // an asymmetric spiral: no rotation maps it onto itself
    const double a = 0.15 * i;
    const Eigen::Vector3d x(std::cos(a) * (1 + 0.01 * i), std::sin(a), 0.02 * i * (i % 3));
    const Eigen::Vector3d y = R.transpose() * (x - t);  // P⁻¹ x
    body_text += xyz_line(x);
    std::ostringstream os;
    os.precision(17);
    os << y.x() << ' ' << y.y() << ' ' << y.z() << '\n';
    scan_text += os.str();
  }
  const std::string body = write("body.txt", body_text), scan = write("scan.txt", scan_text);
  const Outcome ok = run("align " + body + " " + scan + " --out " + path("al") + " --threads 2");
  ASSERT_EQ(ok.status, 0) << ok.err;
  for (const char* f : {"pose.txt", "pose.json", "aligned.ply", "residuals.csv"})
    EXPECT_TRUE(fs::exists(dir_ / "al" / f)) << f;
  const scan::Pose P = read_pose(path("al/pose.txt"));
  EXPECT_LT(scan::rotation_angle_between(P.R, R), 1e-5);  // body written with 6 decimals
  EXPECT_LT((P.t - t).norm(), 1e-5);
  const std::string good = write("good.txt", "0 0 0\n1 0 0\n0 1 0\n0 0 1\n");
  const std::string out = " --out " + path("bad");
  expect_bad_input("align " + good + " " + good + out + " --no-global --initial " +
                       write("p3.txt", "1 0 0 0\n0 1 0 0\n0 0 1 0\n"),
                   "p3.txt: expected 4 rows");
  expect_bad_input("align " + good + " " + good + out + " --initial " +
                       write("p5.txt", "1 0 0 0\n0 1 0 0\n0 0 1\n0 0 0 1\n"),
                   "p5.txt:3: expected 4 numbers, got 3");
  expect_bad_input("align " + good + " " + good + out + " --initial " +
                       write("shear.txt", "1 0.5 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n"),
                   "not a scaled rotation");
  expect_bad_input("align " + good + " " + write("nan.txt", "0 0 0\nnan 1 0\n") + out, "nan.txt:2");
  expect_bad_input("align " + good + " " + good + out + " --score best", "--score must be");
  expect_bad_input("align " + good + " " + good + out + " --score visible",
                   "--score visible is now --score coverage");
  expect_bad_input("align " + good + " " + good + out + " --score-cap 0", "--score-cap must be");
  expect_bad_input("align " + good + " " + good + out + " --similarity --scale-min 1.5",
                   "--scale-min must be in (0, 1]");
  expect_bad_input("align " + good + " " + good + out + " --scale-max 0.8",
                   "--scale-max must be >= 1");
  expect_bad_input("align " + good + " " + write("flat.txt", "0 0\n1 1\n") + out, "align takes 3D");
  expect_bad_input("align " + good + " " + good, "--out DIR is required");
  // --fixture (the table in the body's frame) and --table (the scan's, found by RANSAC).
  expect_bad_input("align " + good + " " + good + out + " --fixture 0,0,0,1 --table 0.1",
                   "--fixture: the normal has zero length");
  expect_bad_input("align " + good + " " + good + out + " --fixture 0,0,1,nan --table 0.1",
                   "--fixture: nan is not a finite double");
  expect_bad_input("align " + good + " " + good + out + " --fixture 0,0,1 --table 0.1",
                   "--fixture must be 4 numbers");
  expect_bad_input("align " + good + " " + good + out + " --fixture 0,0,1,0",
                   "--fixture needs --table T");
  expect_bad_input("align " + good + " " + good + out + " --fixture 0,0,1,0 --table 0",
                   "--table must be > 0");
  expect_bad_input("align " + good + " " + good + out + " --fixture 0,0,1,0 --table 1 --similarity",
                   "--fixture needs a rigid alignment");
  std::string scattered;  // 40 points of which no plane holds 10 % within 1e-9
  for (int i = 0; i < 40; ++i)
    scattered += xyz_line(
        Eigen::Vector3d(std::sin(1.3 * i), std::cos(2.1 * i + 0.4), std::sin(0.7 * i * i)));
  expect_bad_input("align " + good + " " + write("scattered.txt", scattered) + out +
                       " --fixture 0,0,1,0 --table 1e-9",
                   "scattered.txt: no table plane for --fixture");
}

// align --surface: the body's surface is the scene mesh's boundary, so a scan of points on
// that surface (not its nodes: a grid over each face, between the nodes), rigidly moved, is put
// back to rounding from a start 10 degrees off (the point-to-plane finish); without --surface
// only to the nodes' spacing. A cloud body has no surface: exit 2 naming --surface.
TEST_F(Cli, AlignSurfaceRecoversPointsBetweenTheNodes) {
  const std::string scene = write("box.json", R"({
  "mesh": { "type": "box", "lower": [0, 0, 0], "upper": [1, 0.6, 0.3], "cells": [3, 2, 1], "order": 1 },
  "material": { "model": "mooney_rivlin", "a": 1e5, "b": 2e4, "c": 3e5 },
  "fibers": [1, 0, 0],
  "clamp": ["x0"],
  "control": { "space": "vertex", "lower": -1e5, "upper": 0, "initial": 0 }
})");
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(0.17, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const Eigen::Vector3d t(0.05, -0.1, 0.02), upper(1.0, 0.6, 0.3);
  std::ostringstream scan;
  scan.precision(17);
  for (int a = 0; a < 3; ++a)  // the box's 6 faces, a 7 × 7 grid of points on each
    for (double side : {0.0, 1.0})
      for (int i = 0; i < 7; ++i)
        for (int j = 0; j < 7; ++j) {
          Eigen::Vector3d x;
          x[a] = side * upper[a];
          x[(a + 1) % 3] = (i + 0.37) / 7.0 * upper[(a + 1) % 3];
          x[(a + 2) % 3] = (j + 0.61) / 7.0 * upper[(a + 2) % 3];
          const Eigen::Vector3d y = R.transpose() * (x - t);  // P⁻¹ x
          scan << y.x() << ' ' << y.y() << ' ' << y.z() << '\n';
        }
  const std::string clouds = scene + " " + write("box_scan.txt", scan.str());
  const std::string flags = " --no-global --threads 2 --json";
  const nlohmann::json with = align_json(clouds, flags + " --surface");
  const nlohmann::json without = align_json(clouds, flags);
  const auto error = [&](const nlohmann::json& j) -> double {
    if (!j.contains("matrix")) return INFINITY;
    Eigen::Matrix3d M;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) M(r, c) = j["matrix"][r][c].get<double>();
    return scan::rotation_angle_between(M, R);
  };
  EXPECT_LT(error(with), 1e-9);
  EXPECT_GT(error(without), 1e-6);
  EXPECT_EQ(with.value("surface_triangles", -1), 2 * (2 * 3 * 2 + 2 * 3 * 1 + 2 * 2 * 1));
  EXPECT_EQ(without.value("surface_triangles", -1), 0);
  expect_bad_input("align " + write("pts.txt", "0 0 0\n1 0 0\n0 1 0\n0 0 1\n") + " " +
                       clouds.substr(clouds.find(' ') + 1) + " --out " + path("bad") + " --surface",
                   "--surface needs a scene file");
}

// align --inlier F: the overlap's threshold is F times the body size L (pose.json's
// inlier_distance / body_size), and a wider threshold counts at least as many scan points in.
TEST_F(Cli, AlignInlierIsAFractionOfTheBodySize) {
  std::string body_text, scan_text;
  for (int i = 0; i < 60; ++i) {  // an asymmetric spiral and a shifted, perturbed copy
    const double a = 0.15 * i;
    const Eigen::Vector3d x(std::cos(a) * (1 + 0.01 * i), std::sin(a), 0.02 * i * (i % 3));
    const Eigen::Vector3d y = x + Eigen::Vector3d(0.3, -0.1, 0.05 * std::sin(7.0 * i));
    body_text += xyz_line(x);
    scan_text += xyz_line(y);
  }
  const std::string clouds =
      write("body.txt", body_text) + " " + write("scan.txt", scan_text) + " --threads 1 --json";
  const auto pose = [&](const std::string& flags) { return align_json(clouds, flags); };
  const nlohmann::json def = pose(""), wide = pose(" --inlier 0.2");
  const double L = def.value("body_size", 0.0);
  ASSERT_GT(L, 0.0);
  EXPECT_NEAR(def.value("inlier_distance", 0.0), 0.01 * L, 1e-15 * L);  // the default 0.01
  EXPECT_NEAR(wide.value("inlier_distance", 0.0), 0.2 * L, 1e-15 * L);
  EXPECT_GE(wide.value("overlap", 0.0), def.value("overlap", 1.0));
  // a threshold of L or more (the body's diagonal) measures no overlap: refused naming the flag
  for (const char* bad : {"0", "-0.1", "1", "1.5"})
    expect_bad_input("align " + clouds + " --out " + path("bad") + " --inlier " + bad,
                     "--inlier must be in (0, 1)");
}

// align --rotations, --keep, --refine-points and --no-global reach the search: pose.json
// counts the starting poses (rotations + 4 principal-axis ones), the candidates refined (at
// most --keep, plus --initial) and the refinement's points of body and scan, so a flag
// that is ignored fails here.
TEST_F(Cli, AlignSearchFlagsShowInPoseJson) {
  std::string body_text, scan_text;
  for (int i = 0; i < 120; ++i) {  // an asymmetric spiral and a shifted copy of 100 of its points
    const double a = 0.15 * i;
    const Eigen::Vector3d x(std::cos(a) * (1 + 0.01 * i), std::sin(a), 0.02 * i * (i % 3));
    body_text += xyz_line(x);
    if (i >= 100) continue;
    const Eigen::Vector3d y = x + Eigen::Vector3d(0.3, -0.1, 0.2);
    scan_text += xyz_line(y);
  }
  const std::string clouds =
      write("body.txt", body_text) + " " + write("scan.txt", scan_text) + " --threads 1 --json";
  const auto pose = [&](const std::string& flags) { return align_json(clouds, flags); };
  const auto points = [](const nlohmann::json& j) {
    return j.value("refine_points", std::vector<long>{});
  };
  const nlohmann::json def = pose("");
  EXPECT_EQ(def.value("starts", -1), 48 + 4);
  EXPECT_EQ(def.value("candidates", -1), 4);              // the default --keep
  EXPECT_EQ(points(def), (std::vector<long>{120, 100}));  // below the default 1000: all
  EXPECT_EQ(pose(" --rotations 10").value("starts", -1), 10 + 4);
  EXPECT_EQ(pose(" --rotations 0").value("starts", -1), 4);  // the principal-axis starts only
  EXPECT_EQ(pose(" --keep 1").value("candidates", -1), 1);
  EXPECT_EQ(pose(" --keep 2").value("candidates", -1), 2);
  EXPECT_EQ(points(pose(" --refine-points 30")), (std::vector<long>{30, 30}));
  EXPECT_EQ(points(pose(" --refine-points 110")), (std::vector<long>{110, 100}));
  const nlohmann::json local = pose(" --no-global");
  EXPECT_EQ(local.value("starts", -1), 0);
  EXPECT_EQ(local.value("candidates", -1), 1);
  const std::string identity = write("id.txt", "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n");
  EXPECT_EQ(pose(" --keep 2 --initial " + identity).value("candidates", -1), 2 + 1);
}

// A body or scan that fixes no pose (a single point, coincident or collinear points) is refused
// naming its file, as are --distance visible (align has no camera) and a scaled --initial for a
// rigid alignment: exit 2 and one line.
TEST_F(Cli, AlignRefusesCloudsThatFixNoPose) {
  const std::string good = write("good.txt", "0 0 0\n1 0 0\n0 1 0\n0 0 1\n");
  const std::string one = write("one.txt", "0.5 0.2 0.1\n");
  const std::string line = write("line.txt", "0 0 0\n1 2 3\n2 4 6\n");
  const std::string same = write("same.txt", "1 2 3\n1 2 3\n1 2 3\n");
  const std::string out = " --out " + path("bad");
  expect_bad_input("align " + good + " " + one + out, "one.txt: it has a single point");
  expect_bad_input("align " + good + " " + line + out, "line.txt: its 3 points are collinear");
  expect_bad_input("align " + good + " " + same + out, "same.txt: its 3 points coincide");
  expect_bad_input("align " + same + " " + good + out, "same.txt: its 3 points coincide");
  expect_bad_input("align " + good + " " + good + out + " --distance visible",
                   "--distance visible is not supported by align");
  expect_bad_input("align " + good + " " + good + out + " --initial " +
                       write("big.txt", "2 0 0 0\n0 2 0 0\n0 0 2 0\n0 0 0 1\n"),
                   "big.txt: the pose has scale 2; a rigid alignment keeps scale 1");
  EXPECT_FALSE(fs::exists(dir_ / "bad"));
}

// The distance forms (docs/formulation.md §8): the flags give the library's numbers, and their
// misuse is one line naming the flag, the file or its line.
TEST_F(Cli, DistanceFormsMatchTheLibraryAndRefuseMisuse) {
  const PointCloud X = random_cloud(12, 3, 31), Y = random_cloud(9, 3, 32, 0.3, 1.2);
  write_text_cloud(path("x.txt"), X);
  write_text_cloud(path("y.txt"), Y);
  std::string lines = "# visible points\n";
  DistanceForm form;
  form.sides = Sides::visible;
  form.cap = {0.4, 2.0};
  form.camera_mask.resize(12);
  for (int i = 0; i < 12; ++i) {
    form.camera_mask[i] = i % 3 != 1;
    lines += form.camera_mask[i] ? "1\n" : "0  # hidden\n";
  }
  const std::string seen = write("seen.txt", lines);
  const Outcome r =
      run("distance " + path("x.txt") + " " + path("y.txt") + " --distance visible --camera-mask " +
          seen + " --cap 0.4 --cap-q 2 --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  HausdorffRequest req;
  req.form = form;
  const HausdorffResult ref = hausdorff(X, Y, {}, req);
  EXPECT_EQ(j["rho"].get<double>(), ref.rho);
  EXPECT_EQ(j["B"].get<double>(), ref.B);
  EXPECT_EQ(j["distance"], "visible");
  const Outcome one =
      run("distance " + path("x.txt") + " " + path("y.txt") + " --distance scan_to_body --json");
  ASSERT_EQ(one.status, 0) << one.err;
  EXPECT_EQ(nlohmann::json::parse(one.out)["B"].get<double>(), 0.0);
  const std::string xy = path("x.txt") + " " + path("y.txt");
  expect_bad_input("distance " + xy + " --distance both", "unknown distance 'both'");
  expect_bad_input("distance " + xy + " --distance visible",
                   "--distance visible needs --camera-mask");
  expect_bad_input("distance " + xy + " --camera-mask " + seen,
                   "--camera-mask needs --distance visible");
  // the retired spelling of --camera-mask is refused naming the new one
  expect_bad_input("distance " + xy + " --distance visible --visible " + seen,
                   "--visible is now --camera-mask");
  expect_bad_input("distance " + xy + " --cap -1", "--cap/--cap-q: distance cap.c must be");
  expect_bad_input("distance " + xy + " --cap 1 --cap-q 0", "distance cap.q must be");
  // Below the accepted ranges (docs/formulation.md §8.3) rho was 0 or the constant cap.
  expect_bad_input("distance " + xy + " --cap 1 --cap-q 1e-300",
                   "distance cap.q must be finite and >= 0.001");
  expect_bad_input("distance " + xy + " --cap 1e-300",
                   "--cap: distance cap (cap.c) 1e-300 is below");
  expect_bad_input(
      "distance " + xy + " --distance visible --camera-mask " + write("bad.txt", "1\n0\nyes\n"),
      "bad.txt:3: expected 0 or 1, got 'yes'");
  expect_bad_input(
      "distance " + xy + " --distance visible --camera-mask " + write("few.txt", "1\n0\n"),
      "few.txt: 2 entries for the 12 points of");
  expect_bad_input(
      "distance " + xy + " --distance visible --camera-mask " + write("none.txt", "0\n"),
      "none.txt: 1 entries");
  expect_bad_input(
      "distance " + xy + " --distance visible --camera-mask " + write("e.txt", "# no\n"),
      "e.txt: no entries");
  std::string zeros;
  for (int i = 0; i < 12; ++i) zeros += "0\n";
  expect_bad_input("distance " + xy + " --distance visible --camera-mask " + write("z.txt", zeros),
                   "the camera_mask marks no moving point");
}

// distance's cleanup flags act on TARGET as documented: --crop keeps exactly the points in
// MOVING's (inflated) box, --plane removes the dominant plane, --outliers the far point,
// --weights knn gives the library's distance to the knn-weighted cloud; bad values are
// exit 2 and one line naming the flag.
TEST_F(Cli, DistanceCleanupFlagsChangeTheTargetAsDocumented) {
  const std::string x = write("x.txt", "0 0 0\n1 0 0\n0 1 0\n0 0 1\n1 1 1\n");  // box [0,1]^3
  // 3 points in the box, one at 1.5 (kept by a margin of diag = sqrt 3), one at 10 (never).
  const std::string y = write("y.txt", "0.5 0.5 0.5\n0.2 0.1 0.9\n1 1 1\n1.5 0.5 0.5\n10 0 0\n");
  const auto kept = [&](const std::string& flags) {
    const Outcome r = run("distance " + x + " " + y + " --json " + flags);
    EXPECT_EQ(r.status, 0) << flags << ": " << r.err;
    return r.status == 0 ? nlohmann::json::parse(r.out)["M"].get<int>() : -1;
  };
  EXPECT_EQ(kept(""), 5);
  EXPECT_EQ(kept("--crop 0"), 3);
  EXPECT_EQ(kept("--crop 1"), 4);
  // 36 points on the plane z = 0 and 4 off it: the plane goes, the 4 stay.
  std::string plane_text;
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j)
      plane_text += std::to_string(0.2 * i) + " " + std::to_string(0.2 * j) + " 0\n";
  plane_text += "0.1 0.3 0.5\n0.7 0.2 0.8\n0.4 0.9 0.3\n0.6 0.6 1.0\n";
  const Outcome p =
      run("distance " + x + " " + write("p.txt", plane_text) + " --json --plane 0.01");
  ASSERT_EQ(p.status, 0) << p.err;
  EXPECT_EQ(nlohmann::json::parse(p.out)["M"].get<int>(), 4);
  // A 3x3x3 grid of spacing 0.1 and one point at (5,5,5): mean distance to the 4 nearest
  // is <= 0.12 on the grid, ~8.5 for the far point (mean + 1 std over the cloud ~ 1.9).
  std::string grid = "5 5 5\n";
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k)
        grid += std::to_string(0.1 * i) + " " + std::to_string(0.1 * j) + " " +
                std::to_string(0.1 * k) + "\n";
  const Outcome o = run("distance " + x + " " + write("g.txt", grid) + " --json --outliers 4,1");
  ASSERT_EQ(o.status, 0) << o.err;
  EXPECT_EQ(nlohmann::json::parse(o.out)["M"].get<int>(), 27);
  // --weights knn: the library's distance to the cloud with knn area weights.
  const PointCloud X = random_cloud(10, 3, 41), Y = random_cloud(40, 3, 42);
  write_text_cloud(path("rx.txt"), X);
  write_text_cloud(path("ry.txt"), Y);
  const Outcome w =
      run("distance " + path("rx.txt") + " " + path("ry.txt") + " --json --weights knn");
  ASSERT_EQ(w.status, 0) << w.err;
  const double rho_knn =
      hausdorff(X, scan::with_area_weights(Y, scan::AreaEstimate::knn), {}, {}).rho;
  EXPECT_EQ(nlohmann::json::parse(w.out)["rho"].get<double>(), rho_knn);
  EXPECT_NE(rho_knn, hausdorff(X, Y, {}, {}).rho);  // the weights do change the distance
  const std::string xy = x + " " + y;
  expect_bad_input("distance " + xy + " --crop -1", "--crop");
  expect_bad_input("distance " + xy + " --plane 0", "--plane");
  expect_bad_input("distance " + xy + " --outliers 5", "--outliers");
  expect_bad_input("distance " + xy + " --outliers 0,2", "--outliers");
  expect_bad_input("distance " + xy + " --weights area", "--weights");
}

// forward's Newton flags have their documented effect on a 12-element plate (counts read from
// --json): --factorize-every-step factorises more and runs no PCG, --load-increment 0.25 takes
// more load steps, --intermediate-tol 0.5 then accepts the early steps in fewer iterations,
// --step-tol 0 (residual test only) stops sooner than the default 1e-10, --linear-solver
// eigen-llt gives cholmod's displacement, --verbose prints one line per Newton iteration.
TEST_F(Cli, ForwardSolverFlagsChangeTheNewtonRunAsDocumented) {
  const std::string scene = write("s.json", R"({
  "mesh": { "type": "box", "lower": [0, 0, 0], "upper": [2, 0.4, 0.2], "cells": [6, 1, 2], "order": 1 },
  "material": { "model": "mooney_rivlin", "a": 1e5, "b": 2e4, "c": 3e5 },
  "fibers": [1, 0, 0],
  "clamp": ["x0"],
  "control": { "space": "vertex", "lower": -1e5, "upper": 0, "initial": 0 }
})");
  const std::string base = "forward " + scene + " --control-uniform -8e4 --coarse-levels 0 --out " +
                           path("o") + " --probe 2,0.2,0.1 ";
  const auto solve = [&](const std::string& flags) {
    const Outcome r = run(base + "--json " + flags);
    EXPECT_EQ(r.status, 0) << flags << ": " << r.err;
    return r.status == 0 ? nlohmann::json::parse(r.out) : nlohmann::json::object();
  };
  const auto n = [](const nlohmann::json& j, const char* key) { return j.value(key, -1); };
  const nlohmann::json def = solve("");
  ASSERT_EQ(n(def, "load_steps"), 1);
  ASSERT_EQ(n(def, "factorizations"), 1);
  ASSERT_GT(n(def, "krylov_iterations"), 0);
  const nlohmann::json every = solve("--factorize-every-step");
  EXPECT_GT(n(every, "factorizations"), 1);
  EXPECT_EQ(n(every, "krylov_iterations"), 0);
  const nlohmann::json quarter = solve("--load-increment 0.25");
  EXPECT_GE(n(quarter, "load_steps"), 3);  // 0.25, then at most doubled: 0.5 and 0.25 more
  EXPECT_GT(n(quarter, "newton_iterations"), n(def, "newton_iterations"));
  const nlohmann::json loose = solve("--load-increment 0.25 --intermediate-tol 0.5");
  EXPECT_EQ(n(loose, "load_steps"), n(quarter, "load_steps"));
  EXPECT_LT(n(loose, "newton_iterations"), n(quarter, "newton_iterations"));
  EXPECT_LT(n(solve("--step-tol 0"), "newton_iterations"), n(def, "newton_iterations"));
  const nlohmann::json llt = solve("--linear-solver eigen-llt");
  const double u_ref = def["probes"][0]["u"][0].get<double>();
  ASSERT_LT(u_ref, -0.1);  // the plate does shorten
  EXPECT_NEAR(llt["probes"][0]["u"][0].get<double>(), u_ref, 1e-10 * std::abs(u_ref));
  // --verbose: "newton: ..." per iteration on stderr (nothing there without it).
  const Outcome quiet = run(base), verbose = run(base + "--verbose");
  ASSERT_EQ(verbose.status, 0) << verbose.err;
  EXPECT_EQ(quiet.err, "");
  EXPECT_EQ(std::count(verbose.err.begin(), verbose.err.end(), '\n'), n(def, "newton_iterations"));
  EXPECT_EQ(verbose.err.rfind("newton: ", 0), 0u) << verbose.err;
  expect_bad_input(base + "--step-tol 1", "--step-tol");
  expect_bad_input(base + "--load-increment 0", "--load-increment");
  expect_bad_input(base + "--intermediate-tol 1", "--intermediate-tol");
  expect_bad_input(base + "--linear-solver lu", "--linear-solver: unknown linear solver 'lu'");
}

// Scene keys of a file mesh, through forward --json on the unit cube (base x = 0, tip x = 1):
// "mesh.scale": 2 gives 8 times the volume at rest and, the load being a stress, twice the
// displacement at the scaled point; constraints [{"group": "tip", "components": [1]}] makes
// u_y zero on the tip face only (not inside, and not without it); an unknown group is exit 2.
TEST_F(Cli, MeshScaleAndConstraintGroupActOnAFileMesh) {
  const std::string mesh = std::string(SOFTHD_SOURCE_DIR) + "/tests/data/meshes/cube_tet4_v41.msh";
  const auto scene = [&](const std::string& name, const std::string& mesh_extra,
                         const std::string& extra) {
    return write(name, R"({"mesh": {"type": "gmsh", "file": ")" + mesh + "\"" + mesh_extra +
                           R"(}, "material": {"model": "mooney_rivlin", "a": 1, "b": 0.2, "c": 3},
      "fibers": [1, 0, 0], "clamp": ["base"])" +
                           extra + R"(, "control": {"space": "vertex", "lower": -1, "upper": 0}})");
  };
  const std::string one = scene("one.json", "", ""), two = scene("two.json", R"(, "scale": 2)", "");
  const std::string tip =
      scene("tip.json", "", R"(, "constraints": [{"group": "tip", "components": [1]}])");
  const auto solve = [&](const std::string& file, const std::string& flags) {
    const Outcome r =
        run("forward " + file + " --coarse-levels 0 --json --out " + path("o") + " " + flags);
    EXPECT_EQ(r.status, 0) << file << flags << ": " << r.err;
    return r.status == 0 ? nlohmann::json::parse(r.out) : nlohmann::json::object();
  };
  EXPECT_NEAR(solve(one, "--control-uniform 0").value("volume", 0.0), 1.0, 1e-12);
  EXPECT_NEAR(solve(two, "--control-uniform 0").value("volume", 0.0), 8.0, 8e-12);
  const nlohmann::json u1 = solve(one, "--control-uniform -0.3 --probe 0.9,0.3,0.7");
  const nlohmann::json u2 = solve(two, "--control-uniform -0.3 --probe 1.8,0.6,1.4");
  for (int i = 0; i < 3; ++i) {
    const double a = u1["probes"][0]["u"][i].get<double>(),
                 b = u2["probes"][0]["u"][i].get<double>();
    EXPECT_GT(std::abs(a), 1e-3) << i;
    EXPECT_NEAR(b, 2.0 * a, 1e-9 * std::abs(a)) << i;
  }
  const std::string probes = " --control-uniform -0.3 --probe 1,0.1,0.9 --probe 0.9,0.1,0.9";
  const nlohmann::json free = solve(one, probes), held = solve(tip, probes);
  EXPECT_GT(std::abs(free["probes"][0]["u"][1].get<double>()), 1e-3);  // tip, not held
  EXPECT_NEAR(held["probes"][0]["u"][1].get<double>(), 0.0, 1e-14);    // tip, held in y
  EXPECT_GT(std::abs(held["probes"][0]["u"][0].get<double>()), 1e-3);  // x stays free
  EXPECT_GT(std::abs(held["probes"][1]["u"][1].get<double>()), 1e-4);  // inside: free
  const std::string tap =
      scene("tap.json", "", R"(, "constraints": [{"group": "tap", "components": [1]}])");
  expect_bad_input("forward " + tap + " --out " + path("o"),
                   "key 'constraints[].group' is invalid: unknown boundary face 'tap'");
}

// "fibers": {"file": F, "per": "element"} with one row per tetrahedron of the file (counted
// from the file's element blocks), ±x with varying signs, gives the state of the constant
// "fibers": [1, 0, 0] (a fibre is an axis); a file one row short is exit 2 naming it.
TEST_F(Cli, ElementFibreFileIsTheConstantFibreField) {
  const std::string mesh = std::string(SOFTHD_SOURCE_DIR) + "/tests/data/meshes/cube_tet4_v41.msh";
  Eigen::Index elements = 0;
  for (const io::MshElementBlock& b : io::read_msh(mesh).blocks)
    if (b.dim == 3) elements += b.nodes.rows();
  ASSERT_GT(elements, 10);
  const auto fibre_rows = [&](const std::string& name, Eigen::Index rows) {
    std::string t;
    for (Eigen::Index k = 0; k < rows; ++k) t += (k % 3 == 1 ? "-1 0 0\n" : "1 0 0\n");
    return write(name, t);
  };
  fibre_rows("fib.txt", elements);
  fibre_rows("short.txt", elements - 1);
  expect_constant_fibre_state(mesh, R"({"file": "fib.txt", "per": "element"})");
  expect_bad_input("forward " +
                       fibre_scene("s.json", mesh, R"({"file": "short.txt", "per": "element"})") +
                       " --out " + path("o"),
                   "short.txt: " + std::to_string(elements - 1) + " fibre rows for the mesh's " +
                       std::to_string(elements) + " elements");
}

// "fibers": {"data": NAME} reads a $NodeData block of the mesh file: every node's fibre ±x
// (signs varying) gives the state of the constant "fibers": [1, 0, 0]; a name the file does
// not hold is exit 2 naming it.
TEST_F(Cli, NodeDataFibresAreTheConstantFibreField) {
  const std::string cube = std::string(SOFTHD_SOURCE_DIR) + "/tests/data/meshes/cube_tet4_v41.msh";
  const io::MshFile f = io::read_msh(cube);
  std::ifstream in(cube);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  text += "$NodeData\n1\n\"fibres\"\n1\n0\n3\n0\n3\n" + std::to_string(f.node_tags.size()) + "\n";
  for (std::size_t k = 0; k < f.node_tags.size(); ++k)
    text += std::to_string(f.node_tags[k]) + (k % 3 == 1 ? " -1 0 0\n" : " 1 0 0\n");
  text += "$EndNodeData\n";
  const std::string mesh = write("fibres.msh", text);
  expect_constant_fibre_state(mesh, R"({"data": "fibres"})");
  expect_bad_input(
      "forward " + fibre_scene("x.json", mesh, R"({"data": "fibers"})") + " --out " + path("o"),
      "fibers");
}

// Issue 29: OMP_NUM_THREADS=100000 segfaulted inside GOMP_parallel; the default is clamped to
// softhd's cap (1024 threads), and the answer is the one-thread answer.
TEST_F(Cli, AHugeOmpNumThreadsIsClampedNotCrashed) {
  write_text_cloud(path("x.txt"), random_cloud(3000, 3, 1));
  write_text_cloud(path("y.txt"), random_cloud(2000, 3, 2, 0.3, 1.2));
  for (const char* method : {"exact", "tree", "nearest"}) {
    const std::string args =
        "distance " + path("x.txt") + " " + path("y.txt") + " --json --method " + method;
    const Outcome one = run(args + " --threads 1");
    ASSERT_EQ(one.status, 0) << one.err;
    const Outcome many = run(args, "OMP_NUM_THREADS=100000");
    ASSERT_EQ(many.status, 0) << method << ": " << many.err;
    EXPECT_EQ(nlohmann::json::parse(many.out)["rho"], nlohmann::json::parse(one.out)["rho"])
        << method;
  }
}

TEST_F(Cli, ForwardRefusesMeshesBeyondTheLimits) {
  const std::string scene = R"({"mesh": {"type": "box", "lower": [0, 0, 0], "upper": [1, 1, 1],
    "cells": CELLS, "order": 1}, "material": {"model": "mooney_rivlin", "a": 1e5, "b": 2e4,
    "c": 3e5}, "fibers": [1, 0, 0], "clamp": ["x0"],
    "control": {"space": "vertex", "lower": -1e5, "upper": 0}})";
  auto with_cells = [&](const std::string& name, const std::string& cells) {
    std::string s = scene;
    s.replace(s.find("CELLS"), 5, cells);
    return write(name, s);
  };
  // The issue's segfault: 65536 x 65536 x 2 nodes overflowed int.
  expect_bad_input("forward " + with_cells("a.json", "[65535, 65535, 1]"),
                   "above the memory limit of 8 GiB");
  expect_bad_input("forward " + with_cells("b.json", "[1000, 1000, 1000]"),
                   "1003003001 nodes and 1000000000 elements: it needs about");
  expect_bad_input("forward " + with_cells("c.json", "[1290, 1290, 1290]") + " --max-memory 1e6",
                   "more than the 2147483647 one run can index");
  expect_bad_input("forward " + with_cells("d.json", "[4, 4, 4]") + " --max-memory 1e-6",
                   "above the memory limit of");
}

TEST_F(Cli, HelpIsPrintedAndSucceeds) {
  const Outcome r = run("distance --help");
  EXPECT_EQ(r.status, 0);
  EXPECT_NE(r.out.find("usage: softhd distance"), std::string::npos);
  EXPECT_NE(run("--help").out.find("distance"), std::string::npos);
}

}  // namespace
}  // namespace softhd::test
