#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <random>

#include "softhd/error.hpp"
#include "softhd/fe/geometry.hpp"
#include "softhd/fe/mesh.hpp"
#include "softhd/fe/shape.hpp"

using namespace softhd::fe;

// Shape functions of every cell type: tests/fe/test_reference_element.cpp.

TEST(Shape, GaussRuleIntegratesOddDegreeExactly) {
  for (int n = 1; n <= 12; ++n) {  // closed forms up to 4, Golub-Welsch beyond
    Eigen::VectorXd x, w;
    gauss_legendre(n, &x, &w);
    for (int k = 0; k <= 2 * n - 1; ++k) {
      const double exact = (k % 2 == 1) ? 0.0 : 2.0 / (k + 1);
      double sum = 0.0;
      for (int i = 0; i < n; ++i) sum += w[i] * std::pow(x[i], k);
      EXPECT_NEAR(sum, exact, 2e-14) << n << " " << k;
    }
  }
}

TEST(Mesh, BendingPlateCountsAndFaces) {
  const Mesh m = make_box_mesh(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(10, 2, 0.1),
                               Eigen::Vector3i(50, 5, 2), 2);
  EXPECT_EQ(m.num_nodes(), 5555);  // (2·50+1)(2·5+1)(2·2+1), docs/formulation.md §5.1
  EXPECT_EQ(m.num_elements(), 500);
  EXPECT_EQ(m.nodes_per_element(), 27);
  EXPECT_EQ(m.num_vertices(), 51 * 6 * 3);
  EXPECT_EQ(m.face("x0").size(), 11u * 5u);
  EXPECT_EQ(m.face("z1").size(), 101u * 11u);
  for (int n : m.face("x1")) EXPECT_DOUBLE_EQ(m.nodes(n, 0), 10.0);
  for (int n : m.face("z0")) EXPECT_DOUBLE_EQ(m.nodes(n, 2), 0.0);
  EXPECT_THROW(m.face("w0"), softhd::InvalidArgument);
  EXPECT_THROW(make_box_mesh(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 1, 1),
                             Eigen::Vector3i(1, 1, 1), 3),
               softhd::InvalidArgument);
  EXPECT_THROW(
      make_box_mesh(Eigen::Vector2d(0, 0), Eigen::Vector2d(1, -1), Eigen::Vector2i(1, 1), 1),
      softhd::InvalidArgument);
}

// Lumped volumes against the tensor product of the 1-D integrals of the Lagrange basis:
// Q1 on a cell of length h: (h/2, h/2); Q2: (h/6, 2h/3, h/6).
TEST(Mesh, LumpedVolumesMatchOneDimensionalIntegrals) {
  for (int dim : {2, 3})
    for (int p : {1, 2}) {
      Eigen::VectorXd lo = Eigen::VectorXd::Zero(dim), hi(dim);
      Eigen::VectorXi cells(dim);
      const double len[3] = {3.0, 1.0, 0.5};
      const int nc[3] = {3, 2, 1};
      for (int d = 0; d < dim; ++d) {
        hi[d] = len[d];
        cells[d] = nc[d];
      }
      const Mesh m = make_box_mesh(lo, hi, cells, p);
      const ReferenceGeometry g(m);
      const Eigen::VectorXd V = lumped_volumes(m, g);
      double total = 1.0;
      for (int d = 0; d < dim; ++d) total *= len[d];
      EXPECT_NEAR(V.sum(), total, 1e-13);
      for (Eigen::Index n = 0; n < m.num_nodes(); ++n) {
        double expect = 1.0;
        for (int d = 0; d < dim; ++d) {
          const double h = len[d] / nc[d];
          const int nn = p * nc[d] + 1;
          const int i = static_cast<int>(std::lround(m.nodes(n, d) / h * p));
          double w;
          if (p == 1) {
            w = (i == 0 || i == nn - 1) ? h / 2 : h;
          } else {
            w = (i % 2 == 1) ? 2 * h / 3 : ((i == 0 || i == nn - 1) ? h / 6 : h / 3);
          }
          expect *= w;
        }
        EXPECT_NEAR(V[n], expect, 1e-13) << "node " << n;
      }
    }
}

TEST(Mesh, LocateFindsElementAndReferenceCoordinates) {
  const Mesh m = make_box_mesh(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(4, 2, 1),
                               Eigen::Vector3i(4, 2, 2), 2);
  Eigen::VectorXd xi;
  const int e = locate(m, Eigen::Vector3d(2.5, 0.25, 1.0), &xi);
  EXPECT_EQ(e, 2 + 4 * (0 + 2 * 1));
  EXPECT_NEAR(xi[0], 0.0, 1e-14);
  EXPECT_NEAR(xi[1], -0.5, 1e-14);
  EXPECT_NEAR(xi[2], 1.0, 1e-14);
  EXPECT_EQ(locate(m, Eigen::Vector3d(4.1, 0, 0), &xi), -1);
}
