// The state's side of the reduced Hessian-vector product (docs/formulation.md §4.4.1): the
// element terms of fe/second_order.hpp against the assembled residual and tangent, and
// StateSolver::sensitivity / hessian_product by the Taylor test of the reduced gradient.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "expect_error.hpp"
#include "fe_test_util.hpp"
#include "softhd/fe/second_order.hpp"
#include "softhd/fe/state_solver.hpp"

using namespace softhd::fe;
using softhd::HessianPart;

namespace {

std::shared_ptr<const Material> transversely_isotropic() {
  return std::make_shared<TransverselyIsotropic>(1.0, 0.2, 3.0, 10.0, Eigen::Vector3d(1, 1, 0));
}

// A random dof vector with the fixed entries zero.
Eigen::VectorXd free_vector(const Assembler& A, double amplitude, unsigned seed) {
  return A.dofs().expand(fe_test::random_vector(A.dofs().num_free, amplitude, seed));
}

// K(u; m) x on the free dofs, K assembled.
Eigen::VectorXd tangent_times(const Assembler& A, const Eigen::VectorXd& u,
                              const Eigen::MatrixXd& m_qp, const Eigen::VectorXd& x) {
  SparseMatrix K = A.tangent_pattern();
  EXPECT_TRUE(A.evaluate(u, m_qp, nullptr, nullptr, &K));
  return K.selfadjointView<Eigen::Lower>() * A.dofs().restrict(x);
}

Eigen::VectorXd residual(const Assembler& A, const Eigen::VectorXd& u,
                         const Eigen::MatrixXd& m_qp) {
  Eigen::VectorXd R;
  EXPECT_TRUE(A.evaluate(u, m_qp, nullptr, &R, nullptr));
  return R;
}

struct BoxCase {
  int dim, order;
  bool transversely_isotropic;
  ControlKind kind;
};

Assembler make_assembler(const BoxCase& b, AssemblerStorage storage = AssemblerStorage::kFull) {
  const Eigen::Vector3d a0 = b.dim == 3 ? Eigen::Vector3d(1, 0.2, 0.1) : Eigen::Vector3d(1, 0.3, 0);
  return Assembler(
      fe_test::box(b.dim, b.order, {3.0, 1.0, 0.4}, {3, 2, 1}),
      std::vector<std::shared_ptr<const Material>>{
          b.transversely_isotropic ? transversely_isotropic() : fe_test::mooney_rivlin()},
      [&] {
        FiberField f;
        f.values = a0;
        return f;
      }(),
      {{"x0", {}}}, storage);
}

const std::vector<BoxCase> kBodies = {{3, 1, false, ControlKind::kVertex},
                                      {3, 2, true, ControlKind::kVertex},
                                      {2, 2, false, ControlKind::kElement},
                                      {2, 1, true, ControlKind::kVertex}};

}  // namespace

TEST(Materials, ThirdDerivativeInJIsTheDerivativeOfW_JJ) {
  const Eigen::Matrix3d F = Eigen::Matrix3d::Identity() * 1.1;
  const MooneyRivlin mr(1.0, 0.2, 3.0);
  const TransverselyIsotropic ti(1.0, 0.2, 3.0, 10.0, Eigen::Vector3d(1, 1, 0));
  for (const Material* m : {static_cast<const Material*>(&mr), static_cast<const Material*>(&ti)})
    for (double J : {0.6, 1.0, 1.7}) {
      const double h = 1e-4;  // central difference of W_JJ: error O(h²) ≈ 1e-8 relative
      const double fd =
          (m->evaluate(F, F, J + h, true).W_JJ - m->evaluate(F, F, J - h, true).W_JJ) / (2.0 * h);
      EXPECT_NEAR(m->W_JJJ(J), fd, 1e-6 * std::abs(fd)) << "J = " << J;
    }
}

// R is affine in m: R(u; m + v) − R(u; m) = (∂R/∂m) v, and (K(u; m + v) − K(u; m)) λ is the
// mixed term ∂²(λᵀR)/∂u∂m v; ∂²(λᵀR)/∂m∂u is its transpose.
TEST(SecondOrder, ControlTermsAreTheChangesOfResidualAndTangentInM) {
  for (const BoxCase& b : kBodies) {
    const Assembler A = make_assembler(b);
    const ControlSpace c(A.mesh(), A.geometry(), b.kind);
    const Eigen::VectorXd u = free_vector(A, 0.05, 1);
    const Eigen::VectorXd lambda = free_vector(A, 1.0, 2), w = free_vector(A, 1.0, 3);
    const Eigen::VectorXd m = fe_test::random_vector(c.size(), 0.3, 4);
    const Eigen::VectorXd v = fe_test::random_vector(c.size(), 0.3, 5);
    const Eigen::MatrixXd mq = c.to_quadrature(m), mvq = c.to_quadrature(m + v);

    // The differences cancel: their round-off is that of the terms, ~1e-16 |R| each.
    const Eigen::VectorXd Bv = control_force(A, c, u, v);
    const Eigen::VectorXd R1 = residual(A, u, mvq), R0 = residual(A, u, mq), dR = R1 - R0;
    EXPECT_LE((A.dofs().restrict(Bv) - dR).norm(), 1e-13 * (R1.norm() + R0.norm()))
        << b.dim << "D Q" << b.order;
    EXPECT_GT(dR.norm(), 1e-3);
    EXPECT_EQ(Bv, A.dofs().expand(A.dofs().restrict(Bv)));  // fixed entries zero

    const Eigen::VectorXd um = adjoint_mixed_um(A, c, lambda, v);
    const Eigen::VectorXd K1 = tangent_times(A, u, mvq, lambda),
                          K0 = tangent_times(A, u, mq, lambda);
    const Eigen::VectorXd dK = K1 - K0;
    EXPECT_LE((A.dofs().restrict(um) - dK).norm(), 1e-13 * (K1.norm() + K0.norm()))
        << b.dim << "D Q" << b.order;
    EXPECT_GT(dK.norm(), 1e-3);

    const double lhs = adjoint_mixed_mu(A, c, lambda, w).dot(v), rhs = w.dot(um);
    EXPECT_NEAR(lhs, rhs, 1e-12 * std::abs(rhs));
    EXPECT_GT(std::abs(rhs), 1e-3);
  }
}

// ∂²(λᵀR)/∂u² w is d/dε [K(u + ε w) λ]: central differences of the assembled tangent converge
// to it at second order, and the form ⟨δ, T(w, λ)⟩ is symmetric in δ, w, λ.
TEST(SecondOrder, CurvatureIsTheDerivativeOfTheTangent) {
  for (const BoxCase& b : kBodies) {
    const Assembler A = make_assembler(b);
    const ControlSpace c(A.mesh(), A.geometry(), b.kind);
    const Eigen::MatrixXd mq = c.to_quadrature(fe_test::random_vector(c.size(), 0.3, 4));
    const Eigen::VectorXd u = free_vector(A, 0.05, 1);
    const Eigen::VectorXd w = free_vector(A, 1.0, 6), lambda = free_vector(A, 1.0, 7);
    const Eigen::VectorXd delta = free_vector(A, 1.0, 8);
    const Eigen::VectorXd T = A.dofs().restrict(adjoint_curvature(A, u, w, lambda));
    std::vector<double> err;
    for (double h : {4e-3, 2e-3, 1e-3}) {
      const Eigen::VectorXd fd =
          (tangent_times(A, u + h * w, mq, lambda) - tangent_times(A, u - h * w, mq, lambda)) /
          (2.0 * h);
      err.push_back((fd - T).norm());
    }
    for (size_t i = 1; i < err.size(); ++i) {
      const double order = std::log2(err[i - 1] / err[i]);
      std::printf("%dD Q%d %s: central differences of K λ, order %.3f (error %.2e of %.2e)\n",
                  b.dim, b.order, b.transversely_isotropic ? "TI" : "MR", order, err[i], T.norm());
      EXPECT_GT(order, 1.9) << b.dim << "D Q" << b.order;
    }
    // A wrong T would leave a constant error (order 0); at h = 1e-3 three digits agree.
    EXPECT_LT(err.back(), 1e-3 * T.norm());

    const double a1 = delta.dot(adjoint_curvature(A, u, w, lambda));
    const double a2 = w.dot(adjoint_curvature(A, u, delta, lambda));
    const double a3 = lambda.dot(adjoint_curvature(A, u, w, delta));
    EXPECT_NEAR(a1, a2, 1e-12 * std::abs(a1));
    EXPECT_NEAR(a1, a3, 1e-12 * std::abs(a1));

    // Gradients recomputed at every point (a lean assembler) give the same vector.
    const Assembler lean = make_assembler(b, AssemblerStorage::kLean);
    EXPECT_LE((lean.dofs().restrict(adjoint_curvature(lean, u, w, lambda)) - T).norm(),
              1e-12 * T.norm());
  }
}

TEST(SecondOrder, WrongSizesAreRefused) {
  const Assembler A = make_assembler(kBodies[0]);
  const Eigen::VectorXd u = Eigen::VectorXd::Zero(A.dofs().num_dofs);
  softhd::test::expect_error<softhd::InvalidArgument>(
      [&] { adjoint_curvature(A, u, Eigen::VectorXd::Zero(3), u); }, "w must have");
}

namespace {

// J(m) = F(u(m), m) with F = ½ Σ_{n on the free end} c_n |u_n − t_n|² + (M/2)∫m² + (ε/2)∫|∇m|²:
// F_u = c (u − t) there, F_uu w = c w there, F_mm v = the Tikhonov gradient at v (it is
// quadratic), no cross term.
struct Objective {
  StateSolver& S;
  Eigen::VectorXd c, t;  // per dof: weight (0 off the free end) and target
  double M = 0.3, eps = 0.1;

  Objective(StateSolver& solver, double target_scale) : S(solver) {
    const Mesh& mesh = S.assembler().mesh();
    const int dim = mesh.dim;
    c = Eigen::VectorXd::Zero(S.assembler().dofs().num_dofs);
    t = fe_test::random_vector(c.size(), target_scale, 31);
    for (int n : mesh.face("x1")) c.segment(n * dim, dim).setConstant(1.0 + mesh.nodes(n, 1));
  }
  Eigen::VectorXd tikhonov(const Eigen::VectorXd& m) const {
    Eigen::VectorXd g;
    S.control().regularisation(m, M, eps, &g);
    return g;
  }
  // ∇J(m) at the current (converged) state of control m: F_m + the state part.
  Eigen::VectorXd gradient(const Eigen::VectorXd& m) const {
    return tikhonov(m) + S.gradient(c.cwiseProduct(S.displacement() - t));
  }
  // H v = F_mm v + s(v, w, F_uu w), w = (du/dm) v.
  Eigen::VectorXd hessian(const Eigen::VectorXd& v, HessianPart part) const {
    const Eigen::VectorXd w = S.sensitivity(v);
    return tikhonov(v) + S.hessian_product(v, w, c.cwiseProduct(w), part);
  }
};

NewtonOptions tight() {
  NewtonOptions o;
  o.relative_tolerance = 1e-12;
  return o;
}

}  // namespace

namespace {

// A solver at a converged state of a torsion-like control, with the gradient made.
struct Converged {
  StateSolver S{make_assembler({3, 2, true, ControlKind::kVertex}), ControlKind::kVertex, tight()};
  Objective J{S, 0.1};
  Eigen::VectorXd m;
  explicit Converged(bool zero_adjoint) {
    const Eigen::MatrixXd P = S.control().positions(S.assembler().mesh());
    m = -0.5 * P.col(2) / P.col(2).maxCoeff();
    EXPECT_TRUE(S.solve(m).converged());
    if (zero_adjoint) J.t = S.displacement();  // F_u = 0 at the state: λ = 0
    J.gradient(m);
  }
};

}  // namespace

// w = (du/dm) v is the derivative of the equilibrium: central differences of u(m ± h v)
// converge to it at second order.
TEST(StateSolverHessian, SensitivityIsTheDerivativeOfTheState) {
  Converged x(/*zero_adjoint=*/false);
  const Eigen::VectorXd v = fe_test::random_vector(x.m.size(), 0.2, 81);
  const Eigen::VectorXd w = x.S.sensitivity(v);
  EXPECT_EQ(x.S.adjoint_factorizations(), 0);
  const State s0 = x.S.state();
  std::vector<double> err;
  for (double h : {0.04, 0.02, 0.01}) {
    Eigen::VectorXd u[2];
    for (int side = 0; side < 2; ++side) {
      x.S.set_state(s0);
      EXPECT_TRUE(x.S.solve(x.m + (side == 0 ? h : -h) * v).converged());
      u[side] = x.S.displacement();
    }
    err.push_back(((u[0] - u[1]) / (2.0 * h) - w).norm());
  }
  for (size_t i = 1; i < err.size(); ++i) {
    std::printf("sensitivity: central differences, order %.3f (error %.2e of %.2e)\n",
                std::log2(err[i - 1] / err[i]), err[i], w.norm());
    EXPECT_GT(std::log2(err[i - 1] / err[i]), 1.9);
  }
  EXPECT_LT(err.back(), 1e-3 * w.norm());
}

namespace {

struct TaylorCase {
  const char* name;
  BoxCase body;
  double tension;  // m = tension · (z or y)/height + a random part
  HessianPart part;
};

// ‖∇J(m + h v) − ∇J(m) − h H v‖ for h = h0, h0/2, ...
std::vector<double> gradient_remainders(const TaylorCase& k, double h0) {
  StateSolver S(make_assembler(k.body), k.body.kind, tight());
  Objective J(S, 0.1);
  const Eigen::MatrixXd P = S.control().positions(S.assembler().mesh());
  const Eigen::VectorXd m =
      (k.tension * P.col(k.body.dim - 1) / P.col(k.body.dim - 1).maxCoeff()).array() +
      fe_test::random_vector(P.rows(), 0.05, 41).array();
  const Eigen::VectorXd v = fe_test::random_vector(P.rows(), 0.2, 42);
  EXPECT_TRUE(S.solve(m).converged());
  const Eigen::VectorXd g0 = J.gradient(m);
  const Eigen::VectorXd Hv = J.hessian(v, k.part);
  std::vector<double> rem;
  for (double h = h0; rem.size() < 4; h /= 2) {
    EXPECT_TRUE(S.solve(m + h * v).converged());
    rem.push_back((J.gradient(m + h * v) - g0 - h * Hv).norm());
  }
  // The exact H v is what the test sees: the first-order term dominates the remainder.
  if (k.part == HessianPart::full) {
    EXPECT_GT(h0 / 8 * Hv.norm(), 20.0 * rem.back()) << k.name;
  }
  return rem;
}

}  // namespace

// Taylor test of the reduced gradient with the full product: the remainder falls as h².
TEST(StateSolverHessian, FullProductPassesTheTaylorTestOfTheGradient) {
  const std::vector<TaylorCase> cases = {
      {"3D Q2 Mooney-Rivlin bending", {3, 2, false, ControlKind::kVertex}, -0.4, HessianPart::full},
      {"3D Q2 transversely isotropic torsion",
       {3, 2, true, ControlKind::kVertex},
       -0.6,
       HessianPart::full},
      {"2D Q2 Mooney-Rivlin", {2, 2, false, ControlKind::kVertex}, -0.4, HessianPart::full}};
  for (const TaylorCase& k : cases) {
    const std::vector<double> rem = gradient_remainders(k, 0.1);
    for (size_t i = 1; i < rem.size(); ++i) {
      const double order = std::log2(rem[i - 1] / rem[i]);
      std::printf("%s: h-halving %zu, remainder %.3e, observed order %.3f\n", k.name, i, rem[i],
                  order);
      EXPECT_GT(order, 1.9) << k.name;
    }
  }
}

// Gauss–Newton drops the λ-weighted terms: where they matter (λ ≠ 0) its gradient remainder
// falls only as h, which shows the Taylor test above sees them.
TEST(StateSolverHessian, GaussNewtonMissesTheStateCurvatureWhenTheAdjointIsNotZero) {
  const TaylorCase k{"3D Q2 Mooney-Rivlin, Gauss-Newton",
                     {3, 2, false, ControlKind::kVertex},
                     -0.4,
                     HessianPart::gauss_newton};
  const std::vector<double> rem = gradient_remainders(k, 0.1);
  const double order = std::log2(rem[2] / rem[3]);
  std::printf("%s: observed order %.3f\n", k.name, order);
  EXPECT_LT(order, 1.2);
}

// With F_u = 0 at the state (the target is the state itself) λ = 0: the full product is the
// Gauss–Newton one, and both are Sᵀ F_uu S + F_mm with S = du/dm, computed here from two
// sensitivities.
TEST(StateSolverHessian, GaussNewtonIsTheFullProductWhenTheAdjointIsZero) {
  Converged x(/*zero_adjoint=*/true);
  const Eigen::Index n = x.m.size();
  const Eigen::VectorXd a = fe_test::random_vector(n, 1.0, 51),
                        b = fe_test::random_vector(n, 1.0, 52);
  const Eigen::VectorXd full = x.J.hessian(b, HessianPart::full);
  const Eigen::VectorXd gn = x.J.hessian(b, HessianPart::gauss_newton);
  EXPECT_LE((full - gn).norm(), 1e-14 * gn.norm());
  // aᵀ H b = (S a)ᵀ F_uu (S b) + aᵀ F_mm b
  const Eigen::VectorXd Sa = x.S.sensitivity(a), Sb = x.S.sensitivity(b);
  const double expected = Sa.dot(x.J.c.cwiseProduct(Sb)) + a.dot(x.J.tikhonov(b));
  EXPECT_NEAR(a.dot(gn), expected, 1e-9 * std::abs(expected));
}

// Symmetric (to the solves' tolerance) for both parts, and Gauss–Newton positive semi-definite
// (F_uu ≥ 0 here) and equal to Sᵀ F_uu S + F_mm also where λ ≠ 0.
TEST(StateSolverHessian, ProductsAreSymmetricAndGaussNewtonIsPositive) {
  Converged x(/*zero_adjoint=*/false);
  const Eigen::Index n = x.m.size();
  for (HessianPart part : {HessianPart::full, HessianPart::gauss_newton}) {
    const Eigen::VectorXd a = fe_test::random_vector(n, 1.0, 61);
    const Eigen::VectorXd b = fe_test::random_vector(n, 1.0, 62);
    const Eigen::VectorXd Ha = x.J.hessian(a, part), Hb = x.J.hessian(b, part);
    const double aHb = a.dot(Hb), bHa = b.dot(Ha);
    std::printf("%s: aᵀHb = %.15e, bᵀHa = %.15e, relative difference %.2e\n",
                part == HessianPart::full ? "full" : "gauss_newton", aHb, bHa,
                std::abs(aHb - bHa) / (a.norm() * Hb.norm()));
    EXPECT_LE(std::abs(aHb - bHa), 1e-10 * a.norm() * Hb.norm());
    if (part == HessianPart::gauss_newton) {
      for (unsigned seed = 63; seed < 68; ++seed) {
        const Eigen::VectorXd z = fe_test::random_vector(n, 1.0, seed);
        EXPECT_GE(z.dot(x.J.hessian(z, part)), 0.0);
      }
      const Eigen::VectorXd Sa = x.S.sensitivity(a), Sb = x.S.sensitivity(b);
      const double expected = Sa.dot(x.J.c.cwiseProduct(Sb)) + a.dot(x.J.tikhonov(b));
      EXPECT_NEAR(aHb, expected, 1e-9 * std::abs(expected));
    }
  }
}

// The products reuse the converged tangent's factorisation: no new one per product.
TEST(StateSolverHessian, ProductsMakeNoFactorisation) {
  Converged x(/*zero_adjoint=*/false);
  for (unsigned seed = 71; seed < 74; ++seed) {
    const Eigen::VectorXd v = fe_test::random_vector(x.m.size(), 1.0, seed);
    const Eigen::VectorXd w = x.S.sensitivity(v);
    EXPECT_EQ(x.S.adjoint_factorizations(), 0);
    x.S.hessian_product(v, w, x.J.c.cwiseProduct(w), HessianPart::full);
    EXPECT_EQ(x.S.adjoint_factorizations(), 0);
  }
}

TEST(StateSolverHessian, NeedsAGradientAtTheConvergedStateAndRightSizes) {
  using softhd::InvalidArgument;
  using softhd::test::expect_error;
  StateSolver S(make_assembler(kBodies[0]), ControlKind::kVertex, tight());
  const Eigen::VectorXd v = Eigen::VectorXd::Zero(S.control().size());
  const Eigen::VectorXd u0 = Eigen::VectorXd::Zero(S.assembler().dofs().num_dofs);
  expect_error<InvalidArgument>([&] { S.sensitivity(v); }, "followed by gradient()");
  ASSERT_TRUE(S.solve(v.array() - 0.2).converged());
  expect_error<InvalidArgument>([&] { S.sensitivity(v); }, "followed by gradient()");
  S.gradient(u0);
  EXPECT_EQ(S.sensitivity(v).size(), u0.size());
  expect_error<InvalidArgument>([&] { S.sensitivity(u0); }, "control values");
  expect_error<InvalidArgument>([&] { S.hessian_product(v, v, u0, HessianPart::gauss_newton); },
                                "hessian_product() needs");
  S.set_state(S.state());  // a new state: λ is gone
  expect_error<InvalidArgument>([&] { S.hessian_product(v, u0, u0, HessianPart::full); },
                                "followed by gradient()");
  ASSERT_TRUE(S.solve(v.array() - 0.1).converged());
  expect_error<InvalidArgument>([&] { S.sensitivity(v); }, "followed by gradient()");
  S.gradient(u0);
  S.reset();
  expect_error<InvalidArgument>([&] { S.sensitivity(v); }, "followed by gradient()");
}
