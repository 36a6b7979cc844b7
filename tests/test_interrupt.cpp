// Cancelling long calls (softhd/interrupt.hpp): the installed check is polled between the
// passes of a distance and between blocks of its outer points, and between an optimiser's
// evaluations; a true answer unwinds with Interrupted, and an interrupted tracking run leaves a
// checkpoint that resumes to the uninterrupted run.

#include <gtest/gtest.h>

#include <filesystem>

#include "expect_error.hpp"
#include "hausdorff_reference.hpp"
#include "softhd/control/shape_tracking.hpp"
#include "softhd/fe/cloud.hpp"
#include "softhd/fe/materials.hpp"
#include "softhd/fe/mesh.hpp"
#include "softhd/hausdorff.hpp"
#include "softhd/interrupt.hpp"

namespace softhd::test {
namespace {

/// Installs a check for the test's scope and removes it after.
class CheckScope {
 public:
  explicit CheckScope(InterruptCheck check) { set_interrupt_check(std::move(check)); }
  ~CheckScope() { set_interrupt_check({}); }
  CheckScope(const CheckScope&) = delete;
  CheckScope& operator=(const CheckScope&) = delete;
};

TEST(Interrupt, TheCheckIsPolledBetweenBlocksOfAPassAndStopsTheDistance) {
  // 24 000 × 24 000 pairs: two blocks in each of the two passes.
  const PointCloud X = random_cloud(24000, 3, 1, -1.0, 1.0);
  const PointCloud Y = random_cloud(24000, 3, 2, -1.0, 1.0);
  int calls = 0;
  const HausdorffTarget target(Y);
  {
    CheckScope scope([&] { return ++calls, false; });
    target.evaluate(X);
  }
  EXPECT_EQ(calls, 4);  // before each pass and between its two blocks
  // True at the second poll, inside pass 1: the evaluation stops there.
  calls = 0;
  {
    CheckScope scope([&] { return ++calls == 2; });
    expect_error<Interrupted>([&] { target.evaluate(X); }, "interrupted between blocks");
  }
  EXPECT_EQ(calls, 2);
  // Interrupted is a softhd::Error; the target is as good as before.
  static_assert(std::is_base_of_v<Error, Interrupted>);
  const PointCloud few = random_cloud(100, 3, 3, -1.0, 1.0);
  EXPECT_EQ(target.evaluate(few).rho, hausdorff(few, Y).rho);
  // Every method polls between its passes.
  for (Method method : {Method::tree, Method::nearest}) {
    HausdorffOptions o;
    o.method = method;
    CheckScope scope([] { return true; });
    expect_error<Interrupted>([&] { hausdorff(X, Y, o); }, "interrupted between distance passes");
  }
}

fe::Assembler beam() {
  return fe::Assembler(fe::make_box_mesh(Eigen::Vector3d::Zero(), Eigen::Vector3d(3.0, 0.6, 0.3),
                                         Eigen::Vector3i(4, 1, 1), 2),
                       std::make_shared<fe::MooneyRivlin>(1.0, 0.2, 3.0), Eigen::Vector3d::UnitX(),
                       {{"x0", {}}});
}

// The state of the beam under m(X) = -X3 / 0.3 (a known control through the thickness).
fe::State known_state(const fe::Assembler& A, const fe::ControlSpace& space) {
  const Eigen::VectorXd m_true = -0.3 * space.positions(A.mesh()).col(2) / 0.3;
  fe::NewtonSolver newton(A);
  fe::State st = fe::rest_state(A);
  EXPECT_TRUE(newton.solve(space.to_quadrature(m_true), &st).converged());
  return st;
}

// The beam's tracking problem: the target is the known state's nodes (st.u is the map of the
// matched floor), the bounds [-1, 0], the start 0.
class InterruptTracking : public ::testing::Test {
 protected:
  fe::Assembler A = beam();
  fe::ControlSpace space{A.mesh(), A.geometry(), fe::ControlKind::kVertex};
  fe::State st = known_state(A, space);
  PointCloud target =
      fe::deformed_cloud(A, st.u, fe::CloudPoints::kNodes, fe::CloudVolumes::kDeformed);
  Eigen::VectorXd lo = Eigen::VectorXd::Constant(space.size(), -1.0);
  Eigen::VectorXd hi = Eigen::VectorXd::Zero(space.size());
  Eigen::VectorXd m0 = Eigen::VectorXd::Zero(space.size());
};

TEST_F(InterruptTracking, ATrackingRunStopsBetweenEvaluationsAndItsCheckpointResumesIt) {
  const std::string dir = ::testing::TempDir() + "/interrupt_tracking";
  std::filesystem::create_directories(dir);
  ShapeTrackingOptions to;
  to.optimizer.max_iterations = 8;
  to.optimizer.move_limit = 0.2;
  to.checkpoint_every = 2;

  to.checkpoint = dir + "/uninterrupted.bin";
  ShapeObjective J0(A, space, HausdorffTarget(target));
  const ShapeTrackingSummary full = track_shape(J0, lo, hi, m0, st.u, to);
  ASSERT_EQ(full.iterations, 8);

  // Interrupted once iteration 3 is accepted: the next evaluation does not start.
  to.checkpoint = dir + "/interrupted.bin";
  int accepted = 0;
  ShapeTrackingCallbacks cb;
  cb.on_iteration = [&](const TrackingIteration& it, const Eigen::VectorXd&) {
    accepted = it.iteration;
  };
  {
    CheckScope scope([&] { return accepted >= 3; });
    ShapeObjective J1(A, space, HausdorffTarget(target));
    expect_error<Interrupted>([&] { track_shape(J1, lo, hi, m0, st.u, to, cb); },
                              "after 3 iterations (resume from the checkpoint '" + to.checkpoint);
  }
  EXPECT_EQ(accepted, 3);

  // The checkpoint resumes to the uninterrupted run, bit for bit.
  to.resume = true;
  ShapeObjective J2(A, space, HausdorffTarget(target));
  const ShapeTrackingSummary resumed = track_shape(J2, lo, hi, m0, st.u, to);
  EXPECT_EQ(resumed.iterations, full.iterations);
  EXPECT_EQ(resumed.evaluations, full.evaluations);
  EXPECT_GT(resumed.replayed_evaluations, 0);
  EXPECT_EQ(resumed.J_final, full.J_final);
  EXPECT_TRUE(resumed.control == full.control);
}

// The optimiser newton stops as MMA does: Ctrl-C (the installed check) between its evaluations
// and Hessian-vector products, and an observer's StopRequest after an iteration.
TEST_F(InterruptTracking, ANewtonRunStopsOnTheCheckAndOnAStopRequest) {
  ShapeTrackingOptions to;
  to.optimizer.algorithm = Algorithm::newton;
  to.optimizer.max_iterations = 6;
  ShapeObjectiveOptions so;
  so.second_order = true;
  int accepted = 0;
  ShapeTrackingCallbacks cb;
  cb.on_iteration = [&](const TrackingIteration& it, const Eigen::VectorXd&) {
    accepted = it.iteration;
    EXPECT_GT(it.hessian_products, 0);
    EXPECT_GT(it.trust_radius, 0.0);
  };
  {
    CheckScope scope([&] { return accepted >= 2; });
    ShapeObjective J(A, space, HausdorffTarget(target), so);
    expect_error<Interrupted>([&] { track_shape(J, lo, hi, m0, st.u, to, cb); }, "interrupted");
  }
  EXPECT_EQ(accepted, 2);

  // With a checkpoint (its Hessian-vector products logged): interrupted after iteration 3 and
  // resumed, the uninterrupted run bit for bit.
  const std::string dir = ::testing::TempDir() + "/interrupt_newton";
  std::filesystem::create_directories(dir);
  to.checkpoint_every = 2;
  to.checkpoint = dir + "/uninterrupted.bin";
  ShapeObjective J0(A, space, HausdorffTarget(target), so);
  const ShapeTrackingSummary full = track_shape(J0, lo, hi, m0, st.u, to);
  to.checkpoint = dir + "/interrupted.bin";
  accepted = 0;
  {
    CheckScope scope([&] { return accepted >= 3; });
    ShapeObjective J1(A, space, HausdorffTarget(target), so);
    expect_error<Interrupted>([&] { track_shape(J1, lo, hi, m0, st.u, to, cb); },
                              "after 3 iterations");
  }
  to.resume = true;
  ShapeObjective J2(A, space, HausdorffTarget(target), so);
  const ShapeTrackingSummary resumed = track_shape(J2, lo, hi, m0, st.u, to);
  EXPECT_GT(resumed.replayed_evaluations, 0);
  EXPECT_EQ(resumed.iterations, full.iterations);
  EXPECT_EQ(resumed.J_final, full.J_final);
  EXPECT_TRUE(resumed.control == full.control);
  to.resume = false;
  to.checkpoint.clear();

  cb.on_iteration = [&](const TrackingIteration& it, const Eigen::VectorXd&) {
    if (it.iteration == 1) throw StopRequest{};
  };
  ShapeObjective J(A, space, HausdorffTarget(target), so);
  const ShapeTrackingSummary s = track_shape(J, lo, hi, m0, st.u, to, cb);
  EXPECT_EQ(s.iterations, 1);
  EXPECT_EQ(s.status, OptimizerStatus::stopped);
  EXPECT_LT(s.rho_final, s.rho_start);
  // Without the objective's second-order data newton is refused, naming the setting.
  ShapeObjective plain(A, space, HausdorffTarget(target));
  expect_error<InvalidArgument>([&] { track_shape(plain, lo, hi, m0, st.u, to); }, "second_order");
}

}  // namespace
}  // namespace softhd::test
