#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "fe_test_util.hpp"
#include "softhd/control/scene.hpp"
#include "softhd/error.hpp"
#include "softhd/fe/control.hpp"
#include "softhd/fe/forward.hpp"
#include "softhd/fe/newton.hpp"
#include "softhd/fe/state_equation.hpp"

using namespace softhd::fe;
using softhd::load_scene;
using softhd::parse_scene;
using softhd::Scene;

namespace {

constexpr double kA = 1.0, kB = 0.2, kC = 3.0;  // Mooney–Rivlin coefficients of the tests

// Independent 2-unknown Newton (finite-difference Jacobian) on g(x) = 0.
Eigen::Vector2d solve2(const std::function<Eigen::Vector2d(const Eigen::Vector2d&)>& g,
                       Eigen::Vector2d x) {
  for (int it = 0; it < 100 && g(x).norm() > 1e-14; ++it) {
    Eigen::Matrix2d Jg;
    for (int k = 0; k < 2; ++k) {
      Eigen::Vector2d h = Eigen::Vector2d::Zero();
      h[k] = 1e-7;
      Jg.col(k) = (g(x + h) - g(x - h)) / 2e-7;
    }
    x -= Jg.lu().solve(g(x));
  }
  return x;
}

// Stretches (λ1, λ2) of the stress-free homogeneous state under uniform m with fibers
// along X1, from ∂W/∂λ1 = ∂W/∂λ2 = 0 written directly from the energy of docs/formulation.md §3.2:
// 3D (λ2 = λ3): W = a(λ1² + 2λ2²) + b(λ2⁴ + 2λ1²λ2²) + c(J − 1)² − 2(a + 2b) ln J − ½ m λ1²,
// J = λ1 λ2²; plane strain (λ3 = 1): W = a(λ1² + λ2² + 1) + b(λ1² + λ2² + λ1²λ2²)
// + c(J − 1)² − 2(a + 2b) ln J − ½ m λ1², J = λ1 λ2.
Eigen::Vector2d homogeneous_stretches(int dim, double m) {
  const double a = kA, b = kB, c = kC;
  auto grad = [&](const Eigen::Vector2d& l) -> Eigen::Vector2d {
    const double l1 = l[0], l2 = l[1];
    if (dim == 3) {
      const double J = l1 * l2 * l2;
      return {2 * a * l1 + 4 * b * l1 * l2 * l2 + 2 * c * (J - 1) * l2 * l2 - 2 * (a + 2 * b) / l1 -
                  m * l1,
              4 * a * l2 + 4 * b * l2 * l2 * l2 + 4 * b * l1 * l1 * l2 + 4 * c * (J - 1) * l1 * l2 -
                  4 * (a + 2 * b) / l2};
    }
    const double J = l1 * l2;
    return {2 * a * l1 + 2 * b * l1 + 2 * b * l1 * l2 * l2 + 2 * c * (J - 1) * l2 -
                2 * (a + 2 * b) / l1 - m * l1,
            2 * a * l2 + 2 * b * l2 + 2 * b * l1 * l1 * l2 + 2 * c * (J - 1) * l1 -
                2 * (a + 2 * b) / l2};
  };
  return solve2(grad, Eigen::Vector2d(1.0, 1.0));
}

Eigen::MatrixXd uniform(const Assembler& A, double m) {
  return Eigen::MatrixXd::Constant(A.mesh().num_elements(), A.geometry().points_per_element(), m);
}

}  // namespace

// A block with symmetry constraints under uniform m deforms homogeneously.
TEST(Newton, HomogeneousBlockMatchesIndependentStretches) {
  for (int dim : {2, 3})
    for (int order : {1, 2})
      for (double m : {-1.2, 0.8}) {
        std::vector<DirichletConstraint> sym = {{"x0", {0}}, {"y0", {1}}};
        if (dim == 3) sym.push_back({"z0", {2}});
        const Assembler A(fe_test::box(dim, order, {1.0, 0.7, 0.5}, {2, 2, 2}),
                          fe_test::mooney_rivlin(), Eigen::Vector3d::UnitX(), sym);
        NewtonSolver newton(A);
        State s = rest_state(A);
        const NewtonSummary sum = newton.solve(uniform(A, m), &s);
        ASSERT_TRUE(sum.converged()) << sum.FullReport();
        const Eigen::Vector2d l = homogeneous_stretches(dim, m);
        double err = 0.0;
        for (Eigen::Index n = 0; n < A.mesh().num_nodes(); ++n)
          for (int k = 0; k < dim; ++k) {
            const double lk = k == 0 ? l[0] : l[1];
            err = std::max(err, std::abs(s.u[n * dim + k] - (lk - 1.0) * A.mesh().nodes(n, k)));
          }
        EXPECT_LT(err, 1e-9) << dim << "D Q" << order << " m " << m << " stretches "
                             << l.transpose();
        EXPECT_GT(std::abs(l[0] - 1.0), 0.05);  // a real deformation
      }
}

// The 2D plane-strain strip equals the 3D slab whose X3-displacements are constrained
// on both faces (the mid-plane nodes of Q2 stay free and must come out with u3 = 0).
TEST(Newton, PlaneStrainStripEqualsConstrainedSlab) {
  auto m_of = [](double X2) { return -0.8 * (X2 - 0.5) / 0.5; };  // bends in the plane
  const Assembler A2(fe_test::box(2, 2, {4.0, 1.0, 0.0}, {6, 2, 1}), fe_test::mooney_rivlin(),
                     Eigen::Vector3d::UnitX(), {{"x0", {}}});
  const Assembler A3(fe_test::box(3, 2, {4.0, 1.0, 0.5}, {6, 2, 1}), fe_test::mooney_rivlin(),
                     Eigen::Vector3d::UnitX(), {{"x0", {}}, {"z0", {2}}, {"z1", {2}}});
  auto m_qp = [&](const Assembler& A) {
    const Eigen::MatrixXd X = quadrature_points(A.mesh(), A.geometry());
    Eigen::MatrixXd m(A.mesh().num_elements(), A.geometry().points_per_element());
    for (Eigen::Index i = 0; i < X.rows(); ++i) m(i / m.cols(), i % m.cols()) = m_of(X(i, 1));
    return m;
  };
  NewtonSolver n2(A2), n3(A3);
  State s2 = rest_state(A2), s3 = rest_state(A3);
  ASSERT_TRUE(n2.solve(m_qp(A2), &s2).converged());
  ASSERT_TRUE(n3.solve(m_qp(A3), &s3).converged());
  const Eigen::Index N2 = A2.mesh().num_nodes();
  double err = 0.0, scale = 0.0, uz = 0.0;
  for (Eigen::Index n = 0; n < A3.mesh().num_nodes(); ++n) {
    const Eigen::Index n2 = n % N2;  // same (X1, X2) grid in every X3 layer
    ASSERT_NEAR(A3.mesh().nodes(n, 0), A2.mesh().nodes(n2, 0), 1e-14);
    for (int k = 0; k < 2; ++k) err = std::max(err, std::abs(s3.u[n * 3 + k] - s2.u[n2 * 2 + k]));
    scale = std::max(scale, s2.u.segment(n2 * 2, 2).norm());
    uz = std::max(uz, std::abs(s3.u[n * 3 + 2]));
  }
  EXPECT_GT(scale, 0.5);  // a large deformation
  EXPECT_LT(err, 1e-8 * scale);
  EXPECT_LT(uz, 1e-8 * scale);
}

// Warm start after a 5 % change of m reaches the same state as a cold start, faster.
TEST(Newton, WarmStartMatchesColdStart) {
  const Assembler A(fe_test::box(3, 2, {4.0, 1.0, 0.25}, {6, 1, 1}), fe_test::mooney_rivlin(),
                    Eigen::Vector3d::UnitX(), {{"x0", {}}});
  const Eigen::MatrixXd X = quadrature_points(A.mesh(), A.geometry());
  Eigen::MatrixXd m(A.mesh().num_elements(), A.geometry().points_per_element());
  for (Eigen::Index i = 0; i < X.rows(); ++i) m(i / m.cols(), i % m.cols()) = -0.4 * X(i, 2) / 0.25;
  NewtonSolver newton(A);
  State warm = rest_state(A);
  ASSERT_TRUE(newton.solve(m, &warm).converged());
  const NewtonSummary w = newton.solve(1.05 * m, &warm);
  State cold = rest_state(A);
  const NewtonSummary c = newton.solve(1.05 * m, &cold);
  ASSERT_TRUE(w.converged() && c.converged());
  EXPECT_LT(w.newton_iterations, c.newton_iterations);
  EXPECT_LT((warm.u - cold.u).lpNorm<Eigen::Infinity>(), 1e-8 * cold.u.lpNorm<Eigen::Infinity>());
  EXPECT_TRUE(newton.converged());
}

// The watchdog, the path predictor and the reuse of factorisations change the path, not the
// equilibrium: every combination reaches the same state, and each option changes the
// iteration history (so an option that were ignored would fail the test).
TEST(Newton, OptionsChangeThePathNotTheEquilibrium) {
  const Assembler A(fe_test::box(3, 2, {4.0, 1.0, 0.25}, {6, 1, 1}), fe_test::mooney_rivlin(),
                    Eigen::Vector3d::UnitX(), {{"x0", {}}});
  const Eigen::MatrixXd X = quadrature_points(A.mesh(), A.geometry());
  Eigen::MatrixXd m(A.mesh().num_elements(), A.geometry().points_per_element());
  for (Eigen::Index i = 0; i < X.rows(); ++i) m(i / m.cols(), i % m.cols()) = -0.5 * X(i, 2) / 0.25;
  struct Run {
    Eigen::VectorXd u;
    std::vector<double> cold, residuals;  // |R| of the cold solve and of the warm re-solve
    int factorizations = 0;
  };
  auto run = [&](bool watchdog, bool predictor, bool reuse) {
    NewtonOptions o;
    o.watchdog = watchdog;
    o.path_predictor = predictor;
    o.tangent.reuse_factorization = reuse;
    o.relative_tolerance = 1e-11;
    NewtonSolver newton(A, o);
    State s = rest_state(A);
    const NewtonSummary c = newton.solve(m, &s);
    EXPECT_TRUE(c.converged()) << c.FullReport();
    const NewtonSummary w = newton.solve(1.1 * m, &s);
    EXPECT_TRUE(w.converged()) << w.FullReport();
    Run r{s.u, {}, {}, w.factorizations};
    for (const NewtonIteration& it : c.iterations) r.cold.push_back(it.residual);
    for (const NewtonIteration& it : w.iterations) r.residuals.push_back(it.residual);
    return r;
  };
  const Run ref = run(true, true, true);
  for (int mask = 1; mask < 8; ++mask) {
    const Run r = run(!(mask & 1), !(mask & 2), !(mask & 4));
    EXPECT_LT((r.u - ref.u).lpNorm<Eigen::Infinity>(), 1e-8 * ref.u.lpNorm<Eigen::Infinity>())
        << "mask " << mask;
  }
  // Each option on its own changes the warm re-solve's path.
  EXPECT_NE(run(true, false, true).residuals, ref.residuals);  // predictor off
  EXPECT_NE(run(true, true, false).residuals, ref.residuals);  // factorise every tangent
  EXPECT_GT(run(true, true, false).factorizations, ref.factorizations);
  EXPECT_NE(run(false, true, true).cold, ref.cold);  // watchdog off
}

// All linear solvers give the same Newton solution.
TEST(Newton, LinearSolversAgree) {
  const Assembler A(fe_test::box(3, 1, {2.0, 1.0, 0.5}, {4, 2, 2}), fe_test::mooney_rivlin(),
                    Eigen::Vector3d(1, 1, 0), {{"x0", {}}});
  Eigen::VectorXd ref;
  for (LinearSolverType t :
       {LinearSolverType::kEigenLLT, LinearSolverType::kEigenLDLT, LinearSolverType::kCholmod}) {
    NewtonOptions o;
    o.tangent.linear_solver = t;
    NewtonSolver newton(A, o);
    State s = rest_state(A);
    ASSERT_TRUE(newton.solve(uniform(A, -0.5), &s).converged()) << to_string(t);
    if (ref.size() == 0) ref = s.u;
    EXPECT_LT((s.u - ref).norm(), 1e-9 * ref.norm()) << to_string(t);
  }
  EXPECT_EQ(parse_linear_solver("cholmod"), LinearSolverType::kCholmod);
  EXPECT_THROW(parse_linear_solver("umfpack"), softhd::InvalidArgument);
}

TEST(LinearSolver, ReportsIndefiniteMatrices) {
  SparseMatrix K(2, 2);
  K.insert(0, 0) = 1.0;
  K.insert(1, 0) = 2.0;
  K.insert(1, 1) = 1.0;  // eigenvalues −1 and 3
  K.makeCompressed();
  for (LinearSolverType t :
       {LinearSolverType::kEigenLLT, LinearSolverType::kEigenLDLT, LinearSolverType::kCholmod}) {
    auto s = make_linear_solver(t);
    s->analyze(K);
    EXPECT_FALSE(s->factorize(K)) << to_string(t);
    SparseMatrix P = K;
    P.coeffRef(1, 0) = 0.5;
    ASSERT_TRUE(s->factorize(P)) << to_string(t);
    const Eigen::Vector2d x = s->solve(Eigen::Vector2d(1.0, 2.0));
    EXPECT_NEAR(x[0] + 0.5 * x[1], 1.0, 1e-14);
    EXPECT_NEAR(0.5 * x[0] + x[1], 2.0, 1e-14);
  }
}

// m > 2a has no equilibrium (the energy is unbounded below along the fibers): the solver
// ends with a status and a report, and leaves a valid state.
TEST(Newton, FailureIsReportedNotThrown) {
  const Assembler A(fe_test::box(3, 1, {1.0, 1.0, 1.0}, {1, 1, 1}), fe_test::mooney_rivlin(),
                    Eigen::Vector3d::UnitX(), {{"x0", {}}});
  NewtonOptions o;
  o.max_load_steps = 12;
  NewtonSolver newton(A, o);
  State s = rest_state(A);
  const NewtonSummary sum = newton.solve(uniform(A, 6.0 * kA), &s);
  EXPECT_FALSE(sum.converged());
  EXPECT_LT(sum.final_load, 1.0);
  EXPECT_GT(A.min_jacobian(s.u), 0.0);
  EXPECT_NE(sum.FullReport().find("load"), std::string::npos);
  EXPECT_FALSE(newton.converged());
  NewtonOptions budget;
  budget.max_total_iterations = 7;
  NewtonSolver limited(A, budget);
  State s2 = rest_state(A);
  const NewtonSummary sum2 = limited.solve(uniform(A, 6.0 * kA), &s2);
  EXPECT_EQ(sum2.status, NewtonStatus::kTooManyIterations);
  EXPECT_LE(sum2.newton_iterations, 7 + budget.max_iterations);
  NewtonOptions bad;
  bad.max_iterations = 0;
  EXPECT_THROW(NewtonSolver(A, bad), softhd::InvalidArgument);
}

// validate() names the field that is wrong, the tangent solver's included.
TEST(Newton, OptionsValidationNamesTheField) {
  const std::vector<std::pair<std::function<void(NewtonOptions&)>, std::string>> cases = {
      {[](NewtonOptions& o) { o.relative_tolerance = -1.0; }, "relative_tolerance"},
      {[](NewtonOptions& o) { o.absolute_tolerance = std::nan(""); }, "absolute_tolerance"},
      {[](NewtonOptions& o) { o.armijo = 0.5; }, "armijo"},
      {[](NewtonOptions& o) { o.min_load_increment = 2.0; }, "min_load_increment"},
      {[](NewtonOptions& o) { o.forcing = 1.0; }, "forcing"},
      {[](NewtonOptions& o) { o.adjoint_tolerance = 0.0; }, "adjoint_tolerance"},
      {[](NewtonOptions& o) { o.tangent.max_krylov_iterations = 0; }, "max_krylov_iterations"}};
  for (const auto& [spoil, field] : cases) {
    NewtonOptions o;
    EXPECT_NO_THROW(o.validate());
    spoil(o);
    try {
      o.validate();
      ADD_FAILURE() << field << " not refused";
    } catch (const softhd::InvalidArgument& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  }
}

// A zero control is no load: the rest state is the equilibrium, and |R(0; 0)| is only the
// round-off of the stress at F = I. The relative test alone (1e-9 of that round-off) can
// never be met; make_state_solver's residual floor must accept the rest state at once.
// The shipped torsion scene (control.initial = 0) failed after 325 iterations before.
TEST(Newton, ZeroControlConvergesAtRest) {
  const softhd::Scene scene =
      softhd::load_scene(std::string(SOFTHD_SOURCE_DIR) + "/data/scenes/torsion.json");
  const softhd::fe::Assembler a = scene.body.make_assembler();
  const softhd::fe::ControlSpace c(a.mesh(), a.geometry(), scene.body.control_kind);
  const auto solver = softhd::fe::make_state_solver(scene.body, softhd::fe::StateSolverOptions{});
  const softhd::fe::NewtonSummary s = solver->solve(Eigen::VectorXd::Zero(c.size()));
  EXPECT_TRUE(solver->converged()) << s.message;
  EXPECT_EQ(s.newton_iterations, 0);
  EXPECT_EQ(solver->displacement().lpNorm<Eigen::Infinity>(), 0.0);
  const double floor = scene.body.residual_floor();
  EXPECT_GT(s.residual, 0.0);  // round-off, not exactly zero: the case the floor is for
  EXPECT_LE(s.residual, floor);
  // The library's forward (and the Python module's) takes the same floor.
  const softhd::fe::ForwardResult f =
      softhd::fe::solve_forward(scene.body, a, c, Eigen::VectorXd::Zero(c.size()));
  EXPECT_EQ(f.summary.newton_iterations, 0);
  EXPECT_EQ(f.state.u.lpNorm<Eigen::Infinity>(), 0.0);
}
