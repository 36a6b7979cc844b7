// Targets with a known map (docs/formulation.md §5.2): the arc map against its geometric
// properties, and the manufactured-state map against a displacement field its shape functions
// reproduce exactly.

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <cmath>
#include <filesystem>
#include <fstream>

#include "expect_error.hpp"
#include "softhd/control/scene.hpp"
#include "softhd/control/scene_target.hpp"
#include "softhd/control/targets.hpp"
#include "softhd/io/cloud_io.hpp"
#include "softhd/samplers.hpp"

namespace softhd::test {
namespace {

Eigen::Matrix3d jacobian_by_differences(const ArcMap& T, const Eigen::Vector3d& X) {
  const double h = 1e-6;
  Eigen::Matrix3d D;
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d e = h * Eigen::Vector3d::Unit(k);
    D.col(k) = (T(X + e) - T(X - e)) / (2 * h);
  }
  return D;
}

TEST(ArcMap, IsTheIdentityOnTheClampedFaceAndCurlsTowardsPlusX3) {
  const ArcMap T;  // 10 × 2 × 0.1 plate, 180°
  for (double x2 : {0.0, 1.3, 2.0})
    for (double x3 : {0.0, 0.05, 0.1}) {
      const Eigen::Vector3d X(0.0, x2, x3);
      EXPECT_LT((T(X) - X).norm(), 1e-15);
    }
  // Half a turn: the mid-surface tip lands above the clamped end at height 2R.
  const double R = 10.0 / M_PI;
  const Eigen::Vector3d tip = T(Eigen::Vector3d(10.0, 1.0, 0.05));
  EXPECT_NEAR(tip[0], 0.0, 1e-13);
  EXPECT_NEAR(tip[1], 1.0, 1e-15);
  EXPECT_NEAR(tip[2], 0.05 + 2 * R, 1e-13);
  // A quarter of the way: above the plate, ahead of the clamp.
  const Eigen::Vector3d q = T(Eigen::Vector3d(2.5, 1.0, 0.05));
  EXPECT_GT(q[2], 0.05);
  EXPECT_GT(q[0], 0.0);
}

TEST(ArcMap, JacobianMatchesDifferencesAndTheMidSurfaceKeepsItsLength) {
  ArcMap T;
  T.angle = 2.0;
  for (const Eigen::Vector3d& X : {Eigen::Vector3d(0.3, 0.2, 0.01), Eigen::Vector3d(7.1, 1.9, 0.09),
                                   Eigen::Vector3d(9.9, 1.0, 0.05)}) {
    const Eigen::Matrix3d D = jacobian_by_differences(T, X);
    EXPECT_NEAR(D.determinant(), T.jacobian(X), 1e-8);
    if (std::abs(X[2] - 0.05) < 1e-15) {
      EXPECT_NEAR(D.col(0).norm(), 1.0, 1e-8);
    }
  }
}

TEST(ArcMap, MappedVolumesSumToTheIntegralOfTheJacobian) {
  // ∫ (1 − z/R) dX over a plate symmetric in z is its volume, 10 · 2 · 0.1 = 2.
  const ArcMap T;
  const PointCloud grid = sample_box_grid(Eigen::Vector3d::Zero(), Eigen::Vector3d(10, 2, 0.1),
                                          Eigen::Vector3i(40, 4, 3));
  const PointCloud mapped = T.apply(grid);
  EXPECT_NEAR(mapped.volumes().sum(), 2.0, 1e-13);
  EXPECT_EQ(mapped.size(), grid.size());
}

// The plate placed anywhere bends the same way: T_o(X + o) = T_0(X) + o. Before the origin
// existed, a scene with mesh.lower = (1e6, 1e6, 1e6) got an arc about the far-away X1 = 0,
// with negative volumes (refused), and mesh.lower = (1, 0, 0) a silently wrong target.
TEST(ArcMap, CommutesWithTranslations) {
  ArcMap T0, T;
  T0.angle = T.angle = 2.5;
  T.origin = Eigen::Vector3d(1e6, -3.0, 1e6);
  for (const Eigen::Vector3d& X : {Eigen::Vector3d(0.0, 0.4, 0.0), Eigen::Vector3d(7.1, 1.9, 0.09),
                                   Eigen::Vector3d(10.0, 1.0, 0.05)}) {
    const Eigen::Vector3d expected = T0(X) + T.origin;
    EXPECT_LT((T(X + T.origin) - expected).norm(), 1e-9);  // 8 ulps of 1e6
    EXPECT_NEAR(T.jacobian(X + T.origin), T0.jacobian(X), 1e-9);
  }
}

TEST(SceneTarget, ArcOfATranslatedSceneIsTheTranslatedArc) {
  softhd::Scene s = softhd::parse_scene(R"({
    "mesh": { "type": "box", "lower": [0, 0, 0], "upper": [4, 1, 0.2], "cells": [4, 1, 1], "order": 2 },
    "material": { "model": "mooney_rivlin", "a": 1e5, "b": 2e4, "c": 3e5 },
    "fibers": [1, 0, 0], "clamp": ["x0"],
    "control": { "space": "vertex", "lower": -1e5, "upper": 0, "initial": 0 },
    "target": { "kind": "arc", "angle": 1.5 } })",
                                        "plate.json");
  softhd::Scene moved = s;
  const Eigen::Vector3d o(1.0, 2.0, -0.5);
  for (int k = 0; k < 3; ++k) {
    moved.body.lower[k] += o[k];
    moved.body.upper[k] += o[k];
  }
  const SceneTarget a = scene_target(s, s.body.make_mesh()),
                    b = scene_target(moved, moved.body.make_mesh());
  ASSERT_EQ(a.cloud.size(), b.cloud.size());
  const Eigen::MatrixXd d = b.cloud.points().rowwise() - o.transpose();
  EXPECT_LT((d - a.cloud.points()).cwiseAbs().maxCoeff(), 1e-14);
  EXPECT_LT((b.cloud.volumes() - a.cloud.volumes()).cwiseAbs().maxCoeff(), 1e-16);
  ASSERT_TRUE(a.map_displacement && b.map_displacement);
  EXPECT_LT((*b.map_displacement - *a.map_displacement).cwiseAbs().maxCoeff(), 1e-14);
}

// The target as a body with cells (the cell-integrated distance): an arc's sampling grid as
// hexahedra whose nodes T maps, so each sample, T at a cell's centre, lies within the
// second-order gap |T(c) − mean of T at the corners| ≤ (h₁² + h₃²)/(2R) of its cell's centroid.
TEST(SceneTarget, AnArcHasTheCellsOfItsSamplingGrid) {
  const softhd::Scene s = softhd::parse_scene(R"({
    "mesh": { "type": "box", "lower": [0, 0, 0], "upper": [4, 1, 0.2], "cells": [4, 1, 1], "order": 1 },
    "material": { "model": "mooney_rivlin", "a": 1e5, "b": 2e4, "c": 3e5 },
    "fibers": [1, 0, 0], "clamp": ["x0"],
    "control": { "space": "vertex", "lower": -1e5, "upper": 0, "initial": 0 },
    "target": { "kind": "arc", "angle": 1.5, "cells": [8, 2, 2] } })",
                                              "plate.json");
  const SceneTarget t = scene_target(s, s.body.make_mesh());
  ASSERT_TRUE(t.cells.has_value());
  ASSERT_EQ(t.cells->num_elements(), t.cloud.size());
  const double R = 4.0 / 1.5, h1 = 0.5, h3 = 0.1, gap = (h1 * h1 + h3 * h3) / (2 * R);
  for (Eigen::Index j = 0; j < t.cloud.size(); ++j) {  // every sample near one cell's centroid
    double nearest = 1e300;
    for (Eigen::Index e = 0; e < t.cells->num_elements(); ++e) {
      Eigen::RowVector3d c = Eigen::RowVector3d::Zero();
      for (int a = 0; a < 8; ++a) c += t.cells->nodes.row(t.cells->elements(e, a)) / 8.0;
      nearest = std::min(nearest, (c - t.cloud.points().row(j)).norm());
    }
    EXPECT_LT(nearest, gap) << "sample " << j;
  }
}

// A solved_on target's cells are its source mesh at the file's nodes.
TEST(SceneTarget, ASolvedOnTargetHasItsSourceMeshAtTheFilesNodes) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::path(::testing::TempDir()) / "softhd_solved_on_cells";
  fs::create_directories(dir);
  const std::string scene = R"({
    "mesh": { "type": "box", "lower": [0, 0, 0], "upper": [2, 1, 1], "cells": [2, 1, 1], "order": 1 },
    "material": { "model": "mooney_rivlin", "a": 1e5, "b": 2e4, "c": 3e5 },
    "fibers": [1, 0, 0], "clamp": ["x0"],
    "control": { "space": "vertex", "lower": -1e5, "upper": 0, "initial": 0 },
    "target": { "kind": "cloud", "file": "target.ply", "solved_on": "fine.json" } })";
  std::string fine = scene;
  fine.replace(fine.find("[2, 1, 1], \"order"), 9, "[4, 2, 2]");
  std::ofstream(dir / "scene.json") << scene;
  std::ofstream(dir / "fine.json") << fine;
  const fe::Mesh source = load_scene((dir / "fine.json").string()).body.make_mesh();
  const Eigen::MatrixXd moved =
      source.nodes * 1.1 + Eigen::MatrixXd::Constant(source.num_nodes(), 3, 0.3);
  write_cloud((dir / "target.ply").string(), PointCloud(moved));
  const softhd::Scene s = load_scene((dir / "scene.json").string());
  const SceneTarget t = scene_target(s, s.body.make_mesh());
  ASSERT_TRUE(t.cells.has_value());
  EXPECT_EQ(t.cells->elements, source.elements);
  EXPECT_LT((t.cells->nodes - moved).cwiseAbs().maxCoeff(), 1e-6);  // the PLY's float32
  fs::remove_all(dir);
}

// "surface" and "camera" in a target block (docs/guide.md): read into the SceneTarget and
// applied to the objective (boundary particles with current areas; the visible distance from
// the camera); malformed values and a 2D body refused naming the key.
TEST(SceneTarget, SurfaceAndCameraKeys) {
  const std::string head = R"({
    "mesh": { "type": "box", "lower": [0, 0, 0], "upper": [4, 1, 0.2], "cells": [4, 1, 1], "order": 1 },
    "material": { "model": "mooney_rivlin", "a": 1e5, "b": 2e4, "c": 3e5 },
    "fibers": [1, 0, 0], "clamp": ["x0"],
    "control": { "space": "vertex", "lower": -1e5, "upper": 0, "initial": 0 },
    "target": { "kind": "arc", "angle": 1.5)";
  auto target = [&](const std::string& keys) {
    const softhd::Scene s = softhd::parse_scene(head + keys + "} }", "view.json");
    return scene_target(s, s.body.make_mesh());
  };
  const SceneTarget t = target(R"(, "surface": true, "camera": [1, 2, 3])");
  EXPECT_TRUE(t.surface);
  ASSERT_TRUE(t.camera.has_value());
  EXPECT_EQ(*t.camera, Eigen::Vector3d(1, 2, 3));
  ShapeObjectiveOptions o;
  apply_target_settings(t, &o);
  EXPECT_EQ(o.particles, Particles::boundary);
  EXPECT_EQ(o.volumes, ParticleVolumes::deformed);
  EXPECT_EQ(o.form.sides, Sides::visible);
  EXPECT_EQ(*o.camera, Eigen::Vector3d(1, 2, 3));
  EXPECT_NO_THROW(o.validate());
  const SceneTarget plain = target("");
  EXPECT_FALSE(plain.surface || plain.camera.has_value());
  expect_error<InvalidArgument>([&] { target(R"(, "camera": [1, 2])"); }, "target.camera");
  expect_error<InvalidArgument>([&] { target(R"(, "camera": [1, "a", 2])"); }, "target.camera");
  expect_error<InvalidArgument>([&] { target(R"(, "surface": 1)"); }, "target.surface");
  expect_error<FileError>([&] { target(R"(, "camra": [1, 2, 3])"); }, "did you mean 'camera'");
  // The objective's own checks: a camera without the visible distance, visible without one.
  ShapeObjectiveOptions bad;
  bad.camera = Eigen::Vector3d(0, 0, 1);
  expect_error<InvalidArgument>([&] { bad.validate(); }, "camera");
  bad = ShapeObjectiveOptions();
  bad.form.sides = Sides::visible;
  expect_error<InvalidArgument>([&] { bad.validate(); }, "camera");
  bad.camera = Eigen::Vector3d(0, 0, 1);
  bad.particles = Particles::quadrature;
  expect_error<InvalidArgument>([&] { bad.validate(); }, "particles");
}

TEST(ArcMap, RejectsBadGeometry) {
  ArcMap T;
  T.angle = 7.0;
  expect_error<InvalidArgument>([&] { T.validate(); }, "angle must be in (0, 2 pi]");
  T.angle = 1.0;
  T.thickness = 25.0;
  expect_error<InvalidArgument>([&] { T.validate(); }, "radius");
}

// A quadratic displacement, which Q2 elements interpolate exactly.
Eigen::Vector3d quadratic(const Eigen::Vector3d& X) {
  return {0.1 * X[0] * X[0] - 0.3 * X[1] * X[2], 0.2 * X[0] * X[1] + X[2], -0.05 * X[2] * X[2]};
}

PointCloud deformed_nodes(const fe::Mesh& mesh) {
  Eigen::MatrixXd y(mesh.num_nodes(), 3);
  for (Eigen::Index n = 0; n < mesh.num_nodes(); ++n) {
    const Eigen::Vector3d X = mesh.nodes.row(n).transpose();
    y.row(n) = (X + quadratic(X)).transpose();
  }
  return PointCloud(y, Eigen::VectorXd::Ones(mesh.num_nodes()));
}

TEST(NodalMap, ReproducesAFieldItsShapeFunctionsSpanAtAnyPointAndAtCoarserNodes) {
  const Eigen::Vector3d lo(0, 0, 0), hi(5, 1, 0.5);
  const fe::Mesh fine = fe::make_box_mesh(lo, hi, Eigen::Vector3i(8, 4, 2), 2);
  const NodalMap T(fine, deformed_nodes(fine));
  for (const Eigen::Vector3d& X : {Eigen::Vector3d(0.123, 0.77, 0.31),
                                   Eigen::Vector3d(4.99, 0, 0.5), Eigen::Vector3d(2.5, 0.5, 0.25)})
    EXPECT_LT((T.displacement_at(X) - quadratic(X)).norm(), 1e-13) << X.transpose();
  const fe::Mesh coarse = fe::make_box_mesh(lo, hi, Eigen::Vector3i(4, 2, 1), 2);
  const Eigen::VectorXd u = T.displacement(coarse);
  for (Eigen::Index n = 0; n < coarse.num_nodes(); ++n) {
    const Eigen::Vector3d X = coarse.nodes.row(n).transpose();
    EXPECT_LT((u.segment<3>(3 * n) - quadratic(X)).norm(), 1e-13);
  }
}

TEST(NodalMap, RejectsMismatchedCloudsAndPointsOutsideTheBody) {
  const fe::Mesh mesh = fe::make_box_mesh(Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones(),
                                          Eigen::Vector3i(2, 2, 2), 1);
  PointCloud cloud = deformed_nodes(mesh);
  const PointCloud short_cloud(cloud.points().topRows(5), cloud.volumes().head(5));
  expect_error<InvalidArgument>([&] { NodalMap(mesh, short_cloud); }, "has 5 points in 3D");
  const NodalMap T(mesh, cloud);
  expect_error<InvalidArgument>([&] { T.displacement_at(Eigen::Vector3d(2, 0, 0)); },
                                "outside the body");
  const fe::Mesh bigger = fe::make_box_mesh(Eigen::Vector3d::Zero(), Eigen::Vector3d(2, 1, 1),
                                            Eigen::Vector3i(2, 1, 1), 1);
  expect_error<InvalidArgument>([&] { T.displacement(bigger); }, "outside the body");
}

}  // namespace
}  // namespace softhd::test
