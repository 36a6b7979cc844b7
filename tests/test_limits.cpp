// Limits instead of crashes and silent wrong answers: mesh counts beyond int and meshes
// beyond the memory limit are refused before anything is allocated, coordinates whose
// squares would overflow are refused, and within the limit ρ̃ scales with the coordinates
// (ε scaled along) over 300 orders of magnitude. Thread counts above softhd's cap are refused,
// and an OpenMP default above it (OMP_NUM_THREADS=100000) is clamped instead of crashing
// libgomp; ε below its smallest accepted value is refused with that bound.

#include <gtest/gtest.h>
#include <omp.h>

#include <climits>
#include <cmath>

#include "expect_error.hpp"
#include "hausdorff_reference.hpp"
#include "softhd/control/scene.hpp"
#include "softhd/fe/assembly.hpp"
#include "softhd/fe/materials.hpp"
#include "softhd/fe/mesh.hpp"
#include "softhd/hausdorff.hpp"
#include "softhd/parallel.hpp"

namespace softhd::test {
namespace {

std::string scene_with_cells(const std::string& cells, int order) {
  return R"({"mesh": {"type": "box", "lower": [0, 0, 0], "upper": [1, 1, 1], "cells": )" + cells +
         R"(, "order": )" + std::to_string(order) +
         R"(}, "material": {"model": "mooney_rivlin", "a": 1e5, "b": 2e4, "c": 3e5},
         "fibers": [1, 0, 0], "clamp": ["x0"],
         "control": {"space": "vertex", "lower": -1e5, "upper": 0}})";
}

TEST(MeshSize, CountsMatchTheMeshAndDoNotOverflow) {
  const fe::Mesh m = fe::make_box_mesh(Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones(),
                                       Eigen::Vector3i(3, 2, 5), 2);
  const fe::MeshSize s = fe::box_mesh_size(Eigen::Vector3d(3, 2, 5), 2);
  EXPECT_EQ(s.nodes, m.num_nodes());
  EXPECT_EQ(s.elements, m.num_elements());
  EXPECT_EQ(s.dofs, 3 * m.num_nodes());
  EXPECT_EQ(s.quadrature_points, 27 * m.num_elements());
  // 65536² · 2 nodes: 8 589 934 592, beyond int (the issue's segfault).
  const fe::MeshSize big = fe::box_mesh_size(Eigen::Vector3d(65535, 65535, 1), 1);
  EXPECT_EQ(big.nodes, std::int64_t(65536) * 65536 * 2);
  EXPECT_EQ(big.elements, std::int64_t(65535) * 65535);
}

TEST(MeshSize, MeshesBeyondIntAreRefusedNotCrashed) {
  for (const auto& c : {std::pair{Eigen::Vector3i(65535, 65535, 1), 1},
                        {Eigen::Vector3i(1290, 1290, 1290), 1},
                        {Eigen::Vector3i(32767, 32767, 1), 2}}) {
    expect_error<ResourceError>(
        [&] {
          fe::make_box_mesh(Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones(), c.first, c.second);
        },
        "more than the 2147483647 one run can index");
  }
}

TEST(MeshSize, ScenesAboveTheMemoryLimitAreRefusedNamingSizeAndLimit) {
  // [1000, 1000, 1000] Q1: 1e9 elements, ~1e9 nodes; refused before allocating.
  expect_error<ResourceError>(
      [] { softhd::parse_scene(scene_with_cells("[1000, 1000, 1000]", 1), "s"); },
      "GiB, above the memory limit of 8 GiB");
  // [100, 100, 100] Q2 needs more than 8 GiB by the estimate; a raised limit admits it ...
  const fe::MeshSize s = fe::box_mesh_size(Eigen::Vector3d(100, 100, 100), 2);
  EXPECT_GT(s.bytes, fe::kDefaultMemoryLimit);
  expect_error<ResourceError>(
      [] { softhd::parse_scene(scene_with_cells("[100, 100, 100]", 2), "s"); }, "memory limit");
  // ... (checked on the estimate only: building it here would take minutes).
  EXPECT_NO_THROW(fe::check_mesh_size(s, 2 * s.bytes, "mesh"));
  // A small mesh passes the default limit.
  EXPECT_NO_THROW(softhd::parse_scene(scene_with_cells("[4, 2, 2]", 2), "s"));
  // The int range is a hard limit, whatever the memory limit.
  expect_error<ResourceError>(
      [] { softhd::parse_scene(scene_with_cells("[1290, 1290, 1290]", 1), "s", 1e15); },
      "more than the 2147483647");
}

TEST(SceneInput, ConstraintComponentsAndHugeNumbersAreRefused) {
  const std::string base = scene_with_cells("[2, 1, 1]", 1);
  auto with = [&](const std::string& extra) {
    return base.substr(0, base.size() - 1) + ", " + extra + "}";
  };
  for (const char* c : {"[2.5]", "[1e20]", "[-1]", "[3]"})
    expect_error<FileError>(
        [&] {
          softhd::parse_scene(
              with(std::string(R"("constraints": [{"face": "z0", "components": )") + c + "}]"),
              "s.json");
        },
        "constraints[].components");
  EXPECT_NO_THROW(
      softhd::parse_scene(with(R"("constraints": [{"face": "z0", "components": [2]}])"), "s.json"));
  expect_error<FileError>([&] { softhd::parse_scene(with(R"("extra": 1e400)"), "s.json"); },
                          "scene s.json: not valid JSON");
}

// ρ̃ is built from distances and ε only (volumes enter as ratios), so scaling every
// coordinate and ε by s scales ρ̃, A and B by s. s = 10^k, k from −150 to 150.
TEST(Coordinates, RhoScalesWithTheCoordinatesOverTheWholeAcceptedRange) {
  const PointCloud X = random_cloud(40, 3, 7, -1.0, 1.0), Y = random_cloud(30, 3, 8, -1.0, 1.0);
  for (Method method : {Method::exact, Method::tree}) {
    HausdorffOptions o;
    o.method = method;
    o.params.epsilon = 0.05;
    const HausdorffResult base = hausdorff(X, Y, o);
    for (int k = -150; k <= 150; k += 10) {
      SCOPED_TRACE("k = " + std::to_string(k) + ", " + to_string(method));
      const double s = std::pow(10.0, k);
      HausdorffOptions os = o;
      os.params.epsilon = o.params.epsilon * s;
      const HausdorffResult r = hausdorff(PointCloud(X.points() * s, X.volumes()),
                                          PointCloud(Y.points() * s, Y.volumes()), os);
      ASSERT_TRUE(std::isfinite(r.rho) && std::isfinite(r.A) && std::isfinite(r.B));
      // Scaling by 10^k is not exact in binary: each coordinate carries ~1e-16 relative
      // error, and the kernel sums amplify it by at most the exponents (~1e2 here).
      EXPECT_NEAR(r.rho / s, base.rho, 1e-12 * base.rho);
      EXPECT_NEAR(r.A / s, base.A, 1e-12 * base.A);
      EXPECT_NEAR(r.B / s, base.B, 1e-12 * base.B);
    }
  }
}

TEST(Coordinates, BeyondTheLimitTheyAreRefusedNotAnsweredWrongly) {
  Eigen::MatrixXd far(1, 3), origin = Eigen::MatrixXd::Zero(1, 3);
  far << 1e155, 0, 0;
  for (Method method : {Method::exact, Method::tree, Method::nearest}) {
    HausdorffOptions o;
    o.method = method;
    expect_error<InvalidArgument>([&] { hausdorff(PointCloud(far), PointCloud(origin), o); },
                                  "moving cloud: point 1 has a coordinate of magnitude 1e+155");
    expect_error<InvalidArgument>([&] { hausdorff(PointCloud(origin), PointCloud(far), o); },
                                  "above the limit of 1e+150");
  }
  // At the limit the answer is right: the distance between ±1e150 on one axis.
  Eigen::MatrixXd a(1, 3), b(1, 3);
  a << 1e150, 0, 0;
  b << -1e150, 0, 0;
  HausdorffOptions o;
  o.method = Method::nearest;
  EXPECT_DOUBLE_EQ(hausdorff(PointCloud(a), PointCloud(b), o).rho, 2e150);
  o.method = Method::exact;
  o.params.epsilon = 1e147;
  const double rho = hausdorff(PointCloud(a), PointCloud(b), o).rho;
  EXPECT_TRUE(std::isfinite(rho));
  EXPECT_NEAR(rho, 2e150, 1e-12 * 2e150);  // one point each: d̃ = distance exactly
}

TEST(Threads, CountsAboveTheCapAreRefusedNamingThreadsAndTheCap) {
  const std::string cap = "threads must be from 0 to 1024";
  EXPECT_EQ(kMaxThreads, 1024);
  for (int n : {kMaxThreads + 1, 100000, INT_MAX, -1}) {
    SCOPED_TRACE(n);
    expect_error<InvalidArgument>(
        [&] { set_threads(n); },
        cap + " (0: OMP_NUM_THREADS, else all cores), got " + std::to_string(n));
    HausdorffOptions o;
    o.threads = n;
    expect_error<InvalidArgument>([&] { o.validate(); }, cap);
    const PointCloud X = random_cloud(20, 3, 1);
    expect_error<InvalidArgument>([&] { hausdorff(X, X, o); }, cap);
  }
  HausdorffOptions o;
  o.threads = kMaxThreads;
  EXPECT_NO_THROW(o.validate());
}

TEST(Threads, AnOpenMpDefaultAboveTheCapIsClampedNotCrashed) {
  // OMP_NUM_THREADS=100000 sets this default at start-up; omp_set_num_threads sets the same.
  const PointCloud X = random_cloud(3000, 3, 3, -1.0, 1.0), Y = random_cloud(2000, 3, 4, -1.0, 1.0);
  HausdorffRequest req;
  req.gradient_points = req.gradient_volumes = req.gradient_target = true;
  HausdorffOptions one;
  one.threads = 1;
  const HausdorffResult serial = hausdorff(X, Y, one, req);
  const fe::Assembler A(fe::make_box_mesh(Eigen::Vector3d::Zero(), Eigen::Vector3d(3.0, 0.6, 0.3),
                                          Eigen::Vector3i(12, 2, 2), 2),
                        std::make_shared<fe::MooneyRivlin>(1.0, 0.2, 3.0), Eigen::Vector3d::UnitX(),
                        {{"x0", {}}});
  const Eigen::VectorXd u = Eigen::VectorXd::Constant(A.dofs().num_dofs, 1e-3);
  const double volume = A.deformed_volume(u);
  const Eigen::MatrixXd m_qp = Eigen::MatrixXd::Constant(A.mesh().num_elements(), 27, -0.1);
  Eigen::VectorXd R0, R;
  double e0 = 0.0, e = 0.0;
  ASSERT_TRUE(A.evaluate(u, m_qp, &e0, &R0, nullptr));
  const int before = omp_get_max_threads();
  omp_set_num_threads(100000);
  EXPECT_EQ(max_threads(), kMaxThreads);
  EXPECT_EQ(resolve_threads(0), kMaxThreads);
  for (Method method : {Method::exact, Method::tree}) {
    HausdorffOptions o;  // threads = 0: the clamped default
    o.method = method;
    one.method = method;
    const HausdorffResult r = hausdorff(X, Y, o, req);
    const HausdorffResult s = method == Method::exact ? serial : hausdorff(X, Y, one, req);
    EXPECT_EQ(r.rho, s.rho) << to_string(method);
    EXPECT_TRUE(r.gradient_points == s.gradient_points) << to_string(method);
  }
  HausdorffOptions nn;
  nn.method = Method::nearest;
  EXPECT_GT(hausdorff(X, Y, nn).rho, 0.0);
  // The element loops too (the same bits: each element's terms are its own).
  EXPECT_EQ(A.deformed_volume(u), volume);
  ASSERT_TRUE(A.evaluate(u, m_qp, &e, &R, nullptr));
  EXPECT_EQ(e, e0);
  EXPECT_TRUE(R == R0);
  omp_set_num_threads(before);
}

TEST(Epsilon, BelowTheSmallestAcceptedValueItIsRefusedWithTheBound) {
  EXPECT_EQ(kMinEpsilon, 1e-300);
  const PointCloud X = random_cloud(50, 3, 5, -1.0, 1.0);
  for (double eps : {1e-320, 1e-310, 1e-305, 0.5e-300}) {
    SCOPED_TRACE(eps);
    HausdorffOptions o;
    o.params.epsilon = eps;
    expect_error<InvalidArgument>([&] { o.params.validate(); },
                                  "epsilon must be at least 1e-300, got");
    expect_error<InvalidArgument>([&] { o.validate(); }, "epsilon must be at least 1e-300");
    expect_error<InvalidArgument>([&] { HausdorffTarget(X, o); },
                                  "epsilon must be at least 1e-300");
  }
  // At the bound every gradient is finite, also for coincident clouds (the kernel at 1/ε).
  HausdorffRequest req;
  req.gradient_points = req.gradient_volumes = req.gradient_target = true;
  for (Method method : {Method::exact, Method::tree}) {
    for (double alpha : {1.0, 4.0, 1e4}) {
      SCOPED_TRACE(to_string(method) + " alpha " + std::to_string(alpha));
      HausdorffOptions o;
      o.method = method;
      o.params.alpha = alpha;
      o.params.epsilon = kMinEpsilon;
      for (const PointCloud* Y : {&X}) {
        const HausdorffResult r = hausdorff(X, *Y, o, req);
        EXPECT_TRUE(std::isfinite(r.rho));
        EXPECT_TRUE(r.gradient_points.allFinite());
        EXPECT_TRUE(r.gradient_volumes.allFinite());
        EXPECT_TRUE(r.gradient_target.allFinite());
      }
    }
  }
}

}  // namespace
}  // namespace softhd::test
