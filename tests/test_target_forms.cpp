// The distance form of a scene's target block (docs/guide.md; docs/formulation.md §8): its keys
// parsed and refused, the cap's quantile rule, the objective's use of the form, and a tracking
// run against half a target, one-sided against symmetric.

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "expect_error.hpp"
#include "softhd/control/scene.hpp"
#include "softhd/control/scene_target.hpp"
#include "softhd/control/shape_objective.hpp"
#include "softhd/control/tracking_run.hpp"

namespace softhd::test {
namespace {

namespace fs = std::filesystem;

// The bending scene of the multilevel tests, with `target_extra` appended inside its target.
softhd::Scene bend_scene(const std::string& name, const std::string& target_extra) {
  const fs::path file = fs::path(::testing::TempDir()) / ("softhd_forms_" + name + ".json");
  std::ofstream(file) << R"({
      "name": "small_bend",
      "mesh": { "type": "box", "lower": [0, 0, 0], "upper": [2, 0.4, 0.2], "cells": [6, 1, 2],
                "order": 1 },
      "material": { "model": "mooney_rivlin", "a": 1e5, "b": 2e4, "c": 3e5 },
      "fibers": [1, 0, 0],
      "clamp": ["x0"],
      "control": { "space": "vertex", "lower": -1e5, "upper": 0, "initial": 0 },
      "target": { "kind": "arc", "angle": 0.6)"
                      << target_extra << R"( }
    })";
  return softhd::load_scene(file.string());
}

SceneTarget target_of(const softhd::Scene& scene) {
  return scene_target(scene, scene.body.make_assembler().mesh());
}

TEST(TargetForms, KeysAreParsed) {
  const SceneTarget plain = target_of(bend_scene("plain", ""));
  EXPECT_EQ(plain.distance.sides, Sides::symmetric);
  EXPECT_EQ(plain.distance.cap, 0.0);
  const SceneTarget one =
      target_of(bend_scene("one", R"(, "distance": "scan_to_body", "cap": 0.05, "cap_q": 2)"));
  EXPECT_EQ(one.distance.sides, Sides::scan_to_body);
  EXPECT_EQ(one.distance.cap, 0.05);
  EXPECT_EQ(one.distance.cap_q, 2.0);
  const SceneTarget rule =
      target_of(bend_scene("rule", R"(, "cap": {"quantile": 0.9, "factor": 3})"));
  EXPECT_EQ(rule.distance.cap, 0.0);
  EXPECT_EQ(rule.distance.cap_quantile, 0.9);
  EXPECT_EQ(rule.distance.cap_factor, 3.0);
}

TEST(TargetForms, BadKeysAreRefusedInOneLineNamingTheKey) {
  auto refuse = [](const std::string& extra, const std::string& needle) {
    expect_error<Error>([&] { target_of(bend_scene("bad", extra)); }, needle);
  };
  refuse(R"(, "distance": "visible")", "target.distance \"visible\" needs the camera");
  refuse(R"(, "distance": "both")", "target.distance must be");
  refuse(R"(, "distance": 3)", "target.distance must be");
  refuse(R"(, "cap": -1)", "target.cap must be a number > 0");
  refuse(R"(, "cap": "big")", "target.cap must be a number > 0");
  refuse(R"(, "cap": {"quantile": 0.9})", "target.cap needs both");
  refuse(R"(, "cap": {"quantile": 1.5, "factor": 2})", "target.cap.quantile must be in [0, 1]");
  refuse(R"(, "cap": {"quantile": 0.5, "factor": 0})", "target.cap.factor must be a number > 0");
  refuse(R"(, "cap": {"quantile": 0.5, "factor": 2, "q": 3})", "unknown key 'q'");
  refuse(R"(, "cap_q": 0)", "target.cap_q must be a number > 0");
  // Below 0.001 the scaled soft cap underflows (docs/formulation.md §8.3): rho was 0.
  refuse(R"(, "cap_q": 1e-300)", "target.cap_q must be >= 0.001");
}

// The quantile rule gives c = F × the Q-quantile of d̃_X(y_j) of the body at rest, and the
// objective then evaluates with it: its ρ̃ is the library's for that form.
TEST(TargetForms, QuantileCapIsSetFromTheRestStateAndUsed) {
  const softhd::Scene scene = bend_scene(
      "quantile", R"(, "distance": "scan_to_body", "cap": {"quantile": 0.5, "factor": 2})");
  const fe::Assembler assembler = scene.body.make_assembler();
  const fe::ControlSpace control = scene.body.make_control_space(assembler);
  const SceneTarget t = scene_target(scene, assembler.mesh());
  ShapeObjective objective(assembler, control, HausdorffTarget(t.cloud));
  const Eigen::VectorXd rest = Eigen::VectorXd::Zero(objective.state_path().last_state().u.size());
  const Eigen::VectorXd field = objective.fields(rest).field_target;
  const DistanceForm form = target_form(t.distance, objective);
  EXPECT_EQ(form.sides, Sides::scan_to_body);
  EXPECT_EQ(form.cap.c, cap_from_quantile(field, 0.5, 2.0));
  objective.set_form(form);
  const ShapeEvaluation ev = objective.evaluate(control.constant(0.0), false);
  HausdorffRequest req;
  req.form = form;
  EXPECT_EQ(ev.rho, objective.target().evaluate(objective.moving_cloud().at(rest), req).rho);
  EXPECT_EQ(ev.B, 0.0);
}

// TrackingRunOptions::distance replaces the target block's form as a whole: the run's target
// description says so, its B is 0 (scan_to_body), and visible is refused naming the field.
TEST(TargetForms, RunOptionsReplaceTheTargetsForm) {
  const softhd::Scene scene = bend_scene("override", R"(, "cap": 0.2)");
  TrackingRunOptions options;
  options.optimiser.max_iterations = 1;
  options.threads = 1;
  options.state.coarse_levels = CoarseLevel::off;
  options.distance.form = TargetDistance{};
  options.distance.form->sides = Sides::scan_to_body;
  const TrackingRunSummary s = run_tracking(scene, options);
  EXPECT_NE(s.target.find("distance scan_to_body"), std::string::npos) << s.target;
  EXPECT_EQ(s.target.find("cap"), std::string::npos) << s.target;  // the block's cap replaced
  ASSERT_FALSE(s.history.empty());
  EXPECT_EQ(s.history.back().B, 0.0);
  EXPECT_EQ(s.history.back().rho, s.history.back().A);
  options.distance.form->sides = Sides::visible;
  expect_error<InvalidArgument>([&] { options.validate(); },
                                "distance.form.sides visible needs the camera");
  options.distance.form->sides = Sides::symmetric;
  options.distance.form->cap = -1.0;
  expect_error<InvalidArgument>([&] { options.validate(); }, "distance.form.cap must be");
}

// The arc target cut at the middle of its z range: the points above it (`upper`) or below.
SceneTarget half_target(const SceneTarget& full, bool upper, Sides sides) {
  const Eigen::VectorXd z = full.cloud.points().col(2);
  const double mid = 0.5 * (z.minCoeff() + z.maxCoeff());
  std::vector<Eigen::Index> keep;
  for (Eigen::Index j = 0; j < z.size(); ++j)
    if ((z[j] > mid) == upper) keep.push_back(j);
  Eigen::MatrixXd p(keep.size(), 3);
  Eigen::VectorXd v(keep.size());
  for (size_t k = 0; k < keep.size(); ++k) {
    p.row(k) = full.cloud.points().row(keep[k]);
    v[k] = full.cloud.volumes()[keep[k]];
  }
  SceneTarget half{
      PointCloud(p, v), full.map_displacement, upper ? "upper half" : "lower half", {}};
  half.distance.sides = sides;
  return half;
}

// Tracking runs against half of the arc target (z above or below the middle), one-sided and
// symmetric, and against the whole target; node errors (max over the nodes, against the
// known arc map) after 40 iterations, measured Dec 2 with β = 4 for every form and Dec 7 with
// the run's default, β = 2 for scan_to_body (printed by the test; SOFTHD_MEASURE for all):
//     whole target, symmetric          0.0693
//     upper half, scan_to_body         0.0691 (β = 2: 0.0651)     symmetric 0.0679
//     lower half, scan_to_body         0.245  (β = 2: 0.2265)     symmetric 0.354
// The upper half holds the bent tip, and this control (contraction only, clamped at x = 0)
// cannot pull the body into the half it sees: the symmetric form does as well there, so no
// inequality between the forms is asserted on it. On the lower half (near the clamp) the
// one-sided form is better by 0.69x (β = 2: 0.64x), not by a clear margin either. Asserted: a
// one-sided run against the upper half recovers the shape as well as the whole target does (within
// 10 %).
TEST(TargetForms, OneSidedRunAgainstAHalfTargetRecoversTheShape) {
  const softhd::Scene scene = bend_scene("half", "");
  const fe::Assembler assembler = scene.body.make_assembler();
  const fe::ControlSpace control = scene.body.make_control_space(assembler);
  const SceneTarget full = scene_target(scene, assembler.mesh());
  TrackingRunOptions options;
  options.optimiser.max_iterations = 40;
  options.threads = 1;
  options.state.coarse_levels = CoarseLevel::off;
  auto node_error = [&](const SceneTarget& target) {
    TrackingRun run(scene, assembler, control, target, options);
    const TrackingRunSummary s = run.run();
    EXPECT_TRUE(s.shape_error_max.has_value());
    std::printf("%s, %s: %d iterations, rho %.4g, node error max %.4g rms %.4g\n",
                target.description.c_str(), to_string(target.distance.sides).c_str(), s.iterations,
                s.rho_final, *s.shape_error_max, *s.shape_error_rms);
    return *s.shape_error_max;
  };
  const double whole = node_error(full);
  const double one_sided = node_error(half_target(full, true, Sides::scan_to_body));
  EXPECT_LT(one_sided, 1.1 * whole);
  if (std::getenv("SOFTHD_MEASURE") != nullptr) {  // the other numbers of the table above
    node_error(half_target(full, true, Sides::symmetric));
    node_error(half_target(full, false, Sides::scan_to_body));
    node_error(half_target(full, false, Sides::symmetric));
  }
}

}  // namespace
}  // namespace softhd::test
