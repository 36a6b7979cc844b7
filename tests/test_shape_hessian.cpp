// The reduced Hessian-vector product of J(m) (ShapeObjective::hessian_product,
// docs/formulation.md §4.4.1) on three small bodies — a bending plate, a torsion beam
// (transversely isotropic, fibres across the beam's axis) and a finger-like body (a stiff
// bottom layer, boundary particles) — with the Tikhonov terms on: the gradient's Taylor
// remainder ‖∇J(m + h v) − ∇J(m) − h H v‖ falls as h² (full part), H is symmetric to round-off,
// the Gauss–Newton part is positive semi-definite, a product after a rejected trial point
// re-establishes the Hessian point's state (0 Newton iterations) and gives the same product,
// and consecutive products make no state solve or factorisation of their own.

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "expect_error.hpp"
#include "hausdorff_reference.hpp"
#include "softhd/control/shape_objective.hpp"
#include "softhd/error.hpp"
#include "softhd/fe/materials.hpp"
#include "softhd/fe/mesh.hpp"

namespace softhd::test {
namespace {

enum class Body { bending, torsion, finger };

struct Case {
  Body body;
  Particles particles;
  fe::ControlKind control;
};

void PrintTo(const Case& c, std::ostream* os) {
  *os << (c.body == Body::bending   ? "bending"
          : c.body == Body::torsion ? "torsion"
                                    : "finger")
      << ' ' << to_string(c.particles) << ' '
      << (c.control == fe::ControlKind::kVertex ? "vertex" : "element");
}

Eigen::Vector3d corner(double x, double y, double z) { return {x, y, z}; }

// A clamped 3D beam (x0) of P2 hexahedra, fibres along X1. torsion: transversely isotropic
// with f = (1, 1, 0)/√2 (the torsion scene's material); finger: a 10× stiffer bottom layer
// (the finger scene's strain-limiting layer); bending: Mooney–Rivlin.
fe::Assembler body(Body b) {
  const Eigen::VectorXd lo = Eigen::Vector3d::Zero();
  const Eigen::VectorXd hi =
      b == Body::bending ? corner(3.0, 0.6, 0.2) : corner(3.0, 0.4, b == Body::finger ? 0.4 : 0.2);
  Eigen::VectorXi cells(3);
  cells << 4, 1, b == Body::finger ? 2 : 1;
  fe::Mesh mesh = fe::make_box_mesh(lo, hi, cells, 2);
  const auto soft = std::make_shared<fe::MooneyRivlin>(1.0, 0.2, 3.0);
  if (b == Body::torsion)
    return fe::Assembler(std::move(mesh),
                         std::make_shared<fe::TransverselyIsotropic>(
                             1.0, 0.2, 3.0, 10.0, Eigen::Vector3d(1.0, 1.0, 0.0).normalized()),
                         Eigen::Vector3d::UnitX(), {{"x0", {}}});
  if (b == Body::bending)
    return fe::Assembler(std::move(mesh), soft, Eigen::Vector3d::UnitX(), {{"x0", {}}});
  mesh.region_names = {"body", "layer"};  // the elements below mid-height are the layer
  mesh.element_region.setZero(mesh.num_elements());
  for (Eigen::Index e = 0; e < mesh.num_elements(); ++e) {
    double z = 0.0;
    for (Eigen::Index a = 0; a < mesh.elements.cols(); ++a) z += mesh.nodes(mesh.elements(e, a), 2);
    if (z / static_cast<double>(mesh.elements.cols()) < 0.2) mesh.element_region[e] = 1;
  }
  return fe::Assembler(std::move(mesh), {soft, std::make_shared<fe::MooneyRivlin>(10.0, 2.0, 30.0)},
                       fe::FiberField{}, {{"x0", {}}});
}

// The objective with a target near the bent body (a random cloud over a bent box), the exact
// pair sums (the product is the exact distance's), tight state solves and the Tikhonov terms.
struct Problem {
  explicit Problem(const Case& c, bool second_order = true)
      : A(body(c.body)), space(A.mesh(), A.geometry(), c.control) {
    PointCloud Y = random_cloud(80, 3, 21, 0.0, 1.0);
    Eigen::MatrixXd py = Y.points();
    py.col(0) *= 2.8;
    py.col(1) *= 0.5;
    py.col(2) = 0.3 * py.col(2) + 0.1 * py.col(0).array().square().matrix();
    ShapeObjectiveOptions o;
    o.particles = c.particles;
    o.tikhonov_mass = 0.05;
    o.tikhonov_gradient = 0.02;
    o.newton.relative_tolerance = 1e-13;
    o.newton.absolute_tolerance = 1e-14;
    o.hausdorff.params.epsilon = 1e-2;
    o.hausdorff.method = Method::exact;
    o.second_order = second_order;
    J = std::make_unique<ShapeObjective>(
        A, space, HausdorffTarget(PointCloud(py, Y.volumes()), o.hausdorff), o);
    // A control that bends the body: m = −0.15 (1 + X3 / 0.2), and random directions.
    const Eigen::MatrixXd P = space.positions(A.mesh());
    m0 = -0.15 * (1.0 + P.col(2).array() / 0.2).matrix();
  }
  Eigen::VectorXd direction(unsigned seed) const {
    Eigen::VectorXd v = random_cloud(static_cast<int>(m0.size()), 2, seed).points().col(0);
    return 0.2 * (v.array() - 0.5).matrix();
  }
  fe::Assembler A;
  fe::ControlSpace space;
  std::unique_ptr<ShapeObjective> J;
  Eigen::VectorXd m0;
};

class ShapeHessian : public ::testing::TestWithParam<Case> {};

TEST_P(ShapeHessian, GradientTaylorRemainderIsSecondOrder) {
  Problem p(GetParam());
  const ShapeEvaluation e0 = p.J->evaluate(p.m0, true);
  ASSERT_EQ(e0.status, EvaluationStatus::ok) << e0.failure;
  const Eigen::VectorXd v = p.direction(5);
  const Eigen::VectorXd Hv = p.J->hessian_product(p.m0, v);
  ASSERT_TRUE(Hv.allFinite());
  ASSERT_GT(Hv.norm(), 0.0);
  std::vector<double> r;
  for (double h = 0.1; h > 0.1 / 20; h /= 2) {
    const ShapeEvaluation e = p.J->evaluate(p.m0 + h * v, true);
    ASSERT_EQ(e.status, EvaluationStatus::ok) << e.failure;
    r.push_back((e.gradient - e0.gradient - h * Hv).norm());
  }
  for (size_t k = 0; k + 1 < r.size(); ++k)
    EXPECT_GE(std::log2(r[k] / r[k + 1]), 1.9)
        << "steps " << k << "," << k + 1 << " remainders " << r[k] << " " << r[k + 1];
  // Without the product the remainder is first order: the test can fail.
  const ShapeEvaluation e = p.J->evaluate(p.m0 + 0.1 * v, true);
  EXPECT_GT((e.gradient - e0.gradient).norm(), 10.0 * r[0]);
}

TEST_P(ShapeHessian, SymmetricAndGaussNewtonPositiveSemiDefinite) {
  Problem p(GetParam());
  ASSERT_EQ(p.J->evaluate(p.m0, true).status, EvaluationStatus::ok);
  const Eigen::VectorXd a = p.direction(7), b = p.direction(8);
  for (HessianPart part : {HessianPart::full, HessianPart::gauss_newton}) {
    const Eigen::VectorXd Ha = p.J->hessian_product(p.m0, a, part);
    const Eigen::VectorXd Hb = p.J->hessian_product(p.m0, b, part);
    // ⟨b, H a⟩ = ⟨a, H b⟩ to round-off
    EXPECT_NEAR(b.dot(Ha), a.dot(Hb), 1e-9 * a.norm() * Hb.norm());
  }
  for (unsigned seed = 11; seed < 16; ++seed) {
    const Eigen::VectorXd v = p.direction(seed);
    const Eigen::VectorXd Hv = p.J->hessian_product(p.m0, v, HessianPart::gauss_newton);
    EXPECT_GE(v.dot(Hv), -1e-12 * v.norm() * Hv.norm()) << "seed " << seed;
  }
}

TEST_P(ShapeHessian, RejectedTrialReestablishesTheHessianPoint) {
  Problem p(GetParam());
  ASSERT_EQ(p.J->evaluate(p.m0, true).status, EvaluationStatus::ok);
  const Eigen::VectorXd v = p.direction(9);
  HessianProductStats st;
  const Eigen::VectorXd Hv = p.J->hessian_product(p.m0, v, HessianPart::full, &st);
  EXPECT_FALSE(st.reestablished);
  // The next products at the same point: no solve, no factorisation.
  const Eigen::VectorXd Hv_again = p.J->hessian_product(p.m0, v, HessianPart::full, &st);
  EXPECT_FALSE(st.reestablished);
  EXPECT_EQ(st.newton_iterations, 0);
  EXPECT_EQ(st.factorizations, 0);
  EXPECT_LE((Hv_again - Hv).norm(), 1e-12 * Hv.norm());  // round-off
  // A trial point (rejected by the optimiser) moves the state; the product at m0 goes back.
  ASSERT_EQ(p.J->evaluate(p.m0 + 0.5 * v, true).status, EvaluationStatus::ok);
  const Eigen::VectorXd Hv_trial = p.J->hessian_product(p.m0 + 0.5 * v, v);
  EXPECT_GT((Hv_trial - Hv).norm(), 1e-6 * Hv.norm());  // another point, another product
  const Eigen::VectorXd Hv_back = p.J->hessian_product(p.m0, v, HessianPart::full, &st);
  EXPECT_TRUE(st.reestablished);
  EXPECT_EQ(st.newton_iterations, 0);
  // The same state again; its adjoint from a new factorisation: equal to round-off (the
  // trial's product differs by more than 1e-6).
  EXPECT_LE((Hv_back - Hv).norm(), 1e-9 * Hv.norm());
  // A renewed solver (a checkpoint's reset) is noticed too.
  p.J->state_path().reset();
  const Eigen::VectorXd Hv_reset = p.J->hessian_product(p.m0, v, HessianPart::full, &st);
  EXPECT_TRUE(st.reestablished);
  EXPECT_LE((Hv_reset - Hv).norm(), 1e-9 * Hv.norm());
}

INSTANTIATE_TEST_SUITE_P(
    Bodies, ShapeHessian,
    ::testing::Values(Case{Body::bending, Particles::nodes, fe::ControlKind::kVertex},
                      Case{Body::torsion, Particles::quadrature, fe::ControlKind::kElement},
                      Case{Body::finger, Particles::boundary, fe::ControlKind::kVertex}));

TEST(ShapeHessianSettings, RefusesWhatItDoesNotSupport) {
  const Case c{Body::bending, Particles::nodes, fe::ControlKind::kVertex};
  Problem plain(c, /*second_order=*/false);
  ASSERT_EQ(plain.J->evaluate(plain.m0, true).status, EvaluationStatus::ok);
  expect_error<InvalidArgument>([&] { plain.J->hessian_product(plain.m0, plain.direction(1)); },
                                "second_order");
  Problem p(c);
  expect_error<InvalidArgument>([&] { p.J->hessian_product(p.m0, Eigen::VectorXd::Zero(3)); },
                                "m and v must be");
  ShapeObjectiveOptions o = p.J->options();
  o.volumes = ParticleVolumes::deformed;
  expect_error<InvalidArgument>([&] { o.validate(); }, "volumes");
  o.volumes = ParticleVolumes::reference;
  o.pose = scan::Pose();
  expect_error<InvalidArgument>([&] { o.validate(); }, "pose");
}

}  // namespace
}  // namespace softhd::test
