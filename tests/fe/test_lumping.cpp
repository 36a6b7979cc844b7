// Positive nodal volumes on every cell type (issue 30 item 4): HRZ on P2 simplices, the row
// sum elsewhere; their sums against the mesh's own volume on curved elements; the exact
// derivative of the deformed HRZ volumes.

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <cmath>

#include "fe_test_util.hpp"
#include "softhd/fe/cloud.hpp"
#include "softhd/fe/geometry.hpp"
#include "unstructured_meshes.hpp"

using namespace softhd::fe;

namespace {

// One straight-sided element of `type` on the reference cell's nodes mapped by X = A ξ + b.
Mesh affine_element(CellType type, const Eigen::MatrixXd& A) {
  const ReferenceElement& r = reference_element(type);
  Mesh m;
  m.dim = r.dim;
  m.order = r.order;
  m.cell = type;
  m.nodes = (r.node_coordinates * A.transpose()).rowwise() + Eigen::RowVectorXd::Ones(r.dim);
  m.elements.resize(1, r.nodes);
  for (int a = 0; a < r.nodes; ++a) m.elements(0, a) = a;
  m.element_region = Eigen::VectorXi::Zero(1);
  return m;
}

}  // namespace

TEST(Lumping, HrzOnAffineP2SimplicesAndRowSumElsewhere) {
  const Eigen::Matrix3d A = (Eigen::Matrix3d() << 2, 0.3, 0.1, 0, 1.5, 0.2, 0.1, 0, 0.7).finished();
  {
    const Mesh m = affine_element(CellType::kTet10, A);
    const ReferenceGeometry g(m);
    const double V = A.determinant() / 6.0;
    const Eigen::VectorXd w = lumped_volumes(m, g);
    for (int a = 0; a < 4; ++a) EXPECT_NEAR(w[a], V / 36.0, 1e-15 * V);         // vertices
    for (int a = 4; a < 10; ++a) EXPECT_NEAR(w[a], 4.0 * V / 27.0, 1e-15 * V);  // edges
    EXPECT_NEAR(w.sum(), V, 1e-14 * V);  // 4/36 + 6·4/27 = 1/9 + 8/9 = 1
    // The row sum this replaces: −V/20 at the vertices, V/5 at the edges.
    Eigen::VectorXd row(10);
    lumped_element_weights(g, Lumping::kRowSum, 0, nullptr, row.data(), nullptr);
    EXPECT_NEAR(row[0], -V / 20.0, 1e-15 * V);
    EXPECT_NEAR(row[4], V / 5.0, 1e-15 * V);
  }
  {
    const Eigen::Matrix2d A2 = A.topLeftCorner<2, 2>();
    const Mesh m = affine_element(CellType::kTri6, A2);
    const double area = A2.determinant() / 2.0;
    const Eigen::VectorXd w = lumped_volumes(m, ReferenceGeometry(m));
    for (int a = 0; a < 3; ++a) EXPECT_NEAR(w[a], area / 19.0, 1e-15 * area);
    for (int a = 3; a < 6; ++a) EXPECT_NEAR(w[a], 16.0 * area / 57.0, 1e-15 * area);
  }
  EXPECT_EQ(lumping(CellType::kTet10), Lumping::kHRZ);
  EXPECT_EQ(lumping(CellType::kTri6), Lumping::kHRZ);
  for (CellType t : {CellType::kTet4, CellType::kTri3, CellType::kHex8, CellType::kHex27,
                     CellType::kQuad4, CellType::kQuad9})
    EXPECT_EQ(lumping(t), Lumping::kRowSum);
}

// On curved tet10 and hex27 meshes the weights are positive and sum to the mesh's volume
// Σ_e Σ_q w_q det J0, which the default rules integrate exactly (det J0 is a polynomial of
// degree 3 on a P2 tetrahedron, of degree 5 per axis on a Q2 hexahedron): a degree-10 rule
// gives the same volume.
TEST(Lumping, PositiveAndSummingToTheVolumeOnCurvedElements) {
  Mesh tets = fe_test::tet_box(2, {2, 2, 2}, {1.0, 1.0, 1.0});
  fe_test::warp(&tets, 0.08);
  Mesh hexes = fe_test::box(3, 2, {1.0, 1.0, 1.0}, {2, 2, 2});
  fe_test::warp(&hexes, 0.08);
  for (const Mesh* m : {&tets, &hexes}) {
    const ReferenceGeometry g(*m), fine(*m, GradientStorage::kStored, 10);
    const Eigen::VectorXd V = lumped_volumes(*m, g);
    const double volume = g.weights().sum();
    EXPECT_GT(V.minCoeff(), 0.0) << to_string(m->cell);
    EXPECT_NEAR(V.sum(), volume, 1e-14) << to_string(m->cell);
    EXPECT_NEAR(fine.weights().sum(), volume, 1e-14) << to_string(m->cell);
    EXPECT_GT(std::abs(volume - 1.0), 1e-4);  // the warp changed the volume: not a box
    // Per element, too.
    Eigen::VectorXd w(m->nodes_per_element());
    for (Eigen::Index e = 0; e < m->num_elements(); ++e) {
      lumped_element_weights(g, lumping(m->cell), e, nullptr, w.data(), nullptr);
      EXPECT_GT(w.minCoeff(), 0.0);
      EXPECT_NEAR(w.sum(), g.weights().row(e).sum(), 1e-15);
    }
  }
}

// cloud_pullback with deformed HRZ volumes is the derivative of the deformed cloud: central
// differences of L(x, V) = <P, x> + <q, V> on a curved tet10 mesh converge at second order.
TEST(Lumping, DeformedHrzVolumesHaveExactGradients) {
  Mesh m = fe_test::tet_box(2, {2, 1, 1}, {2.0, 1.0, 1.0});
  fe_test::warp(&m, 0.05);
  const Assembler A(m, fe_test::mooney_rivlin(), Eigen::Vector3d::UnitX(), {});
  const Eigen::VectorXd u = fe_test::random_vector(A.dofs().num_dofs, 0.05, 1);
  const softhd::PointCloud c = deformed_cloud(A, u, CloudPoints::kNodes, CloudVolumes::kDeformed);
  EXPECT_NEAR(c.total_volume(), A.deformed_volume(u), 1e-13);
  EXPECT_GT(c.volumes().minCoeff(), 0.0);
  const Eigen::MatrixXd P = fe_test::random_vector(c.size() * 3, 1.0, 2).reshaped(c.size(), 3);
  const Eigen::VectorXd q = fe_test::random_vector(c.size(), 1.0, 3);
  auto L = [&](const Eigen::VectorXd& v) {
    const softhd::PointCloud d = deformed_cloud(A, v, CloudPoints::kNodes, CloudVolumes::kDeformed);
    return d.points().cwiseProduct(P).sum() + d.volumes().dot(q);
  };
  const Eigen::VectorXd g =
      cloud_pullback(A, u, CloudPoints::kNodes, CloudVolumes::kDeformed, P, q);
  const Eigen::VectorXd w = fe_test::random_vector(u.size(), 1.0, 4);
  auto err = [&](double h) { return std::abs((L(u + h * w) - L(u - h * w)) / (2 * h) - g.dot(w)); };
  EXPECT_LT(err(1e-6), 1e-8 * (1.0 + std::abs(g.dot(w))));
  EXPECT_GT(std::log2(err(1e-2) / err(5e-3)), 1.8);
}
