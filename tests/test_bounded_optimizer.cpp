// The NLopt driver on problems whose bounded minimisers are known independently.

#include <gtest/gtest.h>

#include <cmath>

#include "expect_error.hpp"
#include "softhd/control/bounded_optimizer.hpp"
#include "softhd/error.hpp"

namespace softhd {
namespace {

const Algorithm kAll[] = {Algorithm::mma, Algorithm::ccsaq, Algorithm::lbfgs, Algorithm::slsqp};

// f(x) = Σ w_k (x_k − c_k)², on bounds of the magnitude of fiber tensions (1e5): the
// bounded minimiser is the projection of c onto the box.
TEST(BoundedOptimizer, QuadraticReachesTheProjectedMinimiser) {
  const int n = 6;
  Eigen::VectorXd c(n), w(n), lo(n), hi(n);
  c << -2e4, -1.5e5, 3e4, -7e4, -1e5, 5e4;
  w << 1, 2, 0.5, 3, 1, 1;
  lo.setConstant(-1e5);
  hi.setZero();
  const Eigen::VectorXd expected = c.cwiseMax(lo).cwiseMin(hi);
  const BoundedObjective f = [&](const Eigen::VectorXd& x, double& v, Eigen::VectorXd* g) {
    v = (w.array() * (x - c).array().square()).sum();
    if (g) *g = 2 * w.cwiseProduct(x - c);
    return true;
  };
  for (Algorithm a : kAll) {
    BoundedOptimizerOptions o;
    o.algorithm = a;
    o.relative_change = 1e-14;
    o.max_iterations = 500;
    const BoundedOptimizerSummary s = minimise(f, Eigen::VectorXd::Constant(n, -5e4), lo, hi, o);
    EXPECT_LE((s.x - expected).cwiseAbs().maxCoeff(), 1.0) << to_string(a) << ": " << s.termination;
    EXPECT_LT(s.final_value, s.initial_value);
    ASSERT_FALSE(s.history.empty());
    EXPECT_EQ(s.history.back().value, s.final_value);
    EXPECT_EQ(static_cast<int>(s.history.size()), s.iterations);
  }
}

// Rosenbrock on x ∈ [−2, 2], y ∈ [−1, 0.5]: the free minimiser (1, 1) is cut off, so the
// minimiser lies on y = 0.5 where f = (1 − x)² + 100 (0.5 − x²)², found here by
// bisection on its derivative (an independent 1-D solve).
TEST(BoundedOptimizer, RosenbrockOnAnActiveBound) {
  auto df = [](double x) { return -2 * (1 - x) - 400 * x * (0.5 - x * x); };
  double a = 0.5, b = 1.0;  // df(0.5) < 0 < df(1)
  for (int k = 0; k < 200; ++k) (df(0.5 * (a + b)) < 0 ? a : b) = 0.5 * (a + b);
  const Eigen::Vector2d expected(0.5 * (a + b), 0.5);
  const BoundedObjective f = [](const Eigen::VectorXd& x, double& v, Eigen::VectorXd* g) {
    v = std::pow(1 - x[0], 2) + 100 * std::pow(x[1] - x[0] * x[0], 2);
    if (g) {
      g->resize(2);
      (*g)[0] = -2 * (1 - x[0]) - 400 * x[0] * (x[1] - x[0] * x[0]);
      (*g)[1] = 200 * (x[1] - x[0] * x[0]);
    }
    return true;
  };
  for (Algorithm alg : kAll) {
    BoundedOptimizerOptions o;
    o.algorithm = alg;
    o.relative_change = 1e-15;
    o.max_iterations = 2000;
    o.max_evaluations = 5000;
    const BoundedOptimizerSummary s = minimise(f, Eigen::Vector2d(-1.5, -0.5),
                                               Eigen::Vector2d(-2, -1), Eigen::Vector2d(2, 0.5), o);
    EXPECT_LE((s.x - expected).norm(), 1e-4) << to_string(alg) << ": " << s.termination;
    EXPECT_LE(s.history.back().projected_gradient_norm, 1e-3) << to_string(alg);
  }
}

// Evaluations fail beyond x = −0.3 (as a state solve may fail for large tensions) while
// the minimiser is at −0.5: the run must end cleanly, inside the region that works.
TEST(BoundedOptimizer, FailedEvaluationsAreRejectedNotFatal) {
  int failures = 0;
  const BoundedObjective f = [&](const Eigen::VectorXd& x, double& v, Eigen::VectorXd* g) {
    if (x[0] < -0.3) {
      ++failures;
      return false;
    }
    v = (x[0] + 0.5) * (x[0] + 0.5);
    if (g) *g = Eigen::VectorXd::Constant(1, 2 * (x[0] + 0.5));
    return true;
  };
  for (Algorithm a : kAll) {
    failures = 0;
    BoundedOptimizerOptions o;
    o.algorithm = a;
    o.max_evaluations = 200;
    const BoundedOptimizerSummary s = minimise(
        f, Eigen::VectorXd::Zero(1), Eigen::VectorXd::Constant(1, -1), Eigen::VectorXd::Zero(1), o);
    EXPECT_TRUE(std::isfinite(s.final_value)) << to_string(a);
    EXPECT_GE(s.x[0], -0.3) << to_string(a);
    EXPECT_LT(s.final_value, s.initial_value) << to_string(a);
    EXPECT_EQ(s.failed_evaluations, failures) << to_string(a);
    EXPECT_FALSE(s.termination.empty());
  }
}

// With a move limit every evaluated point lies within δ (u − l) of the best point known
// when it was asked for, and the bounded minimiser is still reached.
// |x − c|², recording per variable the largest distance of an evaluated point from the best
// point evaluated before it (the start, 0, counts as the first best point).
struct StepWatchingQuadratic {
  explicit StepWatchingQuadratic(const Eigen::VectorXd& centre)
      : c(centre),
        best(Eigen::VectorXd::Zero(centre.size())),
        worst(Eigen::VectorXd::Zero(centre.size())) {}
  BoundedObjective objective() {
    return [this](const Eigen::VectorXd& x, double& v, Eigen::VectorXd* g) {
      worst = worst.cwiseMax((x - best).cwiseAbs());
      v = (x - c).squaredNorm();
      if (g) *g = 2 * (x - c);
      if (v < best_f) {
        best_f = v;
        best = x;
      }
      return true;
    };
  }
  Eigen::VectorXd c, best, worst;
  double best_f = INFINITY;
};

TEST(BoundedOptimizer, MoveLimitBoundsEveryStepAndStillConverges) {
  const int n = 5;
  Eigen::VectorXd c(n), lo = Eigen::VectorXd::Constant(n, -1e5), hi = Eigen::VectorXd::Zero(n);
  c << -2e4, -1.5e5, 3e4, -7e4, -9e4;
  const Eigen::VectorXd expected = c.cwiseMax(lo).cwiseMin(hi);
  const double delta = 0.05;
  for (Algorithm a : kAll) {
    StepWatchingQuadratic q(c);
    const BoundedObjective f = q.objective();
    BoundedOptimizerOptions o;
    o.algorithm = a;
    o.move_limit = delta;
    o.relative_change = 1e-14;
    o.max_iterations = 1000;
    o.max_evaluations = 2000;
    const BoundedOptimizerSummary s = minimise(f, Eigen::VectorXd::Zero(n), lo, hi, o);
    EXPECT_LE(q.worst.maxCoeff(), delta * 1e5 * (1 + 1e-12))
        << to_string(a) << ": " << s.termination << " its " << s.iterations;
    EXPECT_LE((s.x - expected).cwiseAbs().maxCoeff(), 1.0) << to_string(a) << ": " << s.termination;
  }
}

// A per-variable move scale: every step of variable k stays within its own δ·s_k·(u_k − l_k)
// of the best point (the slow ones at a quarter of the others), and the run still converges.
TEST(BoundedOptimizer, MoveScaleBoundsEachVariablesSteps) {
  const int n = 4;
  Eigen::VectorXd c(n), lo = Eigen::VectorXd::Constant(n, -1.0), hi = Eigen::VectorXd::Ones(n);
  c << 0.6, -0.7, 0.5, -0.4;
  Eigen::VectorXd scale(n);
  scale << 1.0, 1.0, 0.25, 0.25;
  const double delta = 0.1;
  StepWatchingQuadratic q(c);
  const BoundedObjective f = q.objective();
  const Eigen::VectorXd& worst = q.worst;
  BoundedOptimizerOptions o;
  o.move_limit = delta;
  o.move_scale = scale;
  o.relative_change = 1e-14;
  o.max_iterations = 1000;
  o.max_evaluations = 2000;
  const BoundedOptimizerSummary s = minimise(f, Eigen::VectorXd::Zero(n), lo, hi, o);
  for (int k = 0; k < n; ++k)
    EXPECT_LE(worst[k], delta * scale[k] * 2.0 * (1 + 1e-12)) << "variable " << k;
  EXPECT_GT(worst[0], delta * 0.25 * 2.0);  // the fast ones did use their larger box
  EXPECT_LE((s.x - c).cwiseAbs().maxCoeff(), 1e-4) << s.termination;
  o.move_scale = Eigen::VectorXd::Constant(n, 0.0);
  EXPECT_THROW(minimise(f, Eigen::VectorXd::Zero(n), lo, hi, o), InvalidArgument);
  o.move_scale = Eigen::VectorXd::Ones(n - 1);
  EXPECT_THROW(minimise(f, Eigen::VectorXd::Zero(n), lo, hi, o), InvalidArgument);
}

TEST(BoundedOptimizer, StopsOnIterationsTargetAndFailedStart) {
  // Σ (x_k − 1/4)⁴ + 1: MMA approaches the minimiser without reaching it, so every
  // iteration improves (from a start symmetric to the box, its first step lands exactly on
  // the minimiser of a function symmetric about the box centre, and then none improves).
  const BoundedObjective f = [](const Eigen::VectorXd& x, double& v, Eigen::VectorXd* g) {
    v = (x.array() - 0.25).pow(4).sum() + 1.0;
    if (g) *g = 4 * (x.array() - 0.25).cube().matrix();
    return true;
  };
  const Eigen::VectorXd lo = Eigen::VectorXd::Constant(3, -1), hi = Eigen::VectorXd::Constant(3, 1);
  const Eigen::VectorXd x0 = Eigen::VectorXd::Constant(3, 0.9);
  BoundedOptimizerOptions o;
  o.max_iterations = 2;
  o.relative_change = 0.0;
  BoundedOptimizerSummary s = minimise(f, x0, lo, hi, o);
  EXPECT_EQ(s.iterations, 2);
  EXPECT_EQ(s.termination, "the iteration limit was reached");
  EXPECT_EQ(s.status, OptimizerStatus::iteration_limit);
  EXPECT_FALSE(s.converged());
  o.max_iterations = 100;
  o.target_value = 1.001;
  s = minimise(f, x0, lo, hi, o);
  EXPECT_LE(s.final_value, 1.001);
  EXPECT_TRUE(s.converged());
  EXPECT_EQ(s.termination, "J reached the target value");
  EXPECT_EQ(s.status, OptimizerStatus::target_value);
  const BoundedObjective broken = [](const Eigen::VectorXd&, double&, Eigen::VectorXd*) {
    return false;
  };
  s = minimise(broken, x0, lo, hi);
  EXPECT_EQ(s.termination, "the evaluation at the starting point failed");
  EXPECT_EQ(s.status, OptimizerStatus::start_failed);
  EXPECT_EQ(to_string(s.status), "start_failed");
  EXPECT_FALSE(s.converged());
}

// A move limit below kCertifyingMoveLimit: its steps are too short for a small change of J, or
// none, to tell a minimum. A quadratic (minimum 0 at c) stopped on the relative change far from
// c, and the same quadratic rounded to 1e-4 (a noisy J, as the tree method's) stopped without
// progress at its start, are status move_limit, not converged; with the default-sized move limit
// both converge to c.
TEST(BoundedOptimizer, TinyMoveLimitIsNotConvergence) {
  const Eigen::Vector3d c(0.5, -0.3, 0.2);
  auto quadratic = [&](double quantum) -> BoundedObjective {
    return [&c, quantum](const Eigen::VectorXd& x, double& v, Eigen::VectorXd* g) {
      v = (x - c).squaredNorm();
      if (quantum > 0.0) v = quantum * std::round(v / quantum);
      if (g) *g = 2.0 * (x - c);
      return true;
    };
  };
  const Eigen::VectorXd lo = Eigen::VectorXd::Constant(3, -1), hi = Eigen::VectorXd::Ones(3);
  const Eigen::VectorXd x0 = Eigen::VectorXd::Zero(3);
  BoundedOptimizerOptions o;
  o.relative_change = 1e-3;
  o.max_iterations = 500;
  o.max_evaluations = 5000;
  for (double quantum : {0.0, 1e-4}) {
    o.move_limit = 1e-6;
    BoundedOptimizerSummary s = minimise(quadratic(quantum), x0, lo, hi, o);
    EXPECT_EQ(s.status, OptimizerStatus::move_limit) << s.termination;
    EXPECT_FALSE(s.converged());
    EXPECT_GT(s.final_value, 0.3);  // still near J(0) = 0.38
    EXPECT_NE(s.termination.find("(move limit 1e-06, below 0.001: steps too short"),
              std::string::npos)
        << s.termination;
    EXPECT_EQ(to_string(s.status), "move_limit");
    o.move_limit = 0.1;
    s = minimise(quadratic(quantum), x0, lo, hi, o);
    EXPECT_TRUE(s.converged()) << s.termination;
    EXPECT_LT((s.x - c).norm(), 0.02) << s.termination;
  }
}

// An iteration observer that throws StopRequest ends the run after that iteration, with
// the best point so far and its own termination.
TEST(BoundedOptimizer, ObserverCanStopTheRun) {
  const BoundedObjective f = [](const Eigen::VectorXd& x, double& v, Eigen::VectorXd* g) {
    v = (x.array() - 0.25).pow(4).sum() + 1.0;
    if (g) *g = 4 * (x.array() - 0.25).cube().matrix();
    return true;
  };
  const Eigen::VectorXd lo = Eigen::VectorXd::Constant(3, -1), hi = Eigen::VectorXd::Constant(3, 1);
  BoundedOptimizerOptions o;
  o.relative_change = 0.0;
  int calls = 0;
  Eigen::VectorXd seen;
  const BoundedOptimizerSummary s =
      minimise(f, Eigen::VectorXd::Constant(3, 0.9), lo, hi, o,
               [&](const IterationRecord& rec, const Eigen::VectorXd& x) {
                 ++calls;
                 seen = x;
                 if (rec.iteration == 3) throw StopRequest{};
               });
  EXPECT_EQ(calls, 3);
  EXPECT_EQ(s.iterations, 3);
  EXPECT_EQ(s.termination, "stopped by the caller");
  EXPECT_EQ(s.status, OptimizerStatus::stopped);
  EXPECT_EQ(s.BriefReport().rfind("stopped (stopped by the caller): 3 iterations", 0), 0u)
      << s.BriefReport();
  EXPECT_FALSE(s.converged());
  EXPECT_EQ(s.x, seen);
}

TEST(BoundedOptimizer, RejectsInconsistentInput) {
  const BoundedObjective f = [](const Eigen::VectorXd& x, double& v, Eigen::VectorXd* g) {
    v = x.squaredNorm();
    if (g) *g = 2 * x;
    return true;
  };
  const Eigen::VectorXd lo = Eigen::VectorXd::Zero(2), hi = Eigen::VectorXd::Ones(2);
  EXPECT_THROW(minimise(f, Eigen::Vector2d(0.5, 2.0), lo, hi), InvalidArgument);
  EXPECT_THROW(minimise(f, Eigen::Vector2d(0.5, 0.5), hi, lo), InvalidArgument);
  EXPECT_THROW(minimise(f, Eigen::VectorXd::Zero(3), lo, hi), InvalidArgument);
  BoundedOptimizerOptions o;
  o.max_iterations = 0;
  EXPECT_THROW(minimise(f, Eigen::Vector2d(0.5, 0.5), lo, hi, o), InvalidArgument);
  EXPECT_THROW(algorithm_from_string("trust-region"), InvalidArgument);
  try {
    minimise(f, Eigen::Vector2d(0.5, 2.0), lo, hi);
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("start of variable 1 (2) is outside its bounds"),
              std::string::npos)
        << e.what();
  }
}

// gradient_tolerance stops every algorithm at the first iteration whose projected gradient
// norm (scaled variables and value) is within it, as converged.
TEST(BoundedOptimizer, StopsOnTheProjectedGradient) {
  const Eigen::Vector2d c(0.3, 2.0), lo(-1, -1), hi(1, 1);  // c_1 beyond its bound
  const BoundedObjective f = [&](const Eigen::VectorXd& x, double& v, Eigen::VectorXd* g) {
    v = 1.0 + (x - c).squaredNorm();
    if (g) *g = 2 * (x - c);
    return true;
  };
  for (Algorithm a : kAll) {
    BoundedOptimizerOptions o;
    o.algorithm = a;
    o.relative_change = 0.0;
    o.gradient_tolerance = 1e-3;
    const BoundedOptimizerSummary s = minimise(f, Eigen::Vector2d(-0.9, -0.9), lo, hi, o);
    EXPECT_EQ(s.status, OptimizerStatus::gradient_tolerance)
        << to_string(a) << ": " << s.termination;
    EXPECT_TRUE(s.converged());
    ASSERT_FALSE(s.history.empty());
    EXPECT_LE(s.history.back().projected_gradient_norm, 1e-3);
    for (std::size_t k = 0; k + 1 < s.history.size(); ++k)
      EXPECT_GT(s.history[k].projected_gradient_norm, 1e-3);
  }
}

// The optimiser owns its objective's exceptions: one thrown inside NLopt (which would turn it
// into "nlopt failure") ends minimise() with that exception, whatever its type, for every
// algorithm and with or without move limits; the objective is not called again after it,
// and an exception of the iteration observer is rethrown the same way.
TEST(BoundedOptimizer, RethrowsTheObjectivesExceptions) {
  struct Custom {
    int evaluation;
  };
  const Eigen::VectorXd lo = Eigen::VectorXd::Constant(3, -1), hi = Eigen::VectorXd::Constant(3, 1);
  const Eigen::VectorXd x0 = Eigen::VectorXd::Constant(3, 0.9);
  for (Algorithm a : kAll) {
    for (double move_limit : {0.0, 0.1}) {
      SCOPED_TRACE(to_string(a) + " move limit " + std::to_string(move_limit));
      BoundedOptimizerOptions o;
      o.algorithm = a;
      o.move_limit = move_limit;
      o.relative_change = 0.0;
      int calls = 0;
      const auto throwing_at = [&](int k, bool custom) {
        return [&calls, k, custom](const Eigen::VectorXd& x, double& v, Eigen::VectorXd* g) {
          if (++calls == k) {
            if (custom) throw Custom{k};
            throw NumericalError("evaluation " + std::to_string(k) + " failed");
          }
          v = (x.array() - 0.25).pow(4).sum() + 1.0;
          if (g) *g = 4 * (x.array() - 0.25).cube().matrix();
          return true;
        };
      };
      calls = 0;
      test::expect_error<NumericalError>([&] { minimise(throwing_at(4, false), x0, lo, hi, o); },
                                         "evaluation 4 failed");
      EXPECT_EQ(calls, 4);
      calls = 0;
      try {
        minimise(throwing_at(3, true), x0, lo, hi, o);
        ADD_FAILURE() << "no exception";
      } catch (const Custom& c) {
        EXPECT_EQ(c.evaluation, 3);
      }
      EXPECT_EQ(calls, 3);
      // The first evaluation (outside NLopt) throws through as well.
      calls = 0;
      test::expect_error<NumericalError>([&] { minimise(throwing_at(1, false), x0, lo, hi, o); },
                                         "evaluation 1 failed");
      calls = 0;
      int observed = 0;
      test::expect_error<FileError>(
          [&] {
            minimise(throwing_at(0, false), x0, lo, hi, o,
                     [&](const IterationRecord& rec, const Eigen::VectorXd&) {
                       ++observed;
                       if (rec.iteration == 2) throw FileError("cannot write iteration 2");
                     });
          },
          "cannot write iteration 2");
      EXPECT_EQ(observed, 2);
    }
  }
}

}  // namespace
}  // namespace softhd
