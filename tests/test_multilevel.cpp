// Multilevel tracking runs (TrackingRunOptions::Levels, lib/src/control/multilevel.cpp): the
// coarse target keeps the total volume, the prolongation reproduces what Q1 interpolation and
// piecewise constants reproduce exactly, and a run's levels, history and caller stop.

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>

#include "control/multilevel.hpp"
#include "expect_error.hpp"
#include "softhd/control/tracking_run.hpp"
#include "softhd/fe/gmsh_mesh.hpp"
#include "softhd/fe/materials.hpp"
#include "softhd/fe/mesh.hpp"
#include "softhd/fe/mesh_hierarchy.hpp"

namespace softhd::test {
namespace {

namespace fs = std::filesystem;

fe::Assembler box(const Eigen::Vector3i& cells, int order) {
  return fe::Assembler(
      fe::make_box_mesh(Eigen::Vector3d::Zero(), Eigen::Vector3d(3.0, 0.6, 0.3), cells, order),
      std::make_shared<fe::MooneyRivlin>(1.0, 0.2, 3.0), Eigen::Vector3d::UnitX(), {{"x0", {}}});
}

TEST(Multilevel, SubsamplingKeepsEveryStrideThPointAndTheTotalVolume) {
  Eigen::MatrixXd p(10, 2);
  Eigen::VectorXd v(10);
  for (int i = 0; i < 10; ++i) {
    p.row(i) << i, -i;
    v[i] = i + 1.0;  // total 55
  }
  const PointCloud c = detail::subsampled(PointCloud(p, v), 3);
  ASSERT_EQ(c.size(), 4);  // points 0, 3, 6, 9
  for (int k = 0; k < 4; ++k) {
    EXPECT_EQ(c.points()(k, 0), 3.0 * k);
    // volumes 1, 4, 7, 10 (sum 22) scaled by 55 / 22
    EXPECT_NEAR(c.volumes()[k], (3.0 * k + 1.0) * 55.0 / 22.0, 1e-12);
  }
  EXPECT_NEAR(c.volumes().sum(), 55.0, 1e-12);
}

TEST(Multilevel, ProlongationReproducesAffineVertexFieldsAndCoarseElementValues) {
  const fe::Assembler coarse = box(Eigen::Vector3i(2, 1, 1), 1);
  const fe::Assembler fine = box(Eigen::Vector3i(4, 2, 2), 2);
  {
    const fe::ControlSpace cs(coarse.mesh(), coarse.geometry(), fe::ControlKind::kVertex);
    const fe::ControlSpace fs_(fine.mesh(), fine.geometry(), fe::ControlKind::kVertex);
    // m = 1 + 2 X1 − 3 X2 + 5 X3: trilinear interpolation reproduces it.
    const auto affine = [](const Eigen::MatrixXd& X) -> Eigen::VectorXd {
      return (1.0 + 2.0 * X.col(0).array() - 3.0 * X.col(1).array() + 5.0 * X.col(2).array())
          .matrix();
    };
    const Eigen::VectorXd m = fe::prolongate_control(
        coarse.mesh(), cs, affine(cs.positions(coarse.mesh())), fine.mesh(), fs_, {});
    const Eigen::VectorXd expected = affine(fs_.positions(fine.mesh()));
    ASSERT_EQ(m.size(), expected.size());
    EXPECT_LT((m - expected).cwiseAbs().maxCoeff(), 1e-12);
  }
  {
    const fe::ControlSpace cs(coarse.mesh(), coarse.geometry(), fe::ControlKind::kElement);
    const fe::ControlSpace fs_(fine.mesh(), fine.geometry(), fe::ControlKind::kElement);
    const Eigen::VectorXd m =
        fe::prolongate_control(coarse.mesh(), cs, Eigen::Vector2d(1.0, 2.0), fine.mesh(), fs_, {});
    const Eigen::MatrixXd centres = fs_.positions(fine.mesh());
    ASSERT_EQ(m.size(), 16);
    for (Eigen::Index e = 0; e < m.size(); ++e)  // coarse element 0 holds X1 < 1.5
      EXPECT_EQ(m[e], centres(e, 0) < 1.5 ? 1.0 : 2.0) << e;
  }
}

// A mesh file's P1 level (p-sequencing, fe::coarsened) has the mesh's own vertices and
// elements: its controls pass to the curved P2 mesh unchanged, bit for bit.
TEST(Multilevel, ALinearLevelPassesItsControlsUnchanged) {
  const fe::Mesh p2 = fe::read_gmsh_mesh(std::string(SOFTHD_SOURCE_DIR) +
                                         "/tests/data/meshes/cylinder_tet10_v41.msh");
  const fe::Mesh p1 = fe::linear_mesh(p2);
  const fe::ReferenceGeometry g1(p1), g2(p2);
  for (fe::ControlKind kind : {fe::ControlKind::kVertex, fe::ControlKind::kElement}) {
    const fe::ControlSpace c1(p1, g1, kind), c2(p2, g2, kind);
    ASSERT_EQ(c1.size(), c2.size());
    Eigen::VectorXd m(c1.size());
    for (Eigen::Index k = 0; k < m.size(); ++k) m[k] = -0.1 - 0.37 * std::sin(0.3 * k);
    EXPECT_EQ(fe::prolongate_control(p1, c1, m, p2, c2, {}), m);
  }
}

class MultilevelRun : public ::testing::Test {
 protected:
  void SetUp() override {
    // One file per test: CTest runs the tests of this fixture at the same time.
    file_ = fs::path(::testing::TempDir()) /
            (std::string("softhd_multilevel_scene_") +
             ::testing::UnitTest::GetInstance()->current_test_info()->name() + ".json");
    std::ofstream(file_) << R"({
      "name": "small_bend",
      "mesh": { "type": "box", "lower": [0, 0, 0], "upper": [2, 0.4, 0.2], "cells": [6, 1, 2],
                "order": 1 },
      "material": { "model": "mooney_rivlin", "a": 1e5, "b": 2e4, "c": 3e5 },
      "fibers": [1, 0, 0],
      "clamp": ["x0"],
      "control": { "space": "vertex", "lower": -1e5, "upper": 0, "initial": 0 },
      "target": { "kind": "arc", "angle": 0.6 }
    })";
    scene_ = softhd::load_scene(file_.string());
    options_.optimiser.max_iterations = 5;
    options_.optimiser.relative_change = 0.0;
    options_.threads = 1;
  }
  fs::path file_;
  softhd::Scene scene_;
  TrackingRunOptions options_;
};

TEST_F(MultilevelRun, CoarseLevelFirstThenTheUsersMeshFromItsControl) {
  const TrackingRunSummary one = run_tracking(scene_, options_);
  EXPECT_TRUE(one.levels.empty());
  for (const TrackingIteration& it : one.history) EXPECT_EQ(it.level, 0);

  // The coarse level's iterations are bounded by max_iterations too: room for the switch
  // rule here, and the user's mesh stopped after 5 iterations as the single-level run.
  options_.levels.count = 2;
  options_.optimiser.max_iterations = 30;
  TrackingRunCallbacks stop_at_5;
  stop_at_5.on_iteration = [](const TrackingIteration& it, const Eigen::VectorXd&) {
    if (it.level == 0 && it.iteration == 5) throw StopRequest{};
  };
  const TrackingRunSummary two = run_tracking(scene_, options_, stop_at_5);
  ASSERT_EQ(two.levels.size(), 2u);
  EXPECT_EQ(two.levels[0].level, 1);
  EXPECT_EQ(two.levels[1].level, 0);
  EXPECT_EQ(two.levels[1].nodes, one.nodes);
  EXPECT_LT(two.levels[0].nodes, one.nodes);
  // The scene's arc grid for the coarse body: twice as fine as its nodes, (6, 2, 2) cells.
  EXPECT_EQ(two.levels[0].target_points, 6 * 2 * 2);
  EXPECT_EQ(two.iterations, 5);
  const int coarse = two.levels[0].iterations;
  ASSERT_GE(coarse, 1);
  ASSERT_EQ(two.history.size(), static_cast<std::size_t>(coarse + 5));
  for (int k = 0; k < coarse + 5; ++k) EXPECT_EQ(two.history[k].level, k < coarse ? 1 : 0) << k;
  // The user's mesh starts from the coarse level's control, not the scene's m = 0: near the
  // coarse level's end (a 0.6 rad arc: ρ̃ at rest is far above, about 1.8 × the floor).
  EXPECT_LT(two.rho_start, 0.7 * one.rho_start) << two.rho_start << " vs " << one.rho_start;
  EXPECT_GT(two.control.cwiseAbs().maxCoeff(), 0.0);
  ASSERT_GT(coarse, 2) << "the bound below could not fail";
  options_.optimiser.max_iterations = 2;
  EXPECT_EQ(run_tracking(scene_, options_).levels[0].iterations, 2);
}

TEST_F(MultilevelRun, ACallerStopOnACoarseLevelEndsTheRunAfterOneIterationOnTheUsersMesh) {
  options_.levels.count = 2;
  TrackingRunCallbacks cb;
  cb.on_iteration = [](const TrackingIteration& it, const Eigen::VectorXd&) {
    if (it.level == 1) throw StopRequest{};
  };
  const TrackingRunSummary s = run_tracking(scene_, options_, cb);
  ASSERT_EQ(s.levels.size(), 2u);
  EXPECT_EQ(s.levels[0].iterations, 1);
  EXPECT_EQ(s.iterations, 1);
  EXPECT_EQ(s.status, OptimizerStatus::stopped);
}

// The user's mesh, started from the coarse level's control, keeps each round inside the box of
// half-width refined_move_limit × (upper − lower) around its best point (docs/formulation.md
// §4.8): its first iterate lies in the first round's box around the start. With the coarse
// level's move limit instead, the same first step leaves that box (the bound can fail).
TEST_F(MultilevelRun, LevelsAfterTheCoarsestStepWithinTheRefinedMoveLimit) {
  options_.levels.count = 2;
  options_.levels.coarse_iterations = 3;
  options_.optimiser.max_iterations = 1;
  const double range = scene_.body.control_upper - scene_.body.control_lower;
  auto first_step = [&](double refined) {
    options_.levels.refined_move_limit = refined;
    Eigen::VectorXd start, first;
    TrackingRunCallbacks cb;
    cb.on_start = [&](const ShapeTrackingSummary& s) { start = s.control; };
    cb.on_iteration = [&](const TrackingIteration& it, const Eigen::VectorXd& m) {
      if (it.level == 0 && first.size() == 0) first = m;
    };
    run_tracking(scene_, options_, cb);
    EXPECT_EQ(start.size(), first.size());
    return (first - start).lpNorm<Eigen::Infinity>() / range;
  };
  const double small = 0.002;
  const double step = first_step(small);
  EXPECT_GT(step, 0.0);
  EXPECT_LE(step, small * (1.0 + 1e-12));
  EXPECT_GT(first_step(options_.optimiser.move_limit), small) << "the check could not fail";
}

// A level stopped under a move limit below kCertifyingMoveLimit is not converged: the user's
// mesh started from the coarse level with refined_move_limit 1e-6 (steps too short to tell a
// minimum) ends with status move_limit, its level report saying why.
TEST_F(MultilevelRun, ALevelStoppedUnderATinyMoveLimitIsNotConverged) {
  options_.levels.count = 2;
  options_.levels.coarse_iterations = 3;
  options_.optimiser.max_iterations = 30;
  options_.optimiser.relative_change = 1e-6;
  options_.levels.refined_move_limit = 1e-6;
  const TrackingRunSummary s = run_tracking(scene_, options_);
  EXPECT_EQ(s.status, OptimizerStatus::move_limit) << s.termination;
  EXPECT_FALSE(s.converged());
  ASSERT_EQ(s.levels.size(), 2u);
  EXPECT_NE(s.levels[1].termination.find("(move limit 1e-06, below 0.001: steps too short"),
            std::string::npos)
      << s.levels[1].termination;
}

// levels 0 (the default) is 1 + the coarser levels of at least 32 elements where the target
// has a known map (fe::Halving::rounded: the even axes halved, else every axis of >= 4 cells
// to (n + 1) / 2; the counts by hand), else 1; 1 against a cloud with no known map (a scan)
// or in the camera's frame; an explicit count is kept.
TEST_F(MultilevelRun, AutomaticLevelsAreEveryCoarserLevelOfAtLeast32Elements) {
  EXPECT_EQ(TrackingRunOptions{}.levels.count, 0);
  const std::pair<std::string, int> cases[] = {
      {"[6, 1, 2]", 1},    // (3, 1, 1): 3 elements
      {"[14, 4, 4]", 1},   // (7, 2, 2): 28
      {"[16, 4, 4]", 2},   // (8, 2, 2): 32
      {"[15, 4, 4]", 2},   // (15, 2, 2): 60, the odd axis kept
      {"[15, 3, 1]", 1},   // no even axis: (8, 3, 1), 24
      {"[25, 5, 1]", 2},   // (13, 3, 1): 39, not nested
      {"[50, 5, 2]", 3}};  // (25, 5, 1): 125, (13, 3, 1): 39, then (7, 2, 1): 14
  std::string text;
  std::getline(std::ifstream(file_), text, '\0');
  const std::string::size_type at = text.find("[6, 1, 2]");
  ASSERT_NE(at, std::string::npos);
  for (const auto& [cells, levels] : cases) {
    std::ofstream(file_) << std::string(text).replace(at, 9, cells);
    const softhd::Scene scene = softhd::load_scene(file_.string());
    const SceneTarget known = tracking_target(scene, scene.body.make_mesh(), TrackingRunOptions{});
    ASSERT_TRUE(known.map_displacement) << "the scene's arc has a known map";
    SceneTarget scan = known, camera = known;
    scan.map_displacement.reset();
    camera.frame = TargetFrame::camera;
    EXPECT_EQ(tracking_levels(scene, TrackingRunOptions{}, known), levels) << cells;
    EXPECT_EQ(tracking_levels(scene, TrackingRunOptions{}, scan), 1) << cells;
    EXPECT_EQ(tracking_levels(scene, TrackingRunOptions{}, camera), 1) << cells;
    TrackingRunOptions explicit_one, explicit_two;
    explicit_one.levels.count = 1;
    explicit_two.levels.count = 2;
    EXPECT_EQ(tracking_levels(scene, explicit_one, known), 1) << cells;
    EXPECT_EQ(tracking_levels(scene, explicit_two, scan), 2) << cells;
  }
}

TEST_F(MultilevelRun, MoreLevelsThanHalvingsAreRefusedNamingLevels) {
  options_.levels.count = 3;  // (6, 1, 2) -> (3, 1, 1) -> no even count: one coarser level
  expect_error<InvalidArgument>([&] { run_tracking(scene_, options_); },
                                "levels.count: 3: 2 coarser levels asked for, but the body has 1");
  options_.levels.count = -1;
  expect_error<InvalidArgument>([&] { options_.validate(); }, "levels.count must be >= 1");
  options_.levels.count = 2;
  options_.levels.refined_move_limit = 1.5;
  expect_error<InvalidArgument>([&] { options_.validate(); },
                                "levels.refined_move_limit must be in [0, 1]");
}

}  // namespace
}  // namespace softhd::test
