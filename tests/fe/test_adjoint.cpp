#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "fe_test_util.hpp"
#include "softhd/error.hpp"
#include "softhd/fe/adjoint.hpp"
#include "softhd/fe/newton.hpp"
#include "softhd/fe/state_solver.hpp"

using namespace softhd::fe;

namespace {

// J(u, m) = Σ_{tip nodes} w_n |u_n|² + (M/2)∫m² + (ε/2)∫|∇m|²: a smooth functional of u.
struct Functional {
  const Assembler& A;
  const ControlSpace& c;
  double M = 0.3, eps = 0.1;
  double value(const Eigen::VectorXd& u, const Eigen::VectorXd& m, Eigen::VectorXd* g_u) const {
    const int dim = A.mesh().dim;
    double J = c.regularisation(m, M, eps, nullptr);
    if (g_u) g_u->setZero(u.size());
    for (int n : A.mesh().face("x1")) {
      const double w = 1.0 + A.mesh().nodes(n, 1);
      J += w * u.segment(n * dim, dim).squaredNorm();
      if (g_u) g_u->segment(n * dim, dim) = 2.0 * w * u.segment(n * dim, dim);
    }
    return J;
  }
};

struct Case {
  int dim, order;
  ControlKind kind;
};

}  // namespace

// Taylor test: |J(m + h δm) − J(m) − h dJ·δm| falls as h² (observed order >= 1.9).
TEST(Adjoint, TaylorTestSecondOrder) {
  const std::vector<Case> cases = {{3, 1, ControlKind::kVertex},
                                   {3, 2, ControlKind::kVertex},
                                   {3, 2, ControlKind::kElement},
                                   {2, 2, ControlKind::kVertex},
                                   {2, 1, ControlKind::kElement}};
  for (const Case& k : cases) {
    const Eigen::Vector3d a0 =
        k.dim == 3 ? Eigen::Vector3d(1, 0.2, 0.1) : Eigen::Vector3d(1, 0.2, 0);
    const Assembler A(fe_test::box(k.dim, k.order, {3.0, 1.0, 0.4}, {4, 2, 2}),
                      fe_test::mooney_rivlin(), a0, {{"x0", {}}});
    const ControlSpace c(A.mesh(), A.geometry(), k.kind);
    const Functional F{A, c};
    NewtonOptions o;
    o.relative_tolerance = 1e-12;
    NewtonSolver newton(A, o);
    const Eigen::VectorXd m = -0.3 + fe_test::random_vector(c.size(), 0.2, 11).array();
    const Eigen::VectorXd dm = fe_test::random_vector(c.size(), 0.3, 12);
    State s0 = rest_state(A);
    ASSERT_TRUE(newton.solve(c.to_quadrature(m), &s0).converged());
    Eigen::VectorXd g_u, g_m;
    const double J0 = F.value(s0.u, m, &g_u);
    const Eigen::VectorXd lambda = solve_adjoint(A, newton, g_u);
    c.regularisation(m, F.M, F.eps, &g_m);
    const Eigen::VectorXd grad = g_m + control_gradient(A, c, s0.u, lambda);
    const double slope = grad.dot(dm);
    std::vector<double> rem;
    for (double h : {0.2, 0.1, 0.05, 0.025}) {
      State s = s0;
      ASSERT_TRUE(newton.solve(c.to_quadrature(m + h * dm), &s).converged());
      rem.push_back(std::abs(F.value(s.u, m + h * dm, nullptr) - J0 - h * slope));
    }
    for (size_t i = 1; i < rem.size(); ++i) {
      std::printf("%dD Q%d %s: h-halving %zu, observed order %.3f\n", k.dim, k.order,
                  k.kind == ControlKind::kVertex ? "vertex" : "element", i,
                  std::log2(rem[i - 1] / rem[i]));
      EXPECT_GT(std::log2(rem[i - 1] / rem[i]), 1.9)
          << k.dim << "D Q" << k.order << " remainders " << rem[i - 1] << " " << rem[i];
    }
    // The first-order term dominates the remainder, so a wrong sign or scale of the
    // gradient would show as order 1.
    EXPECT_GT(0.025 * std::abs(slope), 5.0 * rem.back());
  }
}

TEST(Adjoint, NoConvergedStateIsAnError) {
  const Assembler A(fe_test::box(3, 1, {1.0, 1.0, 1.0}, {1, 1, 1}), fe_test::mooney_rivlin(),
                    Eigen::Vector3d::UnitX(), {{"x0", {}}});
  NewtonSolver newton(A);
  EXPECT_THROW(solve_adjoint(A, newton, Eigen::VectorXd::Zero(A.dofs().num_dofs)),
               softhd::InvalidArgument);
}

// The optimiser's view: StateSolver with warm starts between solves and the adjoint
// gradient of J = |u|² over the free end; Taylor remainders fall as h².
TEST(StateSolver, WarmStartedSolvesAndGradientPassTaylorTest) {
  Assembler A(fe_test::box(3, 2, {3.0, 1.0, 0.3}, {4, 1, 1}), fe_test::mooney_rivlin(),
              Eigen::Vector3d::UnitX(), {{"x0", {}}});
  NewtonOptions o;
  o.relative_tolerance = 1e-12;
  StateSolver S(std::move(A), ControlKind::kVertex, o);
  const Eigen::MatrixXd P = S.control().positions(S.assembler().mesh());
  const Eigen::VectorXd m = -0.5 * P.col(2) / 0.3;
  const Eigen::VectorXd dm = fe_test::random_vector(m.size(), 0.2, 21);
  auto J = [&](Eigen::VectorXd* g) {
    const Eigen::VectorXd& u = S.displacement();
    if (g) g->setZero(u.size());
    double v = 0.0;
    for (int n : S.assembler().mesh().face("x1")) {
      v += u.segment(3 * n, 3).squaredNorm();
      if (g) g->segment(3 * n, 3) = 2.0 * u.segment(3 * n, 3);
    }
    return v;
  };
  ASSERT_TRUE(S.solve(m).converged());
  Eigen::VectorXd g;
  const double J0 = J(&g);
  const double slope = S.gradient(g).dot(dm);
  std::vector<double> rem;
  for (double h : {0.2, 0.1, 0.05}) {
    ASSERT_TRUE(S.solve(m + h * dm).converged());  // warm start from the previous state
    rem.push_back(std::abs(J(nullptr) - J0 - h * slope));
  }
  for (size_t i = 1; i < rem.size(); ++i) EXPECT_GT(std::log2(rem[i - 1] / rem[i]), 1.9);
  EXPECT_GT(0.05 * std::abs(slope), 5.0 * rem.back());
}
