// The coupled objective J(m) = ρ̃(Φ_m(Ω₀), Ω_d) + regularisation: Taylor tests of its
// adjoint gradient (remainder falls as h², observed order ≥ 1.9) for every particle and
// volume mode (the boundary nodes with their facet areas in 3D), vertex and element controls,
// in 2D and 3D.

#include <gtest/gtest.h>

#include "hausdorff_reference.hpp"
#include "softhd/control/shape_objective.hpp"
#include "softhd/fe/grid_sequencing.hpp"
#include "softhd/fe/materials.hpp"
#include "softhd/fe/mesh.hpp"
#include "softhd/fe/scene.hpp"

namespace softhd::test {
namespace {

struct Case {
  int dim;
  Particles particles;
  ParticleVolumes volumes;
  fe::ControlKind control;
};

void PrintTo(const Case& c, std::ostream* os) {
  *os << c.dim << "D " << to_string(c.particles) << ' ' << to_string(c.volumes) << ' '
      << (c.control == fe::ControlKind::kVertex ? "vertex" : "element");
}

fe::Assembler strip(int dim) {
  Eigen::VectorXd lo = Eigen::VectorXd::Zero(dim), hi(dim);
  Eigen::VectorXi cells(dim);
  if (dim == 2) {
    hi << 3.0, 0.3;
    cells << 4, 1;
  } else {
    hi << 3.0, 0.6, 0.3;
    cells << 4, 1, 1;
  }
  return fe::Assembler(fe::make_box_mesh(lo, hi, cells, 2),
                       std::make_shared<fe::MooneyRivlin>(1.0, 0.2, 3.0), Eigen::Vector3d::UnitX(),
                       {{"x0", {}}});
}

class ShapeGradient : public ::testing::TestWithParam<Case> {};

TEST_P(ShapeGradient, TaylorRemainderIsSecondOrder) {
  const Case c = GetParam();
  const fe::Assembler A = strip(c.dim);
  const fe::ControlSpace space(A.mesh(), A.geometry(), c.control);
  // A target near the body, at another resolution: a random cloud over a bent box.
  PointCloud Y = random_cloud(60, c.dim, 21, 0.0, 1.0);
  Eigen::MatrixXd py = Y.points();
  py.col(0) *= 2.8;
  py.col(c.dim - 1) = 0.4 * py.col(c.dim - 1) + 0.1 * py.col(0).array().square().matrix();
  ShapeObjectiveOptions o;
  o.particles = c.particles;
  o.volumes = c.volumes;
  o.tikhonov_mass = 0.05;
  o.tikhonov_gradient = 0.02;
  o.newton.relative_tolerance = 1e-13;
  o.newton.absolute_tolerance = 1e-14;
  o.hausdorff.params.epsilon = 1e-2;
  ShapeObjective J(A, space, HausdorffTarget(PointCloud(py, Y.volumes())), o);

  // A control that bends the strip: m = −0.3 (1 + X_last / t) sampled at the controls.
  const Eigen::MatrixXd P = space.positions(A.mesh());
  const double t = c.dim == 2 ? 0.3 : 0.3;
  Eigen::VectorXd m0 = -0.15 * (1.0 + P.col(c.dim - 1).array() / t).matrix();
  Eigen::VectorXd dm = random_cloud(static_cast<int>(m0.size()), 2, 5).points().col(0);
  dm.array() -= 0.5;
  dm *= 0.2;

  const ShapeEvaluation e0 = J.evaluate(m0, true);
  ASSERT_EQ(e0.status, EvaluationStatus::ok) << e0.failure;
  ASSERT_TRUE(e0.gradient.allFinite());
  const double slope = e0.gradient.dot(dm);
  std::vector<double> remainder;
  for (double h = 0.2; h > 0.2 / 32; h /= 2) {
    const ShapeEvaluation e = J.evaluate(m0 + h * dm, false);
    ASSERT_EQ(e.status, EvaluationStatus::ok) << e.failure;
    remainder.push_back(std::fabs(e.J - e0.J - h * slope));
  }
  for (size_t k = 0; k + 1 < remainder.size(); ++k) {
    const double order = std::log2(remainder[k] / remainder[k + 1]);
    EXPECT_GE(order, 1.9) << "steps " << k << "," << k + 1 << " remainders " << remainder[k] << " "
                          << remainder[k + 1];
  }
}

std::vector<Case> cases() {
  std::vector<Case> out;
  for (int d : {2, 3})
    for (Particles p : {Particles::nodes, Particles::quadrature, Particles::boundary})
      for (ParticleVolumes v : {ParticleVolumes::reference, ParticleVolumes::deformed})
        for (fe::ControlKind k : {fe::ControlKind::kVertex, fe::ControlKind::kElement})
          if (d == 3 || p != Particles::boundary) out.push_back({d, p, v, k});  // boundary: 3D
  return out;
}

std::string case_name(const ::testing::TestParamInfo<Case>& info) {
  const Case& c = info.param;
  return std::to_string(c.dim) + "D_" + to_string(c.particles) + "_" + to_string(c.volumes) +
         (c.control == fe::ControlKind::kVertex ? "_vertex" : "_element");
}

INSTANTIATE_TEST_SUITE_P(Adjoint, ShapeGradient, ::testing::ValuesIn(cases()), case_name);

TEST(ShapeObjective, FailedStateSolveIsReportedNotThrown) {
  const fe::Assembler A = strip(2);
  const fe::ControlSpace space(A.mesh(), A.geometry(), fe::ControlKind::kElement);
  ShapeObjectiveOptions o;
  o.newton.max_load_steps = 3;  // too few to reach a strong contraction
  ShapeObjective J(A, space, HausdorffTarget(random_cloud(10, 2, 3)), o);
  // m far beyond the existence limit m < 2a (a = 1): no equilibrium to find.
  const ShapeEvaluation e = J.evaluate(Eigen::VectorXd::Constant(space.size(), 50.0), true);
  EXPECT_EQ(e.status, EvaluationStatus::state_failed);
  EXPECT_FALSE(e.failure.empty());
}

// Two-level starts change the path, never the state: large steps (from rest, then from
// the first state) land on the states (and J) of the plain warm start, the first with
// fewer fine Newton iterations.
TEST(ShapeObjective, TwoLevelStartsReachTheSameStateWithFewerFineIterations) {
  fe::Scene scene = fe::load_scene(std::string(SOFTHD_SOURCE_DIR) + "/data/scenes/bending.json");
  scene.cells << 6, 1, 2;  // coarse level 3 x 1 x 1
  const fe::Assembler A = scene.make_assembler();
  const fe::Assembler coarse = fe::coarsened(scene).make_assembler();
  const fe::ControlSpace space(A.mesh(), A.geometry(), scene.control_kind);
  const Eigen::MatrixXd P = space.positions(A.mesh());
  const Eigen::VectorXd m = -2.5e4 * (1.0 + P.col(2).array() / 0.1).matrix();  // ~half a turn
  PointCloud Y = random_cloud(50, 3, 4, 0.0, 1.0);
  ShapeObjectiveOptions o;
  o.newton.relative_tolerance = 1e-12;
  o.newton.displacement_tolerance = 1e-11;  // both paths end on the same state, soft modes too
  o.coarse_correction_iterations = 0;       // always take the coarse-corrected start
  ShapeObjective plain(A, space, HausdorffTarget(Y), o);
  ShapeObjective two_level(A, space, HausdorffTarget(Y), o);
  two_level.use_coarse_level(coarse);
  EXPECT_EQ(plain.coarse_level(), nullptr);
  EXPECT_EQ(two_level.coarse_level(), &coarse);
  const ShapeEvaluation a = plain.evaluate(m, true), b = two_level.evaluate(m, true);
  ASSERT_TRUE(a.status == EvaluationStatus::ok && b.status == EvaluationStatus::ok)
      << a.failure << b.failure;
  const Eigen::VectorXd& ua = plain.last_state().u;
  EXPECT_LT((two_level.last_state().u - ua).lpNorm<Eigen::Infinity>(),
            1e-9 * ua.lpNorm<Eigen::Infinity>());
  EXPECT_NEAR(b.J, a.J, 1e-10 * a.J);
  EXPECT_LT((b.gradient - a.gradient).norm(), 1e-6 * a.gradient.norm());
  EXPECT_LT(b.newton_iterations, a.newton_iterations);
  // A second step starts from the first one's state, whose coarse equilibrium is kept.
  const ShapeEvaluation c = plain.evaluate(1.4 * m, false), d = two_level.evaluate(1.4 * m, false);
  ASSERT_TRUE(c.status == EvaluationStatus::ok && d.status == EvaluationStatus::ok)
      << c.failure << d.failure;
  const Eigen::VectorXd& uc = plain.last_state().u;
  EXPECT_LT((two_level.last_state().u - uc).lpNorm<Eigen::Infinity>(),
            1e-9 * uc.lpNorm<Eigen::Infinity>());
  EXPECT_NEAR(d.J, c.J, 1e-10 * c.J);
}

}  // namespace
}  // namespace softhd::test
