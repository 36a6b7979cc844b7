// Mesh convergence of unstructured tetrahedra (issue 30): the equilibrium energy converges
// at the order the element promises, observed from three nested meshes.
//
// The problem is smooth up to its boundary, so no singularity caps the rate: the unit cube
// on rollers (u_x = 0 on x = 0, u_y = 0 on y = 0, u_z = 0 on z = 0), a uniform tension
// m = -0.6, and fibres a0 ∝ (1, 0.4 x y, 0) given per node. The rollers act as mirror planes
// and the mirrored fibre tensor a0 ⊗ a0 is smooth across them (its xy entry is odd in x and
// in y), so the solution extends smoothly. (With uniform fibres the solution is a
// homogeneous stretch and every mesh gives it exactly, as checked while writing this.)
//
// At a minimum the energy error is the square of the energy-norm error: O(h^{2p}), 4 for
// P2 and 2 for P1. From h, h/2, h/4, p = log2((Π_h − Π_{h/2}) / (Π_{h/2} − Π_{h/4})).
// Measured (nested Kuhn meshes of n³ cubes): P2 3.05 from n = 1, 2, 4 and 3.43 from
// n = 2, 4, 8; P1 1.6 from n = 2, 4, 8 and 1.72 from n = 4, 8, 16: both rise towards the
// theory. The bars below sit between the two elements' measured rates, so a P2 that
// converged like P1 (or worse, e.g. a wrong quadrature or midside node) fails.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "fe_test_util.hpp"
#include "softhd/fe/assembly.hpp"
#include "softhd/fe/newton.hpp"
#include "unstructured_meshes.hpp"

using namespace softhd::fe;

namespace {

// The equilibrium energy Π(u) on the cube of n³ Kuhn cubes.
double equilibrium_energy(int order, int n) {
  Mesh mesh = fe_test::tet_box(order, {n, n, n}, {1.0, 1.0, 1.0});
  for (Eigen::Index k = 0; k < mesh.num_nodes(); ++k)
    for (int d = 0; d < 3; ++d)
      if (std::abs(mesh.nodes(k, d)) < 1e-12)
        mesh.boundary_nodes[std::string(1, "xyz"[d]) + "0"].push_back(static_cast<int>(k));
  FiberField fibers;
  fibers.kind = FiberField::Kind::kNode;
  fibers.values.resize(3, mesh.num_nodes());
  for (Eigen::Index k = 0; k < mesh.num_nodes(); ++k)  // a0 ∝ (1, 0.4 x y, 0)
    fibers.values.col(k) << 1.0, 0.4 * mesh.nodes(k, 0) * mesh.nodes(k, 1), 0.0;
  const std::vector<DirichletConstraint> rollers = {{"x0", {0}}, {"y0", {1}}, {"z0", {2}}};
  const Assembler A(mesh, {fe_test::mooney_rivlin()}, fibers, rollers);
  NewtonOptions options;
  options.absolute_tolerance = 1e-13;
  NewtonSolver newton(A, options);
  State state = rest_state(A);
  const Eigen::MatrixXd m_qp =
      Eigen::MatrixXd::Constant(mesh.num_elements(), A.geometry().points_per_element(), -0.6);
  EXPECT_TRUE(newton.solve(m_qp, &state).converged());
  EXPECT_GT(state.u.cwiseAbs().maxCoeff(), 0.05);  // the body did move
  double Pi = 0.0;
  EXPECT_TRUE(A.evaluate(state.u, m_qp, &Pi, nullptr, nullptr));
  return Pi;
}

double observed_order(int order, int n) {
  const double e1 = equilibrium_energy(order, n), e2 = equilibrium_energy(order, 2 * n),
               e4 = equilibrium_energy(order, 4 * n);
  return std::log2((e1 - e2) / (e2 - e4));
}

TEST(Convergence, P2TetrahedraConvergeFasterThanP1AtTheirOrders) {
  const double p2 = observed_order(2, 2), p1 = observed_order(1, 4);
  std::printf("observed energy order: P2 %.2f (theory 4), P1 %.2f (theory 2)\n", p2, p1);
  EXPECT_GE(p2, 3.2);
  EXPECT_LE(p2, 4.3);
  EXPECT_GE(p1, 1.5);
  EXPECT_LE(p1, 2.3);
}

}  // namespace
