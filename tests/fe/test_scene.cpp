#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "softhd/control/scene.hpp"
#include "softhd/error.hpp"
#include "softhd/fe/forward.hpp"

using namespace softhd::fe;
using softhd::load_scene;
using softhd::parse_scene;
using softhd::Scene;

namespace {

std::string read(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

const std::string kBending = std::string(SOFTHD_SOURCE_DIR) + "/data/scenes/bending.json";
const std::string kTorsion = std::string(SOFTHD_SOURCE_DIR) + "/data/scenes/torsion.json";

// Expects FileError whose message contains every needle.
void expect_error(const std::string& text, const std::vector<std::string>& needles) {
  try {
    parse_scene(text, "test.json");
    ADD_FAILURE() << "no error for " << text;
  } catch (const softhd::FileError& e) {
    for (const auto& n : needles)
      EXPECT_NE(std::string(e.what()).find(n), std::string::npos) << e.what() << " lacks " << n;
  }
}

std::string replace(std::string s, const std::string& from, const std::string& to) {
  const size_t p = s.find(from);
  EXPECT_NE(p, std::string::npos) << from;
  return s.replace(p, from.size(), to);
}

}  // namespace

TEST(Scene, ReferenceScenesMatchSpec) {
  const Scene b = load_scene(kBending);
  EXPECT_EQ(b.name, "bending");
  EXPECT_EQ(b.body.dim(), 3);
  EXPECT_EQ(b.body.order, 2);
  EXPECT_EQ(b.body.make_mesh().num_nodes(), 5555);
  ASSERT_EQ(b.body.materials.size(), 1u);  // a box: the one region "body"
  EXPECT_NE(dynamic_cast<const MooneyRivlin*>(b.body.materials[0].get()), nullptr);
  EXPECT_DOUBLE_EQ(b.body.materials[0]->a(), 1e5);
  EXPECT_DOUBLE_EQ(b.body.control_lower, -1e5);
  EXPECT_DOUBLE_EQ(b.body.control_upper, 0.0);
  EXPECT_EQ(b.body.constraints.size(), 1u);
  EXPECT_EQ(b.body.constraints[0].face, "x0");
  EXPECT_FALSE(b.target_json.empty());
  const Scene t = load_scene(kTorsion);
  ASSERT_EQ(t.body.materials.size(), 1u);
  EXPECT_NE(dynamic_cast<const TransverselyIsotropic*>(t.body.materials[0].get()), nullptr);
  EXPECT_DOUBLE_EQ(t.body.control_lower, -1.5e6);
  EXPECT_DOUBLE_EQ(t.body.upper[0], 50.0);
  EXPECT_EQ(t.body.fiber_field.kind, FiberField::Kind::kUniform);
  EXPECT_TRUE(t.body.fiber_field.values.isApprox(Eigen::Matrix3Xd(Eigen::Vector3d::UnitX())));
}

// mesh.quadrature_degree: a rule that leaves spurious zero-energy modes (2 by 2 by 2 Gauss
// points on Q2, one point on Q1) is refused naming the key, the cell type and the smallest
// degree without them; that degree is accepted.
TEST(Scene, AQuadratureWithSpuriousModesIsRefused) {
  const std::string good = read(kBending);  // a Q2 box
  expect_error(replace(good, "\"order\": 2", "\"order\": 2, \"quadrature_degree\": 3"),
               {"mesh.quadrature_degree", "hex27", "spurious zero-energy modes", "use degree 4"});
  expect_error(replace(good, "\"order\": 2", "\"order\": 1, \"quadrature_degree\": 1"),
               {"mesh.quadrature_degree", "hex8", "use degree 2"});
  const Scene q6 = parse_scene(
      replace(good, "\"order\": 2", "\"order\": 2, \"quadrature_degree\": 6"), "q.json");
  EXPECT_EQ(q6.body.quadrature_degree, 6);
  // It reaches the assembler: more points per hex27 than the default rule's.
  EXPECT_GT(q6.body.make_assembler().geometry().points_per_element(),
            parse_scene(good, "g.json").body.make_assembler().geometry().points_per_element());
}

TEST(Scene, InvalidFilesNameTheKey) {
  const std::string good = read(kBending);
  expect_error("{", {"not valid JSON"});
  expect_error(replace(good, "\"order\": 2", "\"order\": 3"), {"mesh.order", "1 or 2"});
  expect_error(replace(good, "\"cells\": [50, 5, 2]", "\"cells\": [50, 5]"), {"mesh.cells", "3"});
  expect_error(replace(good, "\"a\": 1e5", "\"a\": \"big\""), {"material.a", "number"});
  expect_error(replace(good, "\"b\": 2e4, ", ""), {"material.b", "missing"});
  expect_error(replace(good, "mooney_rivlin", "neo_hooke"), {"material.model"});
  expect_error(replace(good, "\"clamp\": [\"x0\"]", "\"clamp\": [\"q0\"]"), {"clamp", "q0"});
  expect_error(replace(good, "\"upper\": 0", "\"upper\": 3e5"), {"control.upper", "2a"});
  expect_error(replace(good, "\"space\": \"vertex\"", "\"space\": \"nodal\""), {"control.space"});
  EXPECT_THROW(load_scene("/nonexistent/scene.json"), softhd::FileError);
}

// Issue 29 item 3: the state problem is invariant under lengths × L and stresses × S (u
// scales by L). At both ends of the ranges a scene accepts (sizes 1e-6..1e6, stiffnesses
// 1e-6..1e12) the solve must be the unit problem's, scaled; beyond them the scene is refused
// with one line naming the key (a box scaled by 1e80 used to "converge" at u = 0).
namespace {

std::string scaled_strip(double L, double S) {
  std::ostringstream s;
  s.precision(17);
  s << R"({"name": "strip", "mesh": {"type": "box", "lower": [0, 0, 0], "upper": [)" << L << ", "
    << 0.2 * L << ", " << 0.1 * L << R"(], "cells": [4, 1, 1], "order": 1},
      "material": {"model": "mooney_rivlin", "a": )"
    << S << ", \"b\": " << 0.2 * S << ", \"c\": " << 3 * S << R"(},
      "fibers": [1, 0, 0], "clamp": ["x0"],
      "control": {"space": "vertex", "lower": )"
    << -S << R"(, "upper": 0, "initial": 0}})";
  return s.str();
}

Eigen::VectorXd strip_displacement(double L, double S) {
  const Scene scene = parse_scene(scaled_strip(L, S), "strip.json");
  const Assembler a = scene.body.make_assembler();
  const ControlSpace c(a.mesh(), a.geometry(), scene.body.control_kind);
  const ForwardResult r =
      solve_forward(scene.body, a, c, Eigen::VectorXd::Constant(c.size(), -0.5 * S));
  EXPECT_TRUE(r.summary.converged()) << "L = " << L << ", S = " << S;
  EXPECT_GT(r.summary.newton_iterations, 0) << "L = " << L << ", S = " << S;
  return r.state.u / L;
}

}  // namespace

TEST(Scene, ScaleRangeEndsSolveTheScaledUnitProblem) {
  const Eigen::VectorXd unit = strip_displacement(1.0, 1.0);
  ASSERT_GT(unit.lpNorm<Eigen::Infinity>(), 1e-3);  // a visible bend
  for (double L : {1e-6, 1e6})
    for (double S : {1e-6 / 4.2, 1e12 / 4.2}) {  // the stiffness a + b + c = 4.2 S at the ends
      const Eigen::VectorXd u = strip_displacement(L, S);
      EXPECT_LT((u - unit).lpNorm<Eigen::Infinity>(), 1e-8 * unit.lpNorm<Eigen::Infinity>())
          << "L = " << L << ", S = " << S;
    }
  expect_error(scaled_strip(1e80, 1.0), {"mesh.upper", "1e-6 to 1e6"});
  expect_error(scaled_strip(1e-90, 1.0), {"mesh.upper", "1e-6 to 1e6"});
  expect_error(scaled_strip(1.0, 1e160), {"material", "1e-6 to 1e12"});
  expect_error(scaled_strip(1.0, 1e-200), {"material", "1e-6 to 1e12"});
}

// Issue 29 item 6: a typo in a key is refused, naming it, the keys allowed there and the
// closest one; "description" and "comment" stay free keys.
TEST(Scene, UnknownKeysAreRefusedWithTheClosestName) {
  const std::string b = read(kBending);
  expect_error(replace(b, "\"initial\"", "\"inital\""),
               {"in 'control'", "unknown key 'inital'", "did you mean 'initial'"});
  expect_error(replace(b, "\"order\"", "\"oder\""), {"in 'mesh'", "did you mean 'order'"});
  expect_error(replace(b, "\"upper\": 0", "\"uper\": 0"), {"'uper'", "did you mean 'upper'"});
  expect_error(replace(b, "\"clamp\": [\"x0\"],", "\"clamp\": [\"x0\"], \"clmap\": [],"),
               {"unknown key 'clmap'", "did you mean 'clamp'"});
  expect_error(replace(b, "\"clamp\": [\"x0\"],", "\"clamp\": [\"x0\"], \"constraint\": [],"),
               {"unknown key 'constraint'", "did you mean 'constraints'"});
  expect_error(replace(b, "\"a\": 1e5,", "\"a\": 1e5, \"d\": 1,"), {"in 'material'", "'d'"});
  expect_error(replace(b, "\"clamp\": [\"x0\"],",
                       "\"clamp\": [\"x0\"], \"constraints\": [{\"face\": \"z0\", "
                       "\"component\": [2]}],"),
               {"constraints[]", "did you mean 'components'"});
  EXPECT_NO_THROW(parse_scene(replace(b, "\"fibers\"", "\"comment\": \"x\", \"fibers\""), "c"));
}

// Issue 29 items 1 and 10: the name names the output folder, so it must be a plain file
// name; control.initial outside the bounds names its key.
TEST(Scene, NameMustBeAPlainFileNameAndInitialWithinBounds) {
  const std::string b = read(kBending);
  for (const char* bad : {"x;touch PWNED;#", "../up", "a/b", ".hidden", "", "-rf", "a b"})
    expect_error(replace(b, "\"bending\"", nlohmann::json(bad).dump()), {"'name'", "plain"});
  EXPECT_EQ(parse_scene(replace(b, "\"name\": \"bending\",", ""), "dir/my scene.json").name,
            "my_scene");
  expect_error(replace(b, "\"initial\": 0", "\"initial\": 5"), {"control.initial", "within"});
}

// A box body made in code is the body the bending scene file describes (the file's values
// typed in): the same mesh, free dofs, bounds and residual floor; a clamp naming no face and
// an inverted box are refused.
TEST(Scene, BoxBodyInCodeIsTheSceneFilesBody) {
  const Scene file = load_scene(kBending);
  const Body code =
      box_body(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(10, 2, 0.1), Eigen::Vector3i(50, 5, 2), 2,
               std::make_shared<MooneyRivlin>(1e5, 2e4, 3e5), {"x0"}, -1e5, 0.0);
  EXPECT_TRUE(code.make_mesh().nodes == file.body.make_mesh().nodes);
  EXPECT_EQ(code.make_assembler().dofs().num_free, file.body.make_assembler().dofs().num_free);
  EXPECT_EQ(code.volume, 2.0 * 0.1 * 10.0);
  EXPECT_EQ(code.residual_floor(), file.body.residual_floor());
  EXPECT_EQ(code.control_lower, file.body.control_lower);
  EXPECT_EQ(code.control_upper, file.body.control_upper);
  EXPECT_THROW(
      box_body(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 1, 1), Eigen::Vector3i(2, 2, 2), 1,
               std::make_shared<MooneyRivlin>(1, 0, 1), {"nowhere"}),
      softhd::InvalidArgument);
  EXPECT_THROW(
      box_body(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(-1, 1, 1), Eigen::Vector3i(2, 2, 2), 1,
               std::make_shared<MooneyRivlin>(1, 0, 1), {"x0"}),
      softhd::InvalidArgument);
}
