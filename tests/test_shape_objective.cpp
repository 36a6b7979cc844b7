// The coupled objective J(m) = ρ̃(Φ_m(Ω₀), Ω_d) + regularisation: Taylor tests of its
// adjoint gradient (remainder falls as h², observed order ≥ 1.9) for every particle and
// volume mode (the boundary nodes with their facet areas in 3D), vertex and element controls,
// in 2D and 3D; with a pose (docs/formulation.md §8.10) the Taylor test in the joint variables
// (m, ξ), rigid and similarity, and the invariance under a rigid motion of the target.

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <iostream>
#include <string>
#include <vector>

#include "expect_error.hpp"
#include "hausdorff_reference.hpp"
#include "softhd/control/scene.hpp"
#include "softhd/control/shape_objective.hpp"
#include "softhd/error.hpp"
#include "softhd/fe/grid_sequencing.hpp"
#include "softhd/fe/materials.hpp"
#include "softhd/fe/mesh.hpp"
#include "softhd/scan/pose.hpp"

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

// The Taylor remainders |J(h) − J₀ − h·slope| for h = h₀, h₀/2, …, h₀/16 (J(h) from
// `at`, which must succeed), and the observed order log₂(r_k / r_{k+1}) of each consecutive
// pair checked to lie in [lo, hi].
void expect_taylor_order(double h0, double J0, double slope,
                         const std::function<ShapeEvaluation(double)>& at, double lo, double hi,
                         const std::string& what) {
  std::vector<double> r;
  for (double h = h0; h > h0 / 32; h /= 2) {
    const ShapeEvaluation e = at(h);
    ASSERT_EQ(e.status, EvaluationStatus::ok) << what << ": " << e.failure;
    r.push_back(std::fabs(e.J - J0 - h * slope));
  }
  for (size_t k = 0; k + 1 < r.size(); ++k) {
    const double order = std::log2(r[k] / r[k + 1]);
    EXPECT_GE(order, lo) << what << ", steps " << k << "," << k + 1 << " remainders " << r[k] << " "
                         << r[k + 1];
    EXPECT_LE(order, hi) << what << ", steps " << k << "," << k + 1 << " remainders " << r[k] << " "
                         << r[k + 1];
  }
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
  ShapeObjective J(A, space, HausdorffTarget(PointCloud(py, Y.volumes()), o.hausdorff), o);

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
  expect_taylor_order(
      0.2, e0.J, slope, [&](double h) { return J.evaluate(m0 + h * dm, false); }, 1.9, INFINITY,
      "control");
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
  softhd::Scene scene =
      softhd::load_scene(std::string(SOFTHD_SOURCE_DIR) + "/data/scenes/bending.json");
  scene.body.cells << 6, 1, 2;  // coarse level 3 x 1 x 1
  const fe::Assembler A = scene.body.make_assembler();
  const fe::Assembler coarse = fe::coarsened(scene.body).make_assembler();
  const fe::ControlSpace space(A.mesh(), A.geometry(), scene.body.control_kind);
  const Eigen::MatrixXd P = space.positions(A.mesh());
  const Eigen::VectorXd m = -2.5e4 * (1.0 + P.col(2).array() / 0.1).matrix();  // ~half a turn
  PointCloud Y = random_cloud(50, 3, 4, 0.0, 1.0);
  ShapeObjectiveOptions o;
  o.newton.relative_tolerance = 1e-12;
  o.newton.displacement_tolerance = 1e-11;  // both paths end on the same state, soft modes too
  o.coarse_correction_iterations = 0;       // always take the coarse-corrected start
  ShapeObjective plain(A, space, HausdorffTarget(Y), o);
  ShapeObjective two_level(A, space, HausdorffTarget(Y), o);
  two_level.state_path().use_coarse_level(coarse);
  EXPECT_EQ(plain.state_path().coarse_level(), nullptr);
  EXPECT_EQ(two_level.state_path().coarse_level(), &coarse);
  const ShapeEvaluation a = plain.evaluate(m, true), b = two_level.evaluate(m, true);
  ASSERT_TRUE(a.status == EvaluationStatus::ok && b.status == EvaluationStatus::ok)
      << a.failure << b.failure;
  const Eigen::VectorXd& ua = plain.state_path().last_state().u;
  EXPECT_LT((two_level.state_path().last_state().u - ua).lpNorm<Eigen::Infinity>(),
            1e-9 * ua.lpNorm<Eigen::Infinity>());
  EXPECT_NEAR(b.J, a.J, 1e-10 * a.J);
  EXPECT_LT((b.gradient - a.gradient).norm(), 1e-6 * a.gradient.norm());
  EXPECT_LT(b.newton_iterations, a.newton_iterations);
  // A second step starts from the first one's state, whose coarse equilibrium is kept.
  const ShapeEvaluation c = plain.evaluate(1.4 * m, false), d = two_level.evaluate(1.4 * m, false);
  ASSERT_TRUE(c.status == EvaluationStatus::ok && d.status == EvaluationStatus::ok)
      << c.failure << d.failure;
  const Eigen::VectorXd& uc = plain.state_path().last_state().u;
  EXPECT_LT((two_level.state_path().last_state().u - uc).lpNorm<Eigen::Infinity>(),
            1e-9 * uc.lpNorm<Eigen::Infinity>());
  EXPECT_NEAR(d.J, c.J, 1e-10 * c.J);
}

// ---- The joint pose (docs/formulation.md §8.10) ----

/// A target over the bent 3D strip (body frame), as in the Taylor test above.
PointCloud bent_target() {
  PointCloud Y = random_cloud(60, 3, 21, 0.0, 1.0);
  Eigen::MatrixXd py = Y.points();
  py.col(0) *= 2.8;
  py.col(1) *= 0.6;
  py.col(2) = 0.4 * py.col(2) + 0.1 * py.col(0).array().square().matrix();
  return PointCloud(py, Y.volumes());
}

/// The camera's frame: scan points G(y) of body-frame points y (rotation ~0.6 rad).
scan::Pose camera_motion() {
  Eigen::Matrix<double, 7, 1> tw;
  tw << 0.3, -0.4, 0.35, 0.5, -1.0, 2.0, 0.0;
  return scan::Pose::from_twist(tw);
}

struct PoseCase {
  scan::PoseKind kind;
  Particles particles;
  ParticleVolumes volumes;
};

class JointGradient : public ::testing::TestWithParam<PoseCase> {};

// J(m, ξ) along a joint direction (dm, dξ) from a ξ₀ ≠ 0 (the exponential map's exact
// derivative, not its value at 0): the Taylor remainder falls as h² (observed order in
// [1.9, 2.1]; steps from h = 0.05, the ε = 1e-2 distance's curvature makes h = 0.2 pre-asymptotic,
// order 1.82 there).
TEST_P(JointGradient, TaylorRemainderIsSecondOrderInControlAndPose) {
  const PoseCase c = GetParam();
  const bool similarity = c.kind == scan::PoseKind::similarity;
  const fe::Assembler A = strip(3);
  const fe::ControlSpace space(A.mesh(), A.geometry(), fe::ControlKind::kVertex);
  const scan::Pose G = camera_motion();
  ShapeObjectiveOptions o;
  o.particles = c.particles;
  o.volumes = c.volumes;
  o.tikhonov_mass = 0.05;
  o.newton.relative_tolerance = 1e-13;
  o.newton.absolute_tolerance = 1e-14;
  o.hausdorff.params.epsilon = 1e-2;
  // The start: the true pose G⁻¹ perturbed (0.1 rad, 0.05 translation, 3 % scale).
  Eigen::Matrix<double, 7, 1> off;
  off << 0.05, 0.08, -0.03, 0.05, -0.02, 0.03, similarity ? 0.03 : 0.0;
  o.pose = scan::compose(G.inverse(), scan::Pose::from_twist(off));
  o.pose_kind = c.kind;
  ShapeObjective J(A, space, HausdorffTarget(G.apply(bent_target(), false), o.hausdorff), o);
  const int n = similarity ? 7 : 6;
  ASSERT_EQ(pose_variables(J), n);

  const Eigen::MatrixXd P = space.positions(A.mesh());
  const Eigen::VectorXd m0 = -0.15 * (1.0 + P.col(2).array() / 0.3).matrix();
  Eigen::VectorXd dm = random_cloud(static_cast<int>(m0.size()), 2, 5).points().col(0);
  dm.array() -= 0.5;
  dm *= 0.2;
  Eigen::VectorXd xi0(n), dxi(n);
  xi0.head<6>() << 0.2, -0.1, 0.15, 0.03, 0.02, -0.04;
  dxi.head<6>() << -0.3, 0.2, 0.25, 0.1, -0.15, 0.05;
  if (similarity) {
    xi0[6] = 0.04;
    dxi[6] = -0.2;
  }

  const ShapeEvaluation e0 = J.evaluate(m0, true, xi0);
  ASSERT_EQ(e0.status, EvaluationStatus::ok) << e0.failure;
  ASSERT_EQ(e0.pose_gradient.size(), n);
  ASSERT_TRUE(e0.gradient.allFinite() && e0.pose_gradient.allFinite());
  const double slope = e0.gradient.dot(dm) + e0.pose_gradient.dot(dxi);
  expect_taylor_order(
      0.05, e0.J, slope, [&](double h) { return J.evaluate(m0 + h * dm, false, xi0 + h * dxi); },
      1.9, 2.1, "control and pose");
  // The pose alone (dm = 0) as well: its gradient is not hidden behind the control's.
  expect_taylor_order(
      0.05, e0.J, e0.pose_gradient.dot(dxi),
      [&](double h) { return J.evaluate(m0, false, xi0 + h * dxi); }, 1.9, 2.1, "pose only");
}

INSTANTIATE_TEST_SUITE_P(Pose, JointGradient,
                         ::testing::Values(PoseCase{scan::PoseKind::rigid, Particles::nodes,
                                                    ParticleVolumes::reference},
                                           PoseCase{scan::PoseKind::similarity, Particles::nodes,
                                                    ParticleVolumes::reference},
                                           PoseCase{scan::PoseKind::similarity, Particles::boundary,
                                                    ParticleVolumes::deformed}),
                         [](const ::testing::TestParamInfo<PoseCase>& info) {
                           return to_string(info.param.kind) + "_" +
                                  to_string(info.param.particles) + "_" +
                                  to_string(info.param.volumes);
                         });

// A rigidly moved target with the inverse pose is the unmoved one: the same J and dJ/dm (the
// symmetric distance, and the visible one whose camera follows the pose), and P_ξ as a new
// start at ξ = 0 gives J(m, ξ).
TEST(ShapeObjective, RigidlyMovedTargetWithTheInversePoseGivesTheSameObjective) {
  const fe::Assembler A = strip(3);
  const fe::ControlSpace space(A.mesh(), A.geometry(), fe::ControlKind::kElement);
  const scan::Pose G = camera_motion();
  const PointCloud Y = bent_target();
  const Eigen::VectorXd m = Eigen::VectorXd::Constant(space.size(), -0.2);
  for (const bool visible : {false, true}) {
    SCOPED_TRACE(visible ? "visible" : "symmetric");
    ShapeObjectiveOptions o;
    o.hausdorff.params.epsilon = 1e-2;
    o.particles = Particles::boundary;
    ShapeObjectiveOptions in_body = o, in_camera = o;
    if (visible) {
      // A camera above the strip (body frame); in the camera's frame it sits at G's origin image.
      const scan::Pose P = G.inverse();
      in_body.form.sides = in_camera.form.sides = Sides::visible;
      in_body.camera = P.camera_position();
    }
    in_camera.pose = G.inverse();
    ShapeObjective a(A, space, HausdorffTarget(Y, o.hausdorff), in_body);
    ShapeObjective b(A, space, HausdorffTarget(G.apply(Y, false), o.hausdorff), in_camera);
    EXPECT_EQ(pose_variables(a), 0);
    EXPECT_EQ(pose_variables(b), 6);
    const ShapeEvaluation ea = a.evaluate(m, true), eb = b.evaluate(m, true);
    ASSERT_TRUE(ea.status == EvaluationStatus::ok && eb.status == EvaluationStatus::ok);
    EXPECT_TRUE(ea.pose_gradient.size() == 0);
    EXPECT_NEAR(eb.J, ea.J, 1e-12 * ea.J);
    EXPECT_LT((eb.gradient - ea.gradient).norm(), 1e-9 * ea.gradient.norm());
    // P_ξ at ξ = 0 is the start; at ξ ≠ 0 it starts another objective with the same J.
    EXPECT_LT((pose_at(b, Eigen::VectorXd()).matrix() - G.inverse().matrix()).norm(), 1e-14);
    Eigen::VectorXd xi(6);
    xi << 0.1, -0.2, 0.05, 0.02, 0.01, -0.03;
    const ShapeEvaluation ex = b.evaluate(m, false, xi);
    ShapeObjectiveOptions rebased = in_camera;
    rebased.pose = pose_at(b, xi);
    ShapeObjective c(A, space, HausdorffTarget(G.apply(Y, false), o.hausdorff), rebased);
    const ShapeEvaluation ec = c.evaluate(m, false);
    ASSERT_TRUE(ex.status == EvaluationStatus::ok && ec.status == EvaluationStatus::ok);
    EXPECT_NEAR(ec.J, ex.J, 1e-12 * ex.J);
    EXPECT_GT(std::fabs(ex.J - eb.J), 1e-3 * eb.J);  // ξ does move the body
  }
}

// The visible distance chosen after construction (set_form, as a run's target form does): the
// same J as an objective made with it.
TEST(ShapeObjective, VisibleFormSetLaterWithAPoseIsTheSame) {
  const fe::Assembler A = strip(3);
  const fe::ControlSpace space(A.mesh(), A.geometry(), fe::ControlKind::kElement);
  const scan::Pose G = camera_motion();
  ShapeObjectiveOptions o;
  o.hausdorff.params.epsilon = 1e-2;
  o.pose = G.inverse();
  ShapeObjective later(A, space, HausdorffTarget(G.apply(bent_target(), false), o.hausdorff), o);
  o.form.sides = Sides::visible;
  ShapeObjective made(A, space, HausdorffTarget(G.apply(bent_target(), false), o.hausdorff), o);
  const Eigen::VectorXd m = Eigen::VectorXd::Constant(space.size(), -0.2);
  const ShapeEvaluation symmetric = later.evaluate(m, false);
  later.set_form(o.form);
  const ShapeEvaluation a = later.evaluate(m, true), b = made.evaluate(m, true);
  ASSERT_TRUE(a.status == EvaluationStatus::ok && b.status == EvaluationStatus::ok);
  EXPECT_EQ(a.J, b.J);
  EXPECT_EQ(a.gradient, b.gradient);
  EXPECT_NE(a.B, symmetric.B);  // the mask changed B
}

// The target's options decide the distance: an objective whose options say otherwise is
// refused (setting epsilon on the objective alone used to do nothing).
TEST(ShapeObjective, DistanceOptionsMustBeTheTargets) {
  const fe::Assembler A = strip(3);
  const fe::ControlSpace space(A.mesh(), A.geometry(), fe::ControlKind::kElement);
  ShapeObjectiveOptions o;
  o.hausdorff.params.epsilon = 1e-2;
  expect_error<InvalidArgument>(
      [&] { ShapeObjective(A, space, HausdorffTarget(bent_target()), o); },
      "hausdorff.params.epsilon differs from the target's");
  EXPECT_NO_THROW(ShapeObjective(A, space, HausdorffTarget(bent_target(), o.hausdorff), o));
}

TEST(ShapeObjective, PoseOptionsAreChecked) {
  const fe::Assembler A = strip(3);
  const fe::ControlSpace space(A.mesh(), A.geometry(), fe::ControlKind::kElement);
  ShapeObjectiveOptions o;
  o.pose = scan::Pose();
  o.pose->R(0, 1) = 0.5;  // not a rotation
  EXPECT_THROW(ShapeObjective(A, space, HausdorffTarget(bent_target()), o), InvalidArgument);
  o.pose = scan::Pose();
  o.form.sides = Sides::visible;
  o.camera = Eigen::Vector3d(0, 0, 5);  // a pose brings its own camera
  EXPECT_THROW(ShapeObjective(A, space, HausdorffTarget(bent_target()), o), InvalidArgument);
  o.camera.reset();
  o.pose->s = 1e-100;  // a rigid pose (the default pose_kind) has scale 1
  try {
    ShapeObjective(A, space, HausdorffTarget(bent_target()), o);
    ADD_FAILURE() << "a rigid pose of scale 1e-100 was accepted";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("got scale 1e-100"), std::string::npos) << e.what();
  }
  o.pose->s = 1.0 + 1e-12;  // within the tolerance
  EXPECT_NO_THROW(ShapeObjective(A, space, HausdorffTarget(bent_target()), o));
  o.pose->s = 1.0;
  ShapeObjective J(A, space, HausdorffTarget(bent_target()), o);
  EXPECT_THROW(J.evaluate(Eigen::VectorXd::Zero(space.size()), false, Eigen::VectorXd::Zero(7)),
               InvalidArgument);
  const fe::Assembler A2 = strip(2);
  const fe::ControlSpace space2(A2.mesh(), A2.geometry(), fe::ControlKind::kElement);
  ShapeObjectiveOptions o2;
  o2.pose = scan::Pose();
  EXPECT_THROW(ShapeObjective(A2, space2, HausdorffTarget(random_cloud(10, 2, 3)), o2),
               InvalidArgument);
}

// ---- The pose by variable projection (docs/formulation.md §8.11) ----

/// The options of a projection objective from `start`, the inner minimisation to `tolerance` × L.
ShapeObjectiveOptions projection_options(const scan::Pose& start, double tolerance) {
  ShapeObjectiveOptions o;
  o.tikhonov_mass = 0.05;
  o.newton.relative_tolerance = 1e-13;
  o.newton.absolute_tolerance = 1e-14;
  o.hausdorff.params.epsilon = 1e-2;
  o.pose = start;
  o.pose_method = PoseMethod::projection;
  o.pose_tolerance = tolerance;
  o.pose_iterations = 500;
  return o;
}

/// The start pose: the true one, G⁻¹, moved by a twist of 0.08 rad and 0.06 (L ≈ 3.1).
scan::Pose perturbed(const scan::Pose& G) {
  Eigen::Matrix<double, 7, 1> off;
  off << 0.05, -0.04, 0.05, 0.05, -0.02, 0.03, 0.0;
  return scan::compose(G.inverse(), scan::Pose::from_twist(off));
}

/// The bent strip's control (as the joint test's m0) and a direction.
void control_and_direction(const fe::Assembler& A, const fe::ControlSpace& space,
                           Eigen::VectorXd* m0, Eigen::VectorXd* dm) {
  const Eigen::MatrixXd P = space.positions(A.mesh());
  *m0 = -0.15 * (1.0 + P.col(2).array() / 0.3).matrix();
  *dm = random_cloud(static_cast<int>(m0->size()), 2, 5).points().col(0);
  dm->array() -= 0.5;
  *dm *= 0.2;
}

// A target that is the body's own moving cloud at m, rigidly moved by G: the inner minimisation
// recovers G⁻¹ from a start 0.08 rad and 0.06 off. The symmetric ρ̃ between a cloud and a copy
// moved by δ is even in δ (ρ̃(T_δ X, X) = ρ̃(X, T_δ⁻¹ X)), so δ = 0 is stationary.
// The bent 3D strip at a control m0 (and a direction dm), seen by a camera moved by G.
class PoseProjection : public ::testing::Test {
 protected:
  void SetUp() override { control_and_direction(A, space, &m0, &dm); }
  const fe::Assembler A = strip(3);
  const fe::ControlSpace space{A.mesh(), A.geometry(), fe::ControlKind::kVertex};
  const scan::Pose G = camera_motion();
  Eigen::VectorXd m0, dm;
  // The body's moving cloud at m0 in its own frame (o's distance, no pose).
  PointCloud body_at_m0(const ShapeObjectiveOptions& o) const {
    ShapeObjectiveOptions in_body = o;
    in_body.pose.reset();
    in_body.pose_method = PoseMethod::joint;
    ShapeObjective B(A, space, HausdorffTarget(bent_target(), o.hausdorff), in_body);
    EXPECT_EQ(B.evaluate(m0, false).status, EvaluationStatus::ok);
    return B.moving_cloud().at(B.state_path().last_state().u);
  }
};

TEST_F(PoseProjection, RecoversTheMotionOfAnExactlyMovedCopyOfTheBody) {
  const ShapeObjectiveOptions o = projection_options(perturbed(G), 1e-13);
  const PointCloud X = body_at_m0(o);
  ShapeObjective J(A, space, HausdorffTarget(G.apply(X, false), o.hausdorff), o);
  EXPECT_EQ(pose_variables(J), 0);  // the optimiser sees the control alone
  const ShapeEvaluation e = J.evaluate(m0, true);
  ASSERT_EQ(e.status, EvaluationStatus::ok) << e.failure;
  ASSERT_EQ(e.pose_twist.size(), 6);
  EXPECT_EQ(e.pose_gradient.size(), 0);
  const scan::Pose P = pose_at(J, e.pose_twist), truth = G.inverse();
  const double L = (X.points().colwise().maxCoeff() - X.points().colwise().minCoeff()).norm();
  const double angle = scan::rotation_angle_between(P.R, truth.R);
  const double shift = (P.t - truth.t).norm() / L;
  std::cout << "exact copy: rotation error " << angle << " rad, translation error " << shift
            << " L, " << e.pose_iterations << " BFGS iterations\n";
  EXPECT_LT(angle, 1e-12);
  EXPECT_LT(shift, 1e-12);
  EXPECT_EQ(J.pose_warm_start(), Eigen::VectorXd::Zero(6));  // evaluate leaves it (track_shape
                                                             // sets it)
}

// f(m) = min_ξ ρ̃(Q_ξ(X(u(m))), Y) + J_reg(m) with the inner minimisation tight: the envelope
// gradient (the adjoint at ξ*(m)) against central differences of f. Their difference falls as
// h² (the central difference's remainder f‴h²/6; observed order in [1.9, 2.1]). At ξ* the joint
// objective's dJ/dξ is (near) zero: the inner optimality the envelope theorem needs.
TEST_F(PoseProjection, EnvelopeGradientMatchesCentralDifferences) {
  const ShapeObjectiveOptions o = projection_options(perturbed(G), 1e-13);
  const PointCloud Y = G.apply(bent_target(), false);
  ShapeObjective J(A, space, HausdorffTarget(Y, o.hausdorff), o);
  const ShapeEvaluation e0 = J.evaluate(m0, true);
  ASSERT_EQ(e0.status, EvaluationStatus::ok) << e0.failure;
  const double slope = e0.gradient.dot(dm);
  const auto f = [&](const Eigen::VectorXd& m) {
    const ShapeEvaluation e = J.evaluate(m, false);
    EXPECT_EQ(e.status, EvaluationStatus::ok) << e.failure;
    return e.J;
  };
  std::vector<double> r;
  for (double h = 0.04; h > 0.04 / 32; h /= 2)
    r.push_back(std::fabs((f(m0 + h * dm) - f(m0 - h * dm)) / (2 * h) - slope));
  for (size_t k = 0; k + 1 < r.size(); ++k) {
    const double order = std::log2(r[k] / r[k + 1]);
    std::cout << "central difference - slope " << r[k] << " -> " << r[k + 1] << ", order " << order
              << "\n";
    EXPECT_GE(order, 1.9);
    EXPECT_LE(order, 2.1);
  }
  std::cout << "slope " << slope
            << ", relative difference at h = 0.04/16: " << r.back() / std::fabs(slope) << "\n";
  // The joint objective's pose gradient at ξ*: the inner optimality.
  ShapeObjectiveOptions joint = o;
  joint.pose_method = PoseMethod::joint;
  ShapeObjective Jj(A, space, HausdorffTarget(Y, o.hausdorff), joint);
  const ShapeEvaluation at_start = Jj.evaluate(m0, true);
  const ShapeEvaluation at_optimum = Jj.evaluate(m0, true, e0.pose_twist);
  ASSERT_TRUE(at_start.status == EvaluationStatus::ok && at_optimum.status == EvaluationStatus::ok);
  std::cout << "|dJ/dxi| at the start " << at_start.pose_gradient.norm() << ", at xi* "
            << at_optimum.pose_gradient.norm() << "\n";
  EXPECT_LT(at_optimum.pose_gradient.norm(), 1e-8 * at_start.pose_gradient.norm());
  EXPECT_NEAR(at_optimum.J, e0.J, 1e-14 * e0.J);  // the same (m, ξ*)
  EXPECT_LT((at_optimum.gradient - e0.gradient).norm(), 1e-12 * e0.gradient.norm());
}

TEST_F(PoseProjection, RefusesATwistASimilarityAndABadTolerance) {
  ShapeObjectiveOptions o = projection_options(perturbed(G), 1e-10);
  ShapeObjective J(A, space, HausdorffTarget(G.apply(bent_target(), false), o.hausdorff), o);
  expect_error<InvalidArgument>(
      [&] { J.evaluate(Eigen::VectorXd::Zero(space.size()), false, Eigen::VectorXd::Zero(6)); },
      "expected 0 (the projection finds it)");
  o.pose_kind = scan::PoseKind::similarity;
  expect_error<InvalidArgument>([&] { o.validate(); }, "pose.method projection finds a rigid");
  o.pose_kind = scan::PoseKind::rigid;
  o.pose_tolerance = 0.0;
  expect_error<InvalidArgument>([&] { o.validate(); }, "pose_tolerance must be in (0, 1)");
  o.pose_tolerance = 1e-10;
  o.pose_iterations = 0;
  expect_error<InvalidArgument>([&] { o.validate(); }, "pose_iterations must be >= 1");
}

// A calibrated camera's uncertainty as a bound on the twist (docs/formulation.md §8.11): from a
// start 0.08 rad and 0.06 off an exact moved copy, a bound of 0.02 rad and 0.01 holds the found
// twist on it (|ω| = 0.02, |v| ≤ 0.01 to rounding) at a lower ρ̃ than the start's; a bound the
// truth lies within gives the truth back as unbounded. (With the bound active the projected
// BFGS stops short of the constrained minimum and the envelope gradient is not exact there:
// §8.11 has the measurement.)
TEST_F(PoseProjection, TheUncertaintyBoundsTheTwist) {
  ShapeObjectiveOptions o = projection_options(perturbed(G), 1e-13);
  const PointCloud seen = G.apply(body_at_m0(o), false);
  o.pose_bound = PoseBound{0.02, 0.01};
  ShapeObjective J(A, space, HausdorffTarget(seen, o.hausdorff), o);
  const ShapeEvaluation e = J.evaluate(m0, true);
  ASSERT_EQ(e.status, EvaluationStatus::ok);
  std::cout << "bounded: |omega| " << e.pose_twist.head<3>().norm() << ", |v| "
            << e.pose_twist.segment<3>(3).norm() << "\n";
  EXPECT_LE(e.pose_twist.head<3>().norm(), 0.02 * (1 + 1e-12));
  EXPECT_GT(e.pose_twist.head<3>().norm(), 0.02 * (1 - 1e-9));  // active: the truth is 0.08 away
  EXPECT_LE(e.pose_twist.segment<3>(3).norm(), 0.01 * (1 + 1e-12));
  ShapeObjectiveOptions zero = o;  // ρ̃ at the start pose itself: a bound too small to move
  zero.pose_bound = PoseBound{1e-300, 1e-300};
  ShapeObjective Z(A, space, HausdorffTarget(seen, o.hausdorff), zero);
  EXPECT_LT(e.J, Z.evaluate(m0, false).J);
  o.pose_bound = PoseBound{0.2, 1.0};  // the truth inside: recovered as without a bound
  ShapeObjective K(A, space, HausdorffTarget(seen, o.hausdorff), o);
  const ShapeEvaluation k = K.evaluate(m0, false);
  const scan::Pose P = pose_at(K, k.pose_twist), truth = G.inverse();
  EXPECT_LT(scan::rotation_angle_between(P.R, truth.R), 1e-12);
  o.pose_bound = PoseBound{-1.0, 1.0};
  expect_error<InvalidArgument>([&] { o.validate(); }, "pose_bound.rotation must be finite");
  o.pose_bound = PoseBound{1.0, std::nan("")};
  expect_error<InvalidArgument>([&] { o.validate(); }, "pose_bound.translation must be finite");
  o.pose_bound = PoseBound{1.0, 1.0};
  o.pose_method = PoseMethod::joint;
  expect_error<InvalidArgument>([&] { o.validate(); }, "pose_bound bounds the pose found by");
}

// The fixture's table normal n_b in the projection (docs/formulation.md §8.12): the inner
// minimisation turns the body only about the table's normal and shifts it only along the table.
// A start that differs from the truth by such a motion (0.08 rad about z and (0.05, −0.03))
// gives the truth back to rounding; from a start tilted off it (perturbed()), the pose found
// keeps the start's tilt R_Q n_b and height n_s·t_Q to rounding while ρ̃ falls.
TEST_F(PoseProjection, TheTableNormalKeepsTheStartsTiltAndHeight) {
  ShapeObjectiveOptions o = projection_options(G.inverse(), 1e-13);
  const PointCloud seen = G.apply(body_at_m0(o), false);
  const Eigen::Vector3d n(0.0, 0.0, 2.0);  // the table's normal, not a unit vector
  o.pose_table_normal = n;
  scan::Pose turn;  // body frame: about z through (1, 0.2, 0), then along the table
  turn.R = Eigen::AngleAxisd(0.08, Eigen::Vector3d::UnitZ()).matrix();
  turn.t = Eigen::Vector3d(1.0, 0.2, 0.0) - turn.R * Eigen::Vector3d(1.0, 0.2, 0.0) +
           Eigen::Vector3d(0.05, -0.03, 0.0);
  o.pose = scan::compose(turn, G.inverse());
  ShapeObjective J(A, space, HausdorffTarget(seen, o.hausdorff), o);
  const ShapeEvaluation e = J.evaluate(m0, false);
  ASSERT_EQ(e.status, EvaluationStatus::ok) << e.failure;
  const scan::Pose P = pose_at(J, e.pose_twist), truth = G.inverse();
  EXPECT_LT(scan::rotation_angle_between(P.R, truth.R), 1e-12);
  EXPECT_LT((P.t - truth.t).norm(), 1e-11);
  o.pose = perturbed(G);  // tilted: the truth is off the start's constraint
  ShapeObjective K(A, space, HausdorffTarget(seen, o.hausdorff), o);
  const ShapeEvaluation k = K.evaluate(m0, false);
  const scan::Pose Q0 = o.pose->inverse(), Q = pose_at(K, k.pose_twist).inverse();
  const Eigen::Vector3d ns = Q0.R * n.normalized();
  EXPECT_LT((Q.R * n.normalized() - ns).norm(), 1e-13);
  EXPECT_LT(std::abs(ns.dot(Q.t) - ns.dot(Q0.t)), 1e-12);
  ShapeObjectiveOptions zero = o;  // ρ̃ at the start pose itself
  zero.pose_bound = PoseBound{1e-300, 1e-300};
  ShapeObjective Z(A, space, HausdorffTarget(seen, o.hausdorff), zero);
  EXPECT_LT(k.J, Z.evaluate(m0, false).J);
  o.pose_table_normal = Eigen::Vector3d::Zero();
  expect_error<InvalidArgument>([&] { o.validate(); }, "pose_table_normal must be finite");
  o.pose_table_normal = n;
  o.pose_method = PoseMethod::joint;
  expect_error<InvalidArgument>([&] { o.validate(); }, "pose_table_normal constrains the pose");
}

}  // namespace
}  // namespace softhd::test
