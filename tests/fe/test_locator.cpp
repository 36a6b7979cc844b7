// Point location (fe/locator.hpp) and the interpolation module (fe/interpolation.hpp) on
// structured boxes and on curved unstructured tet10 and hex27 meshes built in code.

#include <gtest/gtest.h>

#include <random>

#include "fe_test_util.hpp"
#include "softhd/error.hpp"
#include "softhd/fe/interpolation.hpp"
#include "softhd/fe/locator.hpp"
#include "unstructured_meshes.hpp"

using namespace softhd::fe;

namespace {

// X(ξ) = Σ_a X_a N_a(ξ) in element e.
Eigen::VectorXd map_point(const Mesh& m, Eigen::Index e, const Eigen::VectorXd& xi) {
  const ReferenceElement& r = reference_element(m.cell);
  Eigen::VectorXd N(r.nodes), dN(r.nodes * r.dim), X = Eigen::VectorXd::Zero(m.dim);
  shape_functions(m.cell, xi.data(), N.data(), dN.data());
  for (int a = 0; a < r.nodes; ++a) X += N[a] * m.nodes.row(m.elements(e, a)).transpose();
  return X;
}

// A random reference point at least `margin` inside the reference cell.
Eigen::VectorXd interior_point(const ReferenceElement& r, double margin, std::mt19937* rng) {
  std::uniform_real_distribution<double> U(0.0, 1.0);
  Eigen::VectorXd xi(r.dim);
  while (true) {
    for (int k = 0; k < r.dim; ++k) xi[k] = r.simplex ? U(*rng) : 2.0 * U(*rng) - 1.0;
    if (!r.simplex && xi.cwiseAbs().maxCoeff() <= 1.0 - margin) return xi;
    if (r.simplex && xi.minCoeff() >= margin && xi.sum() <= 1.0 - margin) return xi;
  }
}

}  // namespace

TEST(Locator, StructuredBoxesLocateByArithmetic) {
  const Mesh m = fe_test::box(3, 2, {4.0, 1.0, 2.0}, {4, 2, 2});
  const PointLocator locator(m);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> U(-0.1, 1.1);
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::Vector3d X(4.0 * U(rng), U(rng), 2.0 * U(rng));
    Eigen::VectorXd xi, xi_box;
    const Eigen::VectorXd Xd = X;
    const int e = locator.locate(Xd, &xi);
    EXPECT_EQ(e, locate(m, Xd, &xi_box));
    if (e >= 0) {
      EXPECT_EQ(xi, xi_box);
    }
  }
}

// Random points of random elements of curved meshes: the located element's map reproduces
// the point, in the element it was made in (interior points lie in one element only).
TEST(Locator, CurvedUnstructuredMeshesInvertTheIsoparametricMap) {
  Mesh tet10 = fe_test::tet_box(2, {3, 2, 2}, {1.5, 1.0, 1.0});
  fe_test::warp(&tet10, 0.06);
  Mesh tet4 = fe_test::tet_box(1, {2, 2, 2}, {1.0, 1.0, 1.0});
  fe_test::warp(&tet4, 0.06);
  Mesh hex27 = fe_test::box(3, 2, {1.5, 1.0, 1.0}, {3, 2, 2});
  fe_test::warp(&hex27, 0.06);
  std::mt19937 rng(11);
  for (const Mesh* m : {&tet10, &tet4, &hex27}) {
    ASSERT_FALSE(m->structured());
    const PointLocator locator(*m);
    const ReferenceElement& r = reference_element(m->cell);
    std::uniform_int_distribution<int> pick(0, static_cast<int>(m->num_elements()) - 1);
    for (int trial = 0; trial < 200; ++trial) {
      const int e = pick(rng);
      const Eigen::VectorXd xi = interior_point(r, 1e-3, &rng);
      const Eigen::VectorXd X = map_point(*m, e, xi);
      Eigen::VectorXd found;
      const int f = locator.locate(X, &found);
      ASSERT_EQ(f, e) << to_string(m->cell) << " trial " << trial;
      EXPECT_LT((found - xi).norm(), 1e-12);
      EXPECT_LT((map_point(*m, f, found) - X).norm(), 1e-13);
    }
    // Outside: beyond the box the warp moves by at most 0.06.
    Eigen::VectorXd xi;
    for (const Eigen::Vector3d& X :
         {Eigen::Vector3d(-0.5, 0.5, 0.5), Eigen::Vector3d(3.0, 0.5, 0.5),
          Eigen::Vector3d(0.5, 0.5, 1.2), Eigen::Vector3d(0.5, -0.2, 0.5)})
      EXPECT_EQ(locator.locate(Eigen::VectorXd(X), &xi), -1) << to_string(m->cell);
    EXPECT_EQ(locator.locate(Eigen::Vector2d(0.5, 0.5), &xi), -1);  // wrong dimension
    // Every node lies in the mesh (on element boundaries: any element sharing it).
    for (Eigen::Index n = 0; n < m->num_nodes(); n += 7) {
      const Eigen::VectorXd X = m->nodes.row(n).transpose();
      const int f = locator.locate(X, &xi);
      ASSERT_GE(f, 0) << to_string(m->cell) << " node " << n;
      EXPECT_LT((map_point(*m, f, xi) - X).norm(), 1e-12);
    }
  }
}

// The coordinates are a nodal field the isoparametric interpolation reproduces exactly; on
// straight-sided tetrahedra the vertex coordinates are reproduced by the P1 functions.
TEST(Interpolation, ReproducesCoordinatesAndReportsOutsidePoints) {
  Mesh curved = fe_test::tet_box(2, {2, 2, 1}, {1.0, 1.0, 0.5});
  fe_test::warp(&curved, 0.05);
  const PointLocator locator(curved);
  Eigen::MatrixXd P(4, 3);
  P << 0.3, 0.4, 0.2, 0.9, 0.1, 0.3, -1.0, 0.0, 0.0, 0.5, 0.5, 0.25;
  std::vector<int> outside;
  const Eigen::MatrixXd X = interpolate_nodal(curved, locator, curved.nodes, P, &outside);
  ASSERT_EQ(outside, std::vector<int>{2});
  for (int p : {0, 1, 3}) EXPECT_LT((X.row(p) - P.row(p)).norm(), 1e-13);
  EXPECT_EQ(X.row(2).norm(), 0.0);
  EXPECT_THROW(interpolate_nodal(curved, locator, curved.nodes, P, nullptr),
               softhd::InvalidArgument);

  const Mesh straight = fe_test::tet_box(2, {2, 2, 1}, {1.0, 1.0, 0.5});
  const PointLocator straight_locator(straight);
  Eigen::MatrixXd V(straight.num_vertices(), 3);
  for (Eigen::Index v = 0; v < V.rows(); ++v)
    V.row(v) = straight.nodes.row(straight.vertex_nodes[v]);
  const Eigen::MatrixXd Y = interpolate_vertex(straight, straight_locator, V, P, &outside);
  for (int p : {0, 1, 3}) EXPECT_LT((Y.row(p) - P.row(p)).norm(), 1e-14);
  EXPECT_EQ(locate_points(straight_locator, P)[2], -1);
}
