// The trust-region Newton–CG (Algorithm::newton, ROL's Lin–Moré) on problems whose bounded
// minimisers are known independently.

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <thread>

#include "expect_error.hpp"
#include "softhd/control/bounded_optimizer.hpp"
#include "softhd/error.hpp"

namespace softhd {
namespace {

// Extended Rosenbrock: pairs (x, y) = (z_2j, z_2j+1), f = Σ_j 100 (y − x²)² + (1 − x)².
// The pairs are independent, so the bounded minimiser is that of each pair's 2-D problem.
struct Rosenbrock {
  Eigen::VectorXd lower, upper;
  int evaluations = 0;
  int outside = 0;  // evaluated or Hessian points outside the bounds

  void check_bounds(const Eigen::VectorXd& z) {
    if (!((z.array() >= lower.array()).all() && (z.array() <= upper.array()).all())) ++outside;
  }
  static double value(const Eigen::VectorXd& z, Eigen::VectorXd* g) {
    double f = 0.0;
    if (g) g->setZero(z.size());
    for (Eigen::Index j = 0; j + 1 < z.size(); j += 2) {
      const double x = z[j], y = z[j + 1], r = y - x * x;
      f += 100 * r * r + (1 - x) * (1 - x);
      if (g) {
        (*g)[j] = -400 * x * r - 2 * (1 - x);
        (*g)[j + 1] = 200 * r;
      }
    }
    return f;
  }
  // ∇²f per pair: [[1200 x² − 400 y + 2, −400 x], [−400 x, 200]].
  static Eigen::VectorXd hess_vec(const Eigen::VectorXd& z, const Eigen::VectorXd& v) {
    Eigen::VectorXd h(z.size());
    for (Eigen::Index j = 0; j + 1 < z.size(); j += 2) {
      const double x = z[j], y = z[j + 1];
      h[j] = (1200 * x * x - 400 * y + 2) * v[j] - 400 * x * v[j + 1];
      h[j + 1] = -400 * x * v[j] + 200 * v[j + 1];
    }
    return h;
  }
  BoundedObjective objective() {
    return [this](const Eigen::VectorXd& z, double& f, Eigen::VectorXd* g) {
      ++evaluations;
      check_bounds(z);
      f = value(z, g);
      return true;
    };
  }
  BoundedHessVec hessian() {
    return [this](const Eigen::VectorXd& z, const Eigen::VectorXd& v, Eigen::VectorXd* hv) {
      check_bounds(z);
      *hv = hess_vec(z, v);
      return true;
    };
  }
};

// The minimiser of 100 (y − x²)² + (1 − x)² on y ≤ 0.5 (the free one, (1, 1), is cut off): on
// y = 0.5, where (1 − x)² + 100 (0.5 − x²)² is least, found by bisection on its derivative.
double constrained_x() {
  auto df = [](double x) { return -2 * (1 - x) - 400 * x * (0.5 - x * x); };
  double a = 0.5, b = 1.0;  // df(0.5) < 0 < df(1)
  for (int k = 0; k < 200; ++k) (df(0.5 * (a + b)) < 0 ? a : b) = 0.5 * (a + b);
  return 0.5 * (a + b);
}

// n/2 pairs on x ∈ [−2, 2], y ∈ [−1, 2]; every third pair has y ≤ 0.5 (active at its minimiser).
Rosenbrock rosenbrock_problem(int n, Eigen::VectorXd* x0, Eigen::VectorXd* expected) {
  Rosenbrock r;
  r.lower.resize(n);
  r.upper.resize(n);
  x0->resize(n);
  expected->resize(n);
  const double xc = constrained_x();
  for (int j = 0; 2 * j + 1 < n; ++j) {
    const bool cut = j % 3 == 0;
    r.lower[2 * j] = -2;
    r.upper[2 * j] = 2;
    r.lower[2 * j + 1] = -1;
    r.upper[2 * j + 1] = cut ? 0.5 : 2;
    (*x0)[2 * j] = -1.2 + 0.1 * (j % 4);
    (*x0)[2 * j + 1] = cut ? 0.5 : 1.0;
    (*expected)[2 * j] = cut ? xc : 1.0;
    (*expected)[2 * j + 1] = cut ? 0.5 : 1.0;
  }
  return r;
}

BoundedOptimizerOptions newton_options() {
  BoundedOptimizerOptions o;
  o.algorithm = Algorithm::newton;
  o.relative_change = 0.0;  // off: the gradient tolerance decides
  o.gradient_tolerance = 1e-10;
  o.max_iterations = 200;
  return o;
}

// 1 000 variables, a third of the pairs on an active bound: the minimiser found, KKT at it
// (projected gradient ≈ 0, the bound active), quadratic convergence at the end, and every point
// ROL asked about inside the bounds.
TEST(NewtonOptimizer, BoundedRosenbrockConvergesQuadratically) {
  Eigen::VectorXd x0, expected;
  Rosenbrock r = rosenbrock_problem(1000, &x0, &expected);
  const BoundedOptimizerSummary s =
      minimise(r.objective(), r.hessian(), x0, r.lower, r.upper, newton_options());
  ASSERT_EQ(s.status, OptimizerStatus::gradient_tolerance) << s.termination;
  EXPECT_TRUE(s.converged());
  EXPECT_LE((s.x - expected).cwiseAbs().maxCoeff(), 1e-8);
  Eigen::VectorXd g;
  Rosenbrock::value(s.x, &g);
  EXPECT_LE(projected_gradient_norm(s.x, g, r.lower, r.upper), 1e-8);
  const double xc = constrained_x();
  for (Eigen::Index j = 0; j + 1 < s.x.size(); j += 6) {  // the cut pairs: y on its bound
    EXPECT_EQ(s.x[j + 1], 0.5);
    // ∂f/∂y = 200 (0.5 − x²) < 0 there: the bound holds y back (a positive multiplier).
    EXPECT_NEAR(g[j + 1], 200 * (0.5 - xc * xc), 1e-6);
    EXPECT_LT(g[j + 1], -0.1);
  }
  EXPECT_EQ(r.outside, 0);
  EXPECT_EQ(s.evaluations, r.evaluations);
  EXPECT_LE(s.iterations, 40);
  ASSERT_GE(s.history.size(), 3u);
  // Quadratic convergence: once the projected gradient p is small (the active set settled),
  // each step squares it up to a constant, p_{k+1} ≤ 100 p_k² (a linear rate 0.1 would give
  // 10⁻⁵ from 10⁻⁴, not ≤ 10⁻⁶).
  int quadratic_steps = 0;
  for (std::size_t k = 1; k < s.history.size(); ++k) {
    const double p0 = s.history[k - 1].projected_gradient_norm;
    const double p1 = s.history[k].projected_gradient_norm;
    if (p0 <= 1e-4) {
      EXPECT_LE(p1, 100 * p0 * p0) << "iteration " << k + 1 << ": " << p0 << " → " << p1;
      ++quadratic_steps;
    }
  }
  EXPECT_GE(quadratic_steps, 2);
  int cg = 0;
  for (const IterationRecord& rec : s.history) {
    EXPECT_GT(rec.trust_radius, 0.0);
    EXPECT_GT(rec.cauchy_step, 0.0);
    cg += rec.cg_iterations;
  }
  EXPECT_GT(s.hessian_products, 0);
  // Each CG iteration asks for a product, computed or answered from the span.
  EXPECT_GE(s.hessian_products + s.hessian_products_reused, cg);
}

// The products at one point span at most n dimensions, and each further one asked for there is
// answered from them (ProductSpan). In one dimension every vector is a multiple of the first:
// on f(x) = x⁴ − 3x² + x (f'' = 12x² − 6, negative curvature near 0) from x = 0.2, started with
// a radius far too large (rejected steps, each a new Cauchy search and CG at the same point),
// every accepted iteration has computed exactly one product, and the run ends at a minimiser
// (f' = 0, f'' > 0). Without the span, a step's Cauchy search, CG iteration and projected
// search ask for at least 3: the reused products show they were asked.
TEST(NewtonOptimizer, ProductsInTheSpanOfThoseAtThePointAreNotRecomputed) {
  const BoundedObjective f = [](const Eigen::VectorXd& x, double& v, Eigen::VectorXd* g) {
    const double t = x[0];
    v = t * t * t * t - 3 * t * t + t;
    if (g) *g = Eigen::VectorXd::Constant(1, 4 * t * t * t - 6 * t + 1);
    return true;
  };
  const BoundedHessVec h = [](const Eigen::VectorXd& x, const Eigen::VectorXd& v,
                              Eigen::VectorXd* hv) {
    *hv = (12 * x[0] * x[0] - 6) * v;
    return true;
  };
  BoundedOptimizerOptions o = newton_options();
  o.trust_region.initial_radius = 10.0;
  const BoundedOptimizerSummary s =
      minimise(f, h, Eigen::VectorXd::Constant(1, 0.2), Eigen::VectorXd::Constant(1, -3.0),
               Eigen::VectorXd::Constant(1, 3.0), o);
  ASSERT_EQ(s.status, OptimizerStatus::gradient_tolerance) << s.termination;
  const double t = s.x[0];
  EXPECT_LE(std::fabs(4 * t * t * t - 6 * t + 1), 1e-8);
  EXPECT_GT(12 * t * t - 6, 0.0);
  int rejected = 0;
  for (std::size_t k = 0; k < s.history.size(); ++k) {
    EXPECT_EQ(s.history[k].hessian_products, 1) << "iteration " << k + 1;
    rejected += s.history[k].evaluation - (k ? s.history[k - 1].evaluation : 1) - 1;
  }
  EXPECT_GT(rejected, 0) << "no rejected step: the start radius did not test the span";
  EXPECT_GE(s.hessian_products_reused, 2 * s.iterations) << "the bound above could not fail";
}

// A move limit bounds the trust radius: Δ ≤ move_limit ‖(u − l)/s‖₂ in z = x/s (s_k the least
// power of 2 ≥ max(|l_k|, |u_k|): 2, or 1 on the cut pairs' y) after every iteration, the run
// still converges to the minimiser, and without the limit the radius grows beyond it (the bound
// acts).
TEST(NewtonOptimizer, MoveLimitBoundsTheTrustRadius) {
  Eigen::VectorXd x0, expected;
  Rosenbrock r = rosenbrock_problem(100, &x0, &expected);
  Eigen::VectorXd s(x0.size());
  for (Eigen::Index k = 0; k < s.size(); ++k) {
    s[k] = 1.0;
    while (s[k] < std::max(std::fabs(r.lower[k]), std::fabs(r.upper[k]))) s[k] *= 2.0;
  }
  BoundedOptimizerOptions o = newton_options();
  o.move_limit = 0.02;
  const double radius_max = o.move_limit * (r.upper - r.lower).cwiseQuotient(s).norm();
  const BoundedOptimizerSummary bounded =
      minimise(r.objective(), r.hessian(), x0, r.lower, r.upper, o);
  ASSERT_TRUE(bounded.converged()) << bounded.termination;
  EXPECT_LE((bounded.x - expected).cwiseAbs().maxCoeff(), 1e-8);
  ASSERT_FALSE(bounded.history.empty());
  for (const IterationRecord& rec : bounded.history)
    EXPECT_LE(rec.trust_radius, radius_max * (1 + 1e-12)) << "iteration " << rec.iteration;
  const BoundedOptimizerSummary free =
      minimise(r.objective(), r.hessian(), x0, r.lower, r.upper, newton_options());
  ASSERT_TRUE(free.converged()) << free.termination;
  double largest = 0.0;
  for (const IterationRecord& rec : free.history) largest = std::max(largest, rec.trust_radius);
  EXPECT_GT(largest, 2 * radius_max);
}

// f = ½ (x − c)ᵀ A (x − c), A the 1-D Laplacian + I (an M-matrix), on [0, 1]: the bounded
// minimiser by projected Gauss–Seidel (which converges for M-matrices), an independent solve.
TEST(NewtonOptimizer, BoundedConvexQuadraticInFewIterations) {
  const int n = 60;
  Eigen::VectorXd c(n);
  for (int k = 0; k < n; ++k) c[k] = 1.5 * std::sin(0.3 * k);  // beyond both bounds in places
  const auto apply = [n](const Eigen::VectorXd& v) {
    Eigen::VectorXd a = 3.0 * v;
    a.head(n - 1) -= v.tail(n - 1);
    a.tail(n - 1) -= v.head(n - 1);
    return a;
  };
  Eigen::VectorXd expected = Eigen::VectorXd::Constant(n, 0.5);
  for (int sweep = 0; sweep < 2000; ++sweep) {
    for (int k = 0; k < n; ++k) {  // row k of A (x − c) = 0 for x_k, then projected
      double rhs = 3.0 * c[k];
      if (k > 0) rhs += expected[k - 1] - c[k - 1];
      if (k + 1 < n) rhs += expected[k + 1] - c[k + 1];
      expected[k] = std::clamp(rhs / 3.0, 0.0, 1.0);
    }
  }
  const BoundedObjective f = [&](const Eigen::VectorXd& x, double& v, Eigen::VectorXd* g) {
    const Eigen::VectorXd ax = apply(x - c);
    v = 0.5 * (x - c).dot(ax);
    if (g) *g = ax;
    return true;
  };
  const BoundedHessVec h = [&](const Eigen::VectorXd&, const Eigen::VectorXd& v,
                               Eigen::VectorXd* hv) {
    *hv = apply(v);
    return true;
  };
  const Eigen::VectorXd lo = Eigen::VectorXd::Zero(n), hi = Eigen::VectorXd::Ones(n);
  const BoundedOptimizerSummary s =
      minimise(f, h, Eigen::VectorXd::Constant(n, 0.5), lo, hi, newton_options());
  ASSERT_TRUE(s.converged()) << s.termination;
  EXPECT_LE((s.x - expected).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_LE(s.iterations, 12);
}

// An evaluation that fails (returns false) in the middle is a rejected step: the radius
// shrinks and the run still reaches the minimiser.
TEST(NewtonOptimizer, SurvivesFailedEvaluations) {
  Eigen::VectorXd x0, expected;
  Rosenbrock r = rosenbrock_problem(20, &x0, &expected);
  const BoundedObjective inner = r.objective();
  int calls = 0;
  const BoundedObjective f = [&](const Eigen::VectorXd& x, double& v, Eigen::VectorXd* g) {
    ++calls;
    if (calls == 4 || calls == 9) return false;
    return inner(x, v, g);
  };
  const BoundedOptimizerSummary s =
      minimise(f, r.hessian(), x0, r.lower, r.upper, newton_options());
  ASSERT_EQ(s.status, OptimizerStatus::gradient_tolerance) << s.termination;
  EXPECT_EQ(s.failed_evaluations, 2);
  EXPECT_EQ(s.evaluations, calls);
  EXPECT_LE((s.x - expected).cwiseAbs().maxCoeff(), 1e-8);
  // Accepted steps do not increase J, beyond ROL's round-off safeguard (100 ε max(1, |J̃|)).
  for (std::size_t k = 1; k < s.history.size(); ++k)
    EXPECT_LE(s.history[k].value, s.history[k - 1].value * (1 + 1e-13));
}

TEST(NewtonOptimizer, StopsOnLimitsAndRequests) {
  Eigen::VectorXd x0, expected;
  Rosenbrock r = rosenbrock_problem(20, &x0, &expected);
  BoundedOptimizerOptions o = newton_options();
  o.max_iterations = 3;
  BoundedOptimizerSummary s = minimise(r.objective(), r.hessian(), x0, r.lower, r.upper, o);
  EXPECT_EQ(s.status, OptimizerStatus::iteration_limit) << s.termination;
  EXPECT_EQ(s.iterations, 3);
  EXPECT_EQ(s.history.size(), 3u);
  EXPECT_FALSE(s.converged());

  o = newton_options();
  o.max_evaluations = 5;
  s = minimise(r.objective(), r.hessian(), x0, r.lower, r.upper, o);
  EXPECT_EQ(s.status, OptimizerStatus::evaluation_limit) << s.termination;
  EXPECT_EQ(s.evaluations, 5);

  o = newton_options();
  o.max_seconds = 0.02;
  const BoundedObjective inner = r.objective();
  const BoundedObjective slow = [&](const Eigen::VectorXd& x, double& v, Eigen::VectorXd* g) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    return inner(x, v, g);
  };
  s = minimise(slow, r.hessian(), x0, r.lower, r.upper, o);
  EXPECT_EQ(s.status, OptimizerStatus::time_limit) << s.termination;
  EXPECT_LT(s.seconds, 0.2);

  o = newton_options();
  o.target_value = 1.0;  // f(x0) ≈ 50
  s = minimise(r.objective(), r.hessian(), x0, r.lower, r.upper, o);
  EXPECT_EQ(s.status, OptimizerStatus::target_value) << s.termination;
  EXPECT_LE(s.final_value, 1.0);
  EXPECT_GT(s.history.at(s.history.size() - 2).value, 1.0);

  int seen = 0;
  const auto stop_at_2 = [&](const IterationRecord& rec, const Eigen::VectorXd&) {
    seen = rec.iteration;
    if (rec.iteration == 2) throw StopRequest{};
  };
  s = minimise(r.objective(), r.hessian(), x0, r.lower, r.upper, newton_options(), stop_at_2);
  EXPECT_EQ(s.status, OptimizerStatus::stopped) << s.termination;
  EXPECT_EQ(s.iterations, 2);
  EXPECT_EQ(seen, 2);

  // A failed start, and a failed Hessian-vector product (the run ends at the best point).
  const BoundedObjective fails = [](const Eigen::VectorXd&, double&, Eigen::VectorXd*) {
    return false;
  };
  s = minimise(fails, r.hessian(), x0, r.lower, r.upper, newton_options());
  EXPECT_EQ(s.status, OptimizerStatus::start_failed);
  int products = 0;
  const BoundedHessVec h = r.hessian();
  const BoundedHessVec fails_later = [&](const Eigen::VectorXd& x, const Eigen::VectorXd& v,
                                         Eigen::VectorXd* hv) {
    return ++products < 30 && h(x, v, hv);
  };
  s = minimise(r.objective(), fails_later, x0, r.lower, r.upper, newton_options());
  EXPECT_EQ(s.status, OptimizerStatus::hessian_failed) << s.termination;
  EXPECT_EQ(s.hessian_products, 30);
  ASSERT_FALSE(s.history.empty());
  EXPECT_EQ(s.final_value, s.history.back().value);
  double f_best = 0.0;
  Eigen::VectorXd unused;
  r.objective()(s.x, f_best, &unused);
  EXPECT_EQ(f_best, s.final_value);
}

// Exceptions of the objective, the product or the observer end minimise() with that exception.
TEST(NewtonOptimizer, RethrowsExceptions) {
  Eigen::VectorXd x0, expected;
  Rosenbrock r = rosenbrock_problem(6, &x0, &expected);
  const BoundedObjective inner = r.objective();
  int calls = 0;
  const BoundedObjective f = [&](const Eigen::VectorXd& x, double& v, Eigen::VectorXd* g) {
    if (++calls == 3) throw std::runtime_error("objective broke");
    return inner(x, v, g);
  };
  EXPECT_THROW(minimise(f, r.hessian(), x0, r.lower, r.upper, newton_options()),
               std::runtime_error);
  const BoundedHessVec h = [](const Eigen::VectorXd&, const Eigen::VectorXd&,
                              Eigen::VectorXd*) -> bool { throw FileError("product broke"); };
  EXPECT_THROW(minimise(r.objective(), h, x0, r.lower, r.upper, newton_options()), FileError);
  const auto observer = [](const IterationRecord&, const Eigen::VectorXd&) {
    throw InternalError("observer broke");
  };
  EXPECT_THROW(
      minimise(r.objective(), r.hessian(), x0, r.lower, r.upper, newton_options(), observer),
      InternalError);
}

TEST(NewtonOptimizer, RejectsMissingProductAndInvalidOptions) {
  EXPECT_EQ(algorithm_from_string("newton"), Algorithm::newton);
  EXPECT_EQ(to_string(Algorithm::newton), "newton");
  EXPECT_EQ(to_string(OptimizerStatus::gradient_tolerance), "gradient_tolerance");
  EXPECT_TRUE(is_converged(OptimizerStatus::gradient_tolerance));
  EXPECT_FALSE(is_converged(OptimizerStatus::hessian_failed));
  Eigen::VectorXd x0, expected;
  Rosenbrock r = rosenbrock_problem(4, &x0, &expected);
  test::expect_error<InvalidArgument>(
      [&] { minimise(r.objective(), x0, r.lower, r.upper, newton_options()); }, "hess_vec");
  BoundedOptimizerOptions o = newton_options();
  o.gradient_tolerance = -1;
  test::expect_error<InvalidArgument>([&] { o.validate(); }, "gradient_tolerance");
  o = newton_options();
  o.trust_region.cg_iterations = 0;
  test::expect_error<InvalidArgument>([&] { o.validate(); }, "trust_region.cg_iterations");
  o = newton_options();
  o.trust_region.cauchy_step = -1;
  test::expect_error<InvalidArgument>([&] { o.validate(); }, "trust_region.cauchy_step");
  o = newton_options();
  o.trust_region.initial_radius = -1;
  test::expect_error<InvalidArgument>([&] { o.validate(); }, "trust_region.initial_radius");
}

// A run stopped after k iterations and restarted from its x_k with that iteration's trust
// radius and Cauchy step, and the run's value scale, makes the uninterrupted run's iterates,
// bitwise, for every k. (Without the value scale they differ; the Cauchy step rarely matters,
// as its search usually ends on the same step length from either start.)
TEST(NewtonOptimizer, RestartFromAnIterationContinuesBitwise) {
  Eigen::VectorXd x0, expected;
  Rosenbrock r = rosenbrock_problem(1000, &x0, &expected);
  std::vector<Eigen::VectorXd> xs;
  const auto keep = [&](const IterationRecord&, const Eigen::VectorXd& x) { xs.push_back(x); };
  const BoundedOptimizerSummary full =
      minimise(r.objective(), r.hessian(), x0, r.lower, r.upper, newton_options(), keep);
  ASSERT_TRUE(full.converged()) << full.termination;
  ASSERT_GE(full.iterations, 8);
  ASSERT_EQ(static_cast<int>(xs.size()), full.iterations);
  for (int k = 1; k < full.iterations; ++k) {
    const IterationRecord& at = full.history[k - 1];
    BoundedOptimizerOptions o = newton_options();
    o.trust_region.initial_radius = at.trust_radius;
    o.trust_region.cauchy_step = at.cauchy_step;
    o.trust_region.value_scale = full.value_scale;
    std::vector<Eigen::VectorXd> again;
    const auto keep_again = [&](const IterationRecord&, const Eigen::VectorXd& x) {
      again.push_back(x);
    };
    const BoundedOptimizerSummary rest =
        minimise(r.objective(), r.hessian(), xs[k - 1], r.lower, r.upper, o, keep_again);
    ASSERT_EQ(rest.iterations, full.iterations - k) << "restart after " << k;
    for (std::size_t j = 0; j < again.size(); ++j) {
      EXPECT_TRUE(again[j] == xs[k + j]) << "restart after " << k << ", iteration " << k + j + 1;
      EXPECT_EQ(rest.history[j].value, full.history[k + j].value);
      EXPECT_EQ(rest.history[j].trust_radius, full.history[k + j].trust_radius);
      EXPECT_EQ(rest.history[j].cg_iterations, full.history[k + j].cg_iterations);
    }
    EXPECT_TRUE(rest.x == full.x);
  }
}

}  // namespace
}  // namespace softhd
