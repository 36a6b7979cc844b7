// The objective against a surface scan seen from one side (docs/formulation.md §8.6, §8.7): the
// moving cloud is the body's boundary with its current facet areas, the distance the visible
// one with the mask recomputed from the deformed boundary at every evaluation. Checked: the
// adjoint gradient by a Taylor test (the mask unchanged over the steps, checked), and a
// tracking run against the visible half of a manufactured body, whose node error is smaller
// than the symmetric distance's against the same half.

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "expect_error.hpp"
#include "softhd/control/shape_tracking.hpp"
#include "softhd/error.hpp"
#include "softhd/fe/boundary.hpp"
#include "softhd/fe/cloud.hpp"
#include "softhd/fe/materials.hpp"
#include "softhd/fe/mesh.hpp"
#include "softhd/fe/newton.hpp"
#include "softhd/scan/visibility.hpp"

namespace softhd::test {
namespace {

using Mask = Eigen::Array<bool, Eigen::Dynamic, 1>;

// Behind the clamped end, above and to the side: the top, the y = 0.6 side and the clamped end
// face it; the bottom, the y = 0 side and the tip are turned away for moderate bending.
const Eigen::Vector3d kCamera(-2.0, 3.0, 6.0);

fe::Assembler beam() {
  return fe::Assembler(fe::make_box_mesh(Eigen::Vector3d::Zero(), Eigen::Vector3d(3.0, 0.6, 0.3),
                                         Eigen::Vector3i(4, 1, 1), 2),
                       std::make_shared<fe::MooneyRivlin>(1.0, 0.2, 3.0), Eigen::Vector3d::UnitX(),
                       {{"x0", {}}});
}

// The seen boundary points of the body deformed by u.
Mask seen(const fe::Mesh& mesh, const Eigen::VectorXd& u) {
  return scan::visible_points(fe::boundary_surface(mesh, u), kCamera);
}

ShapeObjectiveOptions surface_options(Sides sides, Particles particles = Particles::boundary) {
  ShapeObjectiveOptions o;
  o.particles = particles;
  o.volumes = ParticleVolumes::deformed;
  o.form.sides = sides;
  if (sides == Sides::visible) o.camera = kCamera;
  return o;
}

// The state of the control m (vertex controls), solved from rest.
Eigen::VectorXd solve(const fe::Assembler& A, const fe::ControlSpace& space,
                      const Eigen::VectorXd& m) {
  fe::NewtonSolver newton(A);
  fe::State s = fe::rest_state(A);
  EXPECT_TRUE(newton.solve(space.to_quadrature(m), &s).converged());
  return s.u;
}

// The visible part of the body at u: its seen boundary nodes with their current areas.
PointCloud visible_part(const fe::Mesh& mesh, const Eigen::VectorXd& u) {
  const fe::BoundaryFacets f = fe::boundary_facets(mesh);
  const PointCloud c = fe::boundary_cloud(mesh, f, u, fe::CloudVolumes::kDeformed);
  const Mask m = seen(mesh, u);
  Eigen::MatrixXd X(m.count(), 3);
  Eigen::VectorXd V(m.count());
  for (Eigen::Index i = 0, k = 0; i < m.size(); ++i)
    if (m[i]) {
      X.row(k) = c.points().row(i);
      V[k++] = c.volumes()[i];
    }
  return PointCloud(X, V);
}

}  // namespace

// J(m0 + h dm) − J(m0) − h g·dm falls as h² (observed order ≥ 1.9), the visible set the same at
// every step (else the remainder would jump, and the test says so); boundary particles, and
// node particles with the mask on their boundary nodes.
class VisibleGradient : public ::testing::TestWithParam<Particles> {};

TEST_P(VisibleGradient, TaylorRemainderIsSecondOrder) {
  const fe::Assembler A = beam();
  const fe::ControlSpace space(A.mesh(), A.geometry(), fe::ControlKind::kVertex);
  const Eigen::MatrixXd P = space.positions(A.mesh());
  const PointCloud target = visible_part(A.mesh(), solve(A, space, -0.25 * P.col(2) / 0.3));
  ShapeObjectiveOptions o = surface_options(Sides::visible, GetParam());
  o.newton.relative_tolerance = 1e-13;
  o.newton.absolute_tolerance = 1e-14;
  o.hausdorff.params.epsilon = 1e-2;
  o.tikhonov_mass = 0.05;
  ShapeObjective J(A, space, HausdorffTarget(target, o.hausdorff), o);
  const Eigen::VectorXd m0 = -0.1 * (1.0 + P.col(2).array() / 0.3).matrix();
  Eigen::VectorXd dm(m0.size());
  for (Eigen::Index k = 0; k < dm.size(); ++k) dm[k] = 0.02 * std::sin(3.0 * k + 1.0);

  const ShapeEvaluation e0 = J.evaluate(m0, true);
  ASSERT_EQ(e0.status, EvaluationStatus::ok) << e0.failure;
  const Mask mask0 = seen(A.mesh(), J.state_path().last_state().u);
  ASSERT_GT(mask0.count(), 0);
  ASSERT_LT(mask0.count(), mask0.size());
  const double slope = e0.gradient.dot(dm);
  std::vector<double> remainder;
  for (double h = 0.2; h > 0.2 / 32; h /= 2) {
    const ShapeEvaluation e = J.evaluate(m0 + h * dm, false);
    ASSERT_EQ(e.status, EvaluationStatus::ok) << e.failure;
    ASSERT_TRUE((seen(A.mesh(), J.state_path().last_state().u) == mask0).all())
        << "the visible set changed";
    remainder.push_back(std::fabs(e.J - e0.J - h * slope));
  }
  for (size_t k = 0; k + 1 < remainder.size(); ++k)
    EXPECT_GE(std::log2(remainder[k] / remainder[k + 1]), 1.9)
        << "remainders " << remainder[k] << " " << remainder[k + 1];
}

// The boundary cloud and the camera need a 3D body; a camera without the visible distance, or
// with quadrature particles, is refused naming the field.
TEST(VisibleObjective, RefusesWhatItCannotDo) {
  const fe::Assembler A2(fe::make_box_mesh(Eigen::Vector2d::Zero(), Eigen::Vector2d(3.0, 0.3),
                                           Eigen::Vector2i(4, 1), 1),
                         std::make_shared<fe::MooneyRivlin>(1.0, 0.2, 3.0),
                         Eigen::Vector3d::UnitX(), {{"x0", {}}});
  const fe::ControlSpace space(A2.mesh(), A2.geometry(), fe::ControlKind::kVertex);
  ShapeObjectiveOptions o;
  o.particles = Particles::boundary;
  const PointCloud Y(Eigen::MatrixXd::Ones(3, 2));
  expect_error<InvalidArgument>([&] { ShapeObjective(A2, space, HausdorffTarget(Y), o); },
                                "needs a 3D body");
  o = surface_options(Sides::symmetric);
  o.camera = kCamera;
  expect_error<InvalidArgument>([&] { o.validate(); }, "a camera selects the visible distance");
  o = surface_options(Sides::visible, Particles::quadrature);
  expect_error<InvalidArgument>([&] { o.validate(); }, "particles must be nodes or boundary");
  o = surface_options(Sides::visible);
  o.camera = Eigen::Vector3d(NAN, 0.0, 0.0);
  expect_error<InvalidArgument>([&] { o.validate(); }, "camera must be finite");
}

INSTANTIATE_TEST_SUITE_P(Particles, VisibleGradient,
                         ::testing::Values(Particles::boundary, Particles::nodes),
                         [](const ::testing::TestParamInfo<Particles>& info) {
                           return to_string(info.param);
                         });

// A manufactured bend seen from the camera: the target is the visible half of the deformed
// boundary. From rest, the visible distance (B over the seen points only) ends nearer to the
// manufactured state than the symmetric one, which pulls the hidden side onto the seen half.
TEST(VisibleObjective, TracksAHalfViewBetterThanTheSymmetricDistance) {
  const fe::Assembler A = beam();
  const fe::ControlSpace space(A.mesh(), A.geometry(), fe::ControlKind::kVertex);
  const Eigen::VectorXd m_true = -0.3 * space.positions(A.mesh()).col(2) / 0.3;
  const Eigen::VectorXd u_true = solve(A, space, m_true);
  const PointCloud target = visible_part(A.mesh(), u_true);
  const Eigen::VectorXd lo = Eigen::VectorXd::Constant(space.size(), -1.0);
  const Eigen::VectorXd hi = Eigen::VectorXd::Zero(space.size());
  ShapeTrackingOptions to;
  to.optimizer.max_iterations = 15;
  to.optimizer.move_limit = 0.2;
  double rms[2];
  for (Sides sides : {Sides::symmetric, Sides::visible}) {
    const ShapeObjectiveOptions o = surface_options(sides);
    ShapeObjective J(A, space, HausdorffTarget(target, o.hausdorff), o);
    const ShapeTrackingSummary s =
        track_shape(J, lo, hi, Eigen::VectorXd::Zero(space.size()), u_true, to);
    rms[sides == Sides::visible] = *s.shape_error_rms;
    std::printf("%s: node error rms %.3e max %.3e, rho %.3e -> %.3e, %d iterations\n",
                to_string(sides).c_str(), *s.shape_error_rms, *s.shape_error_max, s.rho_start,
                s.rho_final, s.iterations);
  }
  const double rest = shape_error(A.mesh(), Eigen::VectorXd::Zero(u_true.size()), u_true).second;
  std::printf("rest: node error rms %.3e\n", rest);
  EXPECT_LT(rms[1], 0.5 * rest);    // the visible run tracks the bend
  EXPECT_LT(rms[1], 0.2 * rms[0]);  // and beats the symmetric one clearly (measured: 15x)
}

}  // namespace softhd::test
