// track_shape, one shape-tracking run: checked against a target manufactured on the same
// mesh (so the known map is the state itself), and against the invariants of its records.

#include <gtest/gtest.h>

#include <iomanip>

#include "expect_error.hpp"
#include "softhd/control/shape_tracking.hpp"
#include "softhd/fe/cloud.hpp"
#include "softhd/fe/materials.hpp"
#include "softhd/fe/mesh.hpp"

namespace softhd::test {
namespace {

fe::Assembler beam() {
  return fe::Assembler(fe::make_box_mesh(Eigen::Vector3d::Zero(), Eigen::Vector3d(3.0, 0.6, 0.3),
                                         Eigen::Vector3i(4, 1, 1), 2),
                       std::make_shared<fe::MooneyRivlin>(1.0, 0.2, 3.0), Eigen::Vector3d::UnitX(),
                       {{"x0", {}}});
}

struct Manufactured {
  Eigen::VectorXd m_true, u_true;
  PointCloud target;  // the deformed nodes with their deformed volumes
};

// The state of m_true = −0.3 X3/0.3 (bends the beam upwards).
Manufactured manufacture(const fe::Assembler& A, const fe::ControlSpace& space) {
  const Eigen::VectorXd m = -0.3 * space.positions(A.mesh()).col(2) / 0.3;
  fe::NewtonSolver newton(A);
  fe::State s = fe::rest_state(A);
  EXPECT_TRUE(newton.solve(space.to_quadrature(m), &s).converged());
  return {m, s.u, fe::deformed_cloud(A, s.u, fe::CloudPoints::kNodes, fe::CloudVolumes::kDeformed)};
}

TEST(ShapeTracking, StartingAtTheManufacturedControlSitsOnTheMatchedFloor) {
  const fe::Assembler A = beam();
  const fe::ControlSpace space(A.mesh(), A.geometry(), fe::ControlKind::kVertex);
  const Manufactured t = manufacture(A, space);
  ShapeObjectiveOptions o;
  o.volumes = ParticleVolumes::deformed;  // the target's volumes are the deformed ones
  ShapeObjective J(A, space, HausdorffTarget(t.target, o.hausdorff), o);
  ShapeTrackingOptions to;
  to.optimizer.max_iterations = 2;
  to.optimizer.max_evaluations = 10;  // no step can improve on the floor
  const Eigen::VectorXd lo = Eigen::VectorXd::Constant(space.size(), -1.0);
  const Eigen::VectorXd hi = Eigen::VectorXd::Zero(space.size());
  const ShapeTrackingSummary s = track_shape(J, lo, hi, t.m_true, t.u_true, to);
  // The body at m_true is the target: every floor and the start coincide, shape error ~ 0.
  ASSERT_TRUE(s.floor_matched.has_value() && s.floor_self.has_value());
  EXPECT_NEAR(*s.floor_matched, *s.floor_self, 1e-12 * *s.floor_self);
  EXPECT_NEAR(s.rho_start, *s.floor_self, 1e-8 * *s.floor_self);
  EXPECT_LE(s.rho_final, s.rho_start * (1 + 1e-12))
      << std::setprecision(17) << s.rho_final << " " << s.rho_start << " "
      << (s.control - t.m_true).norm();
  EXPECT_LT(*s.shape_error_max, 1e-3);
  // A target too large for its M² self floor: skipped, progress judged on the matched floor.
  to.self_floor_max_pairs = 0.0;
  const ShapeTrackingSummary t2 = track_shape(J, lo, hi, t.m_true, t.u_true, to);
  EXPECT_FALSE(t2.floor_self.has_value());
  EXPECT_EQ(t2.floor(), s.floor_matched);
}

TEST(ShapeTracking, RecordsAreConsistentAndTheShapeErrorFalls) {
  const fe::Assembler A = beam();
  const fe::ControlSpace space(A.mesh(), A.geometry(), fe::ControlKind::kVertex);
  const Manufactured t = manufacture(A, space);
  ShapeObjective J(A, space, HausdorffTarget(t.target));
  ShapeTrackingOptions to;
  to.optimizer.max_iterations = 8;
  to.optimizer.move_limit = 0.2;
  const Eigen::VectorXd lo = Eigen::VectorXd::Constant(space.size(), -1.0);
  const Eigen::VectorXd hi = Eigen::VectorXd::Zero(space.size());
  int calls = 0;
  ShapeTrackingCallbacks cb;
  cb.on_iteration = [&](const TrackingIteration&, const Eigen::VectorXd&) { ++calls; };
  const ShapeTrackingSummary s =
      track_shape(J, lo, hi, Eigen::VectorXd::Zero(space.size()), t.u_true, to, cb);
  ASSERT_EQ(static_cast<int>(s.history.size()), s.iterations);
  EXPECT_EQ(calls, s.iterations);
  EXPECT_GT(s.iterations, 0);
  // Accepted iterations improve the best value: J never rises along the history.
  for (size_t k = 1; k < s.history.size(); ++k) EXPECT_LE(s.history[k].J, s.history[k - 1].J);
  EXPECT_DOUBLE_EQ(s.history.back().J, s.J_final);
  EXPECT_LT(s.rho_final, 0.5 * s.rho_start);
  for (const TrackingIteration& it : s.history)
    EXPECT_NEAR(it.rho_over_floor, it.rho / *s.floor_matched, 1e-12 * it.rho_over_floor);
  // The reported shape error is that of the returned state; the rest state's is larger.
  const auto [mx, rms] = shape_error(A.mesh(), s.displacement, t.u_true);
  EXPECT_EQ(mx, *s.shape_error_max);
  EXPECT_EQ(rms, *s.shape_error_rms);
  EXPECT_LT(rms, shape_error(A.mesh(), Eigen::VectorXd::Zero(t.u_true.size()), t.u_true).second);
  // first_below finds the first record at or under k × floor.
  const auto hit = first_below(s.history, s.history.back().rho_over_floor);
  ASSERT_TRUE(hit.has_value());
  for (const TrackingIteration& it : s.history) {
    if (it.iteration == hit->iteration) break;
    EXPECT_GT(it.rho_over_floor, hit->rho_over_floor);
  }
  EXPECT_FALSE(first_below(s.history, 0.0).has_value());
}

TEST(ShapeTracking, RejectsAMapOfTheWrongSize) {
  const fe::Assembler A = beam();
  const fe::ControlSpace space(A.mesh(), A.geometry(), fe::ControlKind::kVertex);
  ShapeObjective J(A, space, HausdorffTarget(manufacture(A, space).target));
  const Eigen::VectorXd z = Eigen::VectorXd::Zero(space.size());
  expect_error<InvalidArgument>(
      [&] { track_shape(J, z.array() - 1.0, z, z, Eigen::VectorXd::Zero(5)); }, "known map");
}

// A start whose state solve fails on valid input is a numerical failure (StateSolveError, a
// NumericalError: the CLI exits 1), not bad input. Newton is given one iteration and one
// load step, which cannot reach the bent state.
TEST(ShapeTracking, AFailedStartingSolveIsAStateSolveError) {
  const fe::Assembler A = beam();
  const fe::ControlSpace space(A.mesh(), A.geometry(), fe::ControlKind::kVertex);
  ShapeObjectiveOptions o;
  o.newton.max_iterations = 1;
  o.newton.max_load_steps = 1;
  ShapeObjective J(A, space, HausdorffTarget(manufacture(A, space).target, o.hausdorff), o);
  const Eigen::VectorXd z = Eigen::VectorXd::Zero(space.size());
  const Eigen::VectorXd m0 = Eigen::VectorXd::Constant(space.size(), -0.5);
  try {
    track_shape(J, z.array() - 1.0, z, m0, std::nullopt);
    ADD_FAILURE() << "no error";
  } catch (const StateSolveError& e) {
    EXPECT_NE(std::string(e.what()).find("starting control failed"), std::string::npos);
    const NumericalError* numerical = &e;  // the CLI's exit status 1
    EXPECT_NE(numerical, nullptr);
  }
}

}  // namespace
}  // namespace softhd::test
