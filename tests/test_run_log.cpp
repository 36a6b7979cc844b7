// The checkpoint log of a shape-tracking run and resume = the same run: a run interrupted
// (by its iteration limit, or by an exception thrown from its callback like a crash) and
// resumed has bitwise the history and the final control of an uninterrupted run; the log
// survives a torn tail, refuses corruption and checkpoints of another problem.

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "expect_error.hpp"
#include "softhd/control/run_log.hpp"
#include "softhd/control/shape_tracking.hpp"
#include "softhd/fe/cloud.hpp"
#include "softhd/fe/materials.hpp"
#include "softhd/fe/mesh.hpp"
#include "softhd/scan/pose.hpp"

namespace softhd::test {
namespace {

namespace fs = std::filesystem;

fe::Assembler beam() {
  return fe::Assembler(fe::make_box_mesh(Eigen::Vector3d::Zero(), Eigen::Vector3d(3.0, 0.6, 0.3),
                                         Eigen::Vector3i(4, 1, 1), 1),
                       std::make_shared<fe::MooneyRivlin>(1.0, 0.2, 3.0), Eigen::Vector3d::UnitX(),
                       {{"x0", {}}});
}

// A target: the beam bent by m = −0.3 X3/0.3.
PointCloud bent_target(const fe::Assembler& A, const fe::ControlSpace& space) {
  const Eigen::VectorXd m = -0.3 * space.positions(A.mesh()).col(2) / 0.3;
  fe::NewtonSolver newton(A);
  fe::State s = fe::rest_state(A);
  EXPECT_TRUE(newton.solve(space.to_quadrature(m), &s).converged());
  return fe::deformed_cloud(A, s.u, fe::CloudPoints::kNodes, fe::CloudVolumes::kReference);
}

std::string temp_path(const std::string& name) {
  return (fs::path(::testing::TempDir()) / ("softhd_runlog_" + name)).string();
}

struct Outcome {
  ShapeTrackingSummary summary;
  bool interrupted = false;
};

// One process's worth of a run: a fresh objective (as after a restart), stopping with an
// exception after `crash_after` iterations of this process (0: never), saving its states
// every `checkpoint_every` iterations.
Outcome run(const std::string& checkpoint, bool resume, int max_iterations, int crash_after,
            const fe::Assembler& A, const fe::ControlSpace& space, const PointCloud& target,
            double max_seconds = 0.0, int checkpoint_every = 1,
            const std::optional<scan::Pose>& pose = std::nullopt,
            PoseMethod method = PoseMethod::joint) {
  ShapeObjectiveOptions o;
  o.hausdorff.threads = 1;
  o.pose = pose;  // a target in the camera's frame: the pose joins the control, or is projected
  o.pose_method = method;
  ShapeObjective J(A, space, HausdorffTarget(target, o.hausdorff), o);
  ShapeTrackingOptions to;
  to.optimizer.max_iterations = max_iterations;
  to.optimizer.max_evaluations = 1000;
  to.optimizer.relative_change = 0.0;
  to.optimizer.move_limit = 0.1;
  to.optimizer.max_seconds = max_seconds;
  to.checkpoint = checkpoint;
  to.checkpoint_every = checkpoint_every;
  to.resume = resume;
  to.fingerprint["scene"] = "beam";
  int fresh = 0;
  ShapeTrackingCallbacks cb;
  cb.on_iteration = [&](const TrackingIteration& it, const Eigen::VectorXd&) {
    if (!it.replayed && crash_after > 0 && ++fresh == crash_after)
      throw std::runtime_error("simulated crash");
  };
  const Eigen::VectorXd lo = Eigen::VectorXd::Constant(space.size(), -1.0);
  const Eigen::VectorXd hi = Eigen::VectorXd::Zero(space.size());
  const Eigen::VectorXd m0 = Eigen::VectorXd::Zero(space.size());
  Outcome r;
  try {
    r.summary = track_shape(J, lo, hi, m0, std::nullopt, to, cb);
  } catch (const std::runtime_error& e) {
    if (std::string(e.what()) != "simulated crash") throw;
    r.interrupted = true;
  }
  return r;
}

bool bitwise_equal(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

void expect_same_run(const ShapeTrackingSummary& a, const ShapeTrackingSummary& b) {
  ASSERT_EQ(a.history.size(), b.history.size());
  for (size_t k = 0; k < a.history.size(); ++k) {
    const TrackingIteration &x = a.history[k], &y = b.history[k];
    EXPECT_EQ(x.iteration, y.iteration);
    EXPECT_EQ(x.evaluation, y.evaluation) << "iteration " << x.iteration;
    for (auto [p, q] : {std::pair{x.J, y.J},
                        {x.rho, y.rho},
                        {x.A, y.A},
                        {x.B, y.B},
                        {x.projected_gradient_norm, y.projected_gradient_norm}})
      EXPECT_TRUE(bitwise_equal(p, q)) << "iteration " << x.iteration << ": " << p << " vs " << q;
    EXPECT_EQ(x.newton_iterations, y.newton_iterations);
  }
  ASSERT_EQ(a.control.size(), b.control.size());
  EXPECT_EQ(std::memcmp(a.control.data(), b.control.data(), a.control.size() * 8), 0);
  EXPECT_TRUE(bitwise_equal(a.J_final, b.J_final));
  EXPECT_EQ(a.iterations, b.iterations);
  EXPECT_EQ(a.evaluations, b.evaluations);
  EXPECT_EQ(a.termination, b.termination);
  // Bitwise equal doubles (memcmp of an empty vector's null data is undefined: not called).
  auto same_bytes = [](const auto& x, const auto& y) {
    return x.size() == y.size() &&
           (x.size() == 0 || std::memcmp(x.data(), y.data(), x.size() * sizeof(double)) == 0);
  };
  EXPECT_TRUE(same_bytes(a.pose_twist, b.pose_twist));
  for (size_t k = 0; k < a.history.size(); ++k)
    EXPECT_TRUE(same_bytes(a.history[k].pose, b.history[k].pose)) << "iteration " << k + 1;
}

class ResumeIsTheSameRun : public ::testing::Test {
 protected:
  const fe::Assembler A = beam();
  const fe::ControlSpace space{A.mesh(), A.geometry(), fe::ControlKind::kVertex};
  const PointCloud target = bent_target(A, space);
  // The target seen by a camera: moved by G; the start pose the truth G⁻¹ off by a twist of
  // 0.06 rad and 0.05.
  const scan::Pose G = scan::Pose::from_twist(
      (Eigen::Matrix<double, 7, 1>() << 0.4, -0.3, 0.2, 1.0, 0.5, -2.0, 0.0).finished());
  const scan::Pose truth = G.inverse();
  const scan::Pose start = scan::compose(
      truth,
      scan::Pose::from_twist(
          (Eigen::Matrix<double, 7, 1>() << 0.06, -0.05, 0.06, 0.05, 0.0, -0.05, 0.0).finished()));
  const PointCloud seen = G.apply(target, false);
};

TEST_F(ResumeIsTheSameRun, AfterSimulatedCrashes) {
  const std::string ref_log = temp_path("ref.bin"), log = temp_path("crash.bin");
  const Outcome reference = run(ref_log, false, 12, 0, A, space, target);
  ASSERT_FALSE(reference.interrupted);
  ASSERT_GE(reference.summary.iterations, 6) << reference.summary.termination;
  // Crashes after 2, then 3 more iterations; the third process finishes the run.
  Outcome r = run(log, false, 12, 2, A, space, target);
  ASSERT_TRUE(r.interrupted);
  r = run(log, true, 12, 3, A, space, target);
  ASSERT_TRUE(r.interrupted);
  r = run(log, true, 12, 0, A, space, target);
  ASSERT_FALSE(r.interrupted);
  EXPECT_GT(r.summary.replayed_evaluations, 0);
  expect_same_run(reference.summary, r.summary);
}

// States saved every 3 iterations: a crash after 5 iterations keeps the log up to the
// third, and the resumed run makes the fourth and fifth again, as the uninterrupted run did
// (whose solver was renewed at the save, as the resumed one's is).
TEST_F(ResumeIsTheSameRun, WhenStatesAreSavedEveryFewIterations) {
  const std::string ref_log = temp_path("ref3.bin"), log = temp_path("every3.bin");
  const Outcome reference = run(ref_log, false, 9, 0, A, space, target, 0.0, 3);
  ASSERT_GE(reference.summary.iterations, 7) << reference.summary.termination;
  ASSERT_TRUE(run(log, false, 9, 5, A, space, target, 0.0, 3).interrupted);
  const RunLog saved = read_run_log(log);
  EXPECT_EQ(saved.snapshot.iterations, 3);
  const Outcome r = run(log, true, 9, 0, A, space, target, 0.0, 3);
  ASSERT_FALSE(r.interrupted);
  EXPECT_EQ(r.summary.replayed_evaluations, saved.snapshot.evaluations);
  expect_same_run(reference.summary, r.summary);
  // Another interval is another run: refused.
  expect_error<InvalidArgument>([&] { run(log, true, 9, 0, A, space, target, 0.0, 2); },
                                "checkpoint differs");
}

TEST_F(ResumeIsTheSameRun, IterationLimitIsATotalAndAFinishedRunStaysFinished) {
  const std::string ref_log = temp_path("ref2.bin"), log = temp_path("limit.bin");
  const Outcome reference = run(ref_log, false, 10, 0, A, space, target);
  const Outcome first = run(log, false, 4, 0, A, space, target);
  EXPECT_EQ(first.summary.iterations, 4);
  // The limit counts over the whole run: resumed with 10, it ends at 10, as uninterrupted.
  const Outcome second = run(log, true, 10, 0, A, space, target);
  expect_same_run(reference.summary, second.summary);
  // Resumed again with the same limit, the finished run does not go on.
  const Outcome third = run(log, true, 10, 0, A, space, target);
  expect_same_run(reference.summary, third.summary);
  EXPECT_EQ(third.summary.replayed_evaluations, third.summary.evaluations);  // all of them
}

// The wall-clock limit is a total too: resumed with a limit the earlier process already
// used up, the run stops at once, making no new evaluation (with a per-process limit it
// would go on for that long again).
TEST_F(ResumeIsTheSameRun, WallClockLimitIsATotal) {
  const std::string log = temp_path("clock.bin");
  ASSERT_TRUE(run(log, false, 50, 4, A, space, target).interrupted);
  const double used = read_run_log(log).evaluations.back().seconds;
  ASSERT_GT(used, 0.0);
  const Outcome r = run(log, true, 50, 0, A, space, target, 0.5 * used);
  EXPECT_EQ(r.summary.termination, "the wall-clock limit was reached");
  EXPECT_EQ(r.summary.replayed_evaluations, r.summary.evaluations);
}

// A joint pose (docs/formulation.md §8.10): the bent target in a camera's frame, the start pose
// 0.1 rad off. Crashed after 3 iterations and resumed, the run is the uninterrupted one (pose
// included), and another start pose is another run. (From the straight beam the pose first tilts
// towards the bent target's chord, and 16 iterations end 0.055 rad off: the basin problem of
// docs/formulation.md §8.10; the pose's recovery is tested on a rest target in
// test_optimise_cli.)
TEST_F(ResumeIsTheSameRun, WithAJointPose) {
  const std::string ref_log = temp_path("pose_ref.bin"), log = temp_path("pose.bin");
  const Outcome reference = run(ref_log, false, 16, 0, A, space, seen, 0.0, 2, start);
  ASSERT_GE(reference.summary.iterations, 12) << reference.summary.termination;
  ASSERT_TRUE(reference.summary.pose);
  ASSERT_EQ(reference.summary.pose_twist.size(), 6);
  ASSERT_EQ(reference.summary.history.back().pose.size(), 7);
  EXPECT_LT(reference.summary.rho_final, 0.5 * reference.summary.rho_start);
  ASSERT_TRUE(run(log, false, 16, 3, A, space, seen, 0.0, 2, start).interrupted);
  const Outcome r = run(log, true, 16, 0, A, space, seen, 0.0, 2, start);
  ASSERT_FALSE(r.interrupted);
  EXPECT_GT(r.summary.replayed_evaluations, 0);
  expect_same_run(reference.summary, r.summary);
  expect_error<InvalidArgument>([&] { run(log, true, 16, 0, A, space, seen, 0.0, 2, truth); },
                                "pose differs");
}

// The pose by projection (docs/formulation.md §8.11): the warm start of each inner minimisation
// is the last accepted iterate's pose, part of the run's state. States saved every 2
// iterations, a crash after 3: the resumed run replays to the save and makes the third
// iteration again from the second's pose, bitwise the uninterrupted run (pose included);
// another method is another run.
TEST_F(ResumeIsTheSameRun, WithAPoseByProjection) {
  const std::string ref_log = temp_path("proj_ref.bin"), log = temp_path("proj.bin");
  const PoseMethod p = PoseMethod::projection;
  const Outcome reference = run(ref_log, false, 8, 0, A, space, seen, 0.0, 2, start, p);
  ASSERT_GE(reference.summary.iterations, 6) << reference.summary.termination;
  ASSERT_TRUE(reference.summary.pose);
  ASSERT_EQ(reference.summary.pose_twist.size(), 6);
  ASSERT_EQ(reference.summary.history.back().pose.size(), 7);
  ASSERT_TRUE(run(log, false, 8, 3, A, space, seen, 0.0, 2, start, p).interrupted);
  EXPECT_EQ(read_run_log(log).snapshot.iterations, 2);
  const Outcome r = run(log, true, 8, 0, A, space, seen, 0.0, 2, start, p);
  ASSERT_FALSE(r.interrupted);
  EXPECT_GT(r.summary.replayed_evaluations, 0);
  expect_same_run(reference.summary, r.summary);
  expect_error<InvalidArgument>(
      [&] { run(log, true, 8, 0, A, space, seen, 0.0, 2, start, PoseMethod::joint); },
      "pose differs");
}

TEST_F(ResumeIsTheSameRun, ACheckpointOfAnotherProblemIsRefused) {
  const std::string log = temp_path("other.bin");
  run(log, false, 2, 0, A, space, target);
  // Another target (the first point moved by 1e-3): the fingerprint names it.
  Eigen::MatrixXd points = target.points();
  points(0, 0) += 1e-3;
  const PointCloud other(points, target.volumes());
  expect_error<InvalidArgument>([&] { run(log, true, 4, 0, A, space, other); },
                                "was written for another run: target differs");
}

std::string read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream b;
  b << in.rdbuf();
  return b.str();
}

// A log of three evaluations and its states file, for the format tests; returns the log.
std::string small_log(const std::string& path) {
  RunFingerprint f{{"scene", "abc"}};
  RunLogWriter w(path, f);
  for (int k = 0; k < 3; ++k) {
    LoggedEvaluation e;
    e.x = Eigen::VectorXd::Constant(4, 0.1 * k + 1e-17);
    e.gradient = k != 1;
    e.result.status = k != 2 ? EvaluationStatus::ok : EvaluationStatus::state_failed;
    e.result.J = 1.0 / 3.0 + k;
    e.result.gradient =
        e.gradient && k != 2 ? Eigen::VectorXd::Constant(4, -1.0 / 7.0) : Eigen::VectorXd();
    e.result.failure = k == 2 ? "newton failed" : "";
    e.seconds = 0.5 * k;
    w.append(e);
  }
  RunSnapshot s;
  s.evaluations = 3;
  s.iterations = 1;
  WarmStart ws;
  ws.m = Eigen::VectorXd::Constant(4, 0.25);
  ws.state.u = Eigen::VectorXd::LinSpaced(6, 0.0, 1.0);
  ws.state.m_qp = Eigen::MatrixXd::Constant(2, 3, -0.5);
  s.states.push_back(ws);
  w.write_states(s);
  return read_bytes(path);
}

TEST(RunLog, RoundTripsBitwise) {
  const std::string path = temp_path("format.bin");
  small_log(path);
  const RunLog log = read_run_log(path);
  EXPECT_EQ(log.fingerprint.at("scene"), "abc");
  ASSERT_EQ(log.evaluations.size(), 3u);
  EXPECT_TRUE(log.has_snapshot);
  for (int k = 0; k < 3; ++k) {
    const LoggedEvaluation& e = log.evaluations[k];
    EXPECT_EQ(e.x, Eigen::VectorXd::Constant(4, 0.1 * k + 1e-17));
    EXPECT_EQ(e.result.J, 1.0 / 3.0 + k);
    EXPECT_EQ(e.gradient, k != 1);
    EXPECT_EQ(e.result.status, k != 2 ? EvaluationStatus::ok : EvaluationStatus::state_failed);
    EXPECT_EQ(e.seconds, 0.5 * k);
  }
  EXPECT_EQ(log.evaluations[0].result.gradient, Eigen::VectorXd::Constant(4, -1.0 / 7.0));
  EXPECT_EQ(log.evaluations[2].result.failure, "newton failed");
  EXPECT_EQ(log.snapshot.states.at(0).state.m_qp, Eigen::MatrixXd::Constant(2, 3, -0.5));
  EXPECT_EQ(log.snapshot.states.at(0).state.u, Eigen::VectorXd::LinSpaced(6, 0.0, 1.0));
}

TEST(RunLog, DropsATornTailAndRefusesCorruption) {
  const std::string path = temp_path("torn.bin");
  const std::string bytes = small_log(path);
  // Cut inside the last evaluation record: it is dropped (the run was killed writing it).
  const RunLog torn = parse_run_log(bytes.substr(0, bytes.size() - 5), "torn");
  EXPECT_EQ(torn.evaluations.size(), 2u);
  // ... but then the states count more evaluations than the log has: refused.
  std::uint64_t run_id = 0;
  RunLog cut = torn;
  RunSnapshot states = parse_run_states(read_bytes(path + ".states"), "s", &run_id);
  expect_error<FileError>([&] { attach_states(cut, run_id, states, "s"); }, "do not match");
  // A flipped byte in a middle record is corruption, not a torn write.
  std::string bad = bytes;
  bad[40] ^= 0x10;
  expect_error<FileError>([&] { parse_run_log(bad, "bad.bin"); }, "bad.bin: corrupt record");
  expect_error<FileError>([&] { parse_run_log("not a log", "x.bin"); }, "not a softhd checkpoint");
  expect_error<FileError>([&] { read_run_log(::testing::TempDir()); }, "is a directory");
  // States of another run (another run id) are refused.
  RunLog other = parse_run_log(bytes, "log");
  expect_error<FileError>([&] { attach_states(other, run_id + 1, states, "s"); },
                          "belong to another run");
}

// States whose counts are impossible (1e12 evaluations for a log of 3, more iterations than
// evaluations, negative) are refused, checksum or not.
TEST(RunLog, RefusesInconsistentCounts) {
  const std::string path = temp_path("counts.bin");
  for (auto [evaluations, iterations] :
       {std::pair<std::int64_t, std::int64_t>{1000000000000, 1}, {3, 47}, {-1, 0}, {3, -1}}) {
    RunLogWriter w(path, {{"scene", "abc"}});
    LoggedEvaluation e;
    e.x = Eigen::VectorXd::Ones(2);
    for (int k = 0; k < 3; ++k) w.append(e);
    RunSnapshot s;
    s.evaluations = evaluations;
    s.iterations = iterations;
    w.write_states(s);
    expect_error<FileError>([&] { read_run_log(path); }, "evaluations");
  }
}

}  // namespace
}  // namespace softhd::test
