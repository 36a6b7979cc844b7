// The softhd command-line tool, run as a user runs it: exit codes, one-line errors that
// name the problem, JSON output equal to the library's numbers.

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "hausdorff_reference.hpp"
#include "softhd/control/pose_file.hpp"
#include "softhd/hausdorff.hpp"
#include "softhd/io/cloud_io.hpp"

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
    body_text +=
        std::to_string(x.x()) + " " + std::to_string(x.y()) + " " + std::to_string(x.z()) + "\n";
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
  expect_bad_input("align " + good + " " + good + out + " --score-cap 0", "--score-cap must be");
  expect_bad_input("align " + good + " " + good + out + " --similarity --scale-min 1.5",
                   "--scale-min must be in (0, 1]");
  expect_bad_input("align " + good + " " + good + out + " --scale-max 0.8",
                   "--scale-max must be >= 1");
  expect_bad_input("align " + good + " " + write("flat.txt", "0 0\n1 1\n") + out, "align takes 3D");
  expect_bad_input("align " + good + " " + good, "--out DIR is required");
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
  form.visible.resize(12);
  for (int i = 0; i < 12; ++i) {
    form.visible[i] = i % 3 != 1;
    lines += form.visible[i] ? "1\n" : "0  # hidden\n";
  }
  const std::string seen = write("seen.txt", lines);
  const Outcome r = run("distance " + path("x.txt") + " " + path("y.txt") +
                        " --distance visible --visible " + seen + " --cap 0.4 --cap-q 2 --json");
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
  expect_bad_input("distance " + xy + " --distance visible", "--distance visible needs --visible");
  expect_bad_input("distance " + xy + " --visible " + seen, "--visible needs --distance visible");
  expect_bad_input("distance " + xy + " --cap -1", "--cap/--cap-q: distance cap.c must be");
  expect_bad_input("distance " + xy + " --cap 1 --cap-q 0", "distance cap.q must be");
  // Below the accepted ranges (docs/formulation.md §8.3) rho was 0 or the constant cap.
  expect_bad_input("distance " + xy + " --cap 1 --cap-q 1e-300",
                   "distance cap.q must be finite and >= 0.001");
  expect_bad_input("distance " + xy + " --cap 1e-300",
                   "--cap: distance cap (cap.c) 1e-300 is below");
  expect_bad_input(
      "distance " + xy + " --distance visible --visible " + write("bad.txt", "1\n0\nyes\n"),
      "bad.txt:3: expected 0 or 1, got 'yes'");
  expect_bad_input("distance " + xy + " --distance visible --visible " + write("few.txt", "1\n0\n"),
                   "few.txt: 2 entries for the 12 points of");
  expect_bad_input("distance " + xy + " --distance visible --visible " + write("none.txt", "0\n"),
                   "none.txt: 1 entries");
  expect_bad_input("distance " + xy + " --distance visible --visible " + write("e.txt", "# no\n"),
                   "e.txt: no entries");
  std::string zeros;
  for (int i = 0; i < 12; ++i) zeros += "0\n";
  expect_bad_input("distance " + xy + " --distance visible --visible " + write("z.txt", zeros),
                   "no moving point is marked visible");
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
