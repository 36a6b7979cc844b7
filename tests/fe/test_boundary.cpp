// The boundary surface of a mesh and the boundary cloud (fe/boundary.hpp, fe/cloud.hpp;
// docs/formulation.md §8.6): closed, outward, the right area, exact area gradients.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <map>
#include <string>
#include <utility>

#include "fe_test_util.hpp"
#include "softhd/error.hpp"
#include "softhd/fe/boundary.hpp"
#include "softhd/fe/cloud.hpp"
#include "softhd/fe/gmsh_mesh.hpp"

using namespace softhd::fe;
using softhd::scan::TriangleSurface;

namespace {

Mesh read(const std::string& name) {
  return read_gmsh_mesh(std::string(SOFTHD_SOURCE_DIR) + "/tests/data/meshes/" + name);
}

// Every directed edge (a, b) once and its reverse (b, a) once: a closed, consistently
// oriented surface.
void expect_closed(const TriangleSurface& s) {
  std::map<std::pair<int, int>, int> edges;
  for (Eigen::Index t = 0; t < s.triangles.rows(); ++t)
    for (int c = 0; c < 3; ++c) ++edges[{s.triangles(t, c), s.triangles(t, (c + 1) % 3)}];
  for (const auto& [e, n] : edges) {
    EXPECT_EQ(n, 1) << "edge " << e.first << "-" << e.second;
    const auto r = edges.find({e.second, e.first});
    EXPECT_TRUE(r != edges.end() && r->second == 1) << "edge " << e.first << "-" << e.second;
  }
}

// The enclosed volume by the divergence theorem, ∮ x·n dA / 3 = Σ_t (a·(b × c)) / 6: positive
// and equal to the volume only if every triangle points outward.
double enclosed_volume(const TriangleSurface& s) {
  double v = 0.0;
  for (Eigen::Index t = 0; t < s.triangles.rows(); ++t) {
    const Eigen::Vector3d a = s.points.row(s.triangles(t, 0)), b = s.points.row(s.triangles(t, 1)),
                          c = s.points.row(s.triangles(t, 2));
    v += a.dot(b.cross(c)) / 6.0;
  }
  return v;
}

}  // namespace

// A box's boundary: closed, outward (enclosed volume = the box's), area 2(ab + bc + ca), and
// exactly the nodes on its faces.
TEST(Boundary, BoxIsClosedOutwardWithItsArea) {
  for (int order : {1, 2}) {
    const Mesh m = fe_test::box(3, order, {2.0, 1.0, 0.5}, {3, 2, 2});
    const TriangleSurface s = boundary_surface(m, Eigen::VectorXd::Zero(m.num_nodes() * 3));
    expect_closed(s);
    EXPECT_NEAR(enclosed_volume(s), 1.0, 1e-12);
    EXPECT_NEAR(lumped_areas(s).sum(), 2 * (2.0 + 1.0 + 0.5), 1e-12);
    const int n = 2 * order;  // nodes per axis − 1 on the first axis is 3 order
    const int inner = (3 * order - 1) * (n - 1) * (n - 1);
    EXPECT_EQ(static_cast<Eigen::Index>(s.points.rows()), m.num_nodes() - inner);
    EXPECT_EQ(s.triangles.rows(), (order == 1 ? 2 : 8) * 2 * (3 * 2 + 2 * 2 + 3 * 2));
  }
}

// Gmsh tetrahedra of two regions: the faces between the regions are not boundary; P1 and P2
// (four flat triangles a facet), closed and outward, the unit cube's area and volume.
TEST(Boundary, TetrahedraOfTwoRegions) {
  for (const char* file : {"cube_tet4_v41.msh", "cube_tet10_v41.msh"}) {
    const Mesh m = read(file);
    const TriangleSurface s = boundary_surface(m, Eigen::VectorXd::Zero(m.num_nodes() * 3));
    expect_closed(s);
    EXPECT_NEAR(enclosed_volume(s), 1.0, 1e-12) << file;
    EXPECT_NEAR(lumped_areas(s).sum(), 6.0, 1e-12) << file;
    EXPECT_GT(lumped_areas(s).minCoeff(), 0.0);
  }
}

// In a deformed P1 configuration the facets stay flat: the enclosed volume is the deformed
// volume ∫ J dX exactly.
TEST(Boundary, DeformedTetrahedraEncloseTheDeformedVolume) {
  const Mesh m = read("cube_tet4_v41.msh");
  const Assembler A(m, fe_test::mooney_rivlin(), Eigen::Vector3d::UnitX(), {});
  const Eigen::VectorXd u = fe_test::random_vector(m.num_nodes() * 3, 0.03, 7);
  const TriangleSurface s = boundary_surface(m, u);
  EXPECT_NEAR(enclosed_volume(s), A.deformed_volume(u), 1e-12);
}

// The boundary cloud's pullback is the derivative of L(x, V) = <P, x> + <q, V>: central
// differences with observed order 2, for every cell type of order 1 and 2.
TEST(Boundary, CloudPullbackTaylor) {
  const Mesh meshes[] = {fe_test::box(3, 1, {2.0, 1.0, 0.5}, {2, 2, 1}),
                         fe_test::box(3, 2, {2.0, 1.0, 0.5}, {2, 1, 1}), read("cube_tet4_v41.msh"),
                         read("cube_tet10_v41.msh")};
  for (const Mesh& m : meshes)
    for (CloudVolumes vol : {CloudVolumes::kReference, CloudVolumes::kDeformed}) {
      const Assembler A(m, fe_test::mooney_rivlin(), Eigen::Vector3d::UnitX(), {});
      const Eigen::VectorXd u = fe_test::random_vector(A.dofs().num_dofs, 0.05, 1);
      const softhd::PointCloud c = deformed_cloud(A, u, CloudPoints::kBoundaryNodes, vol);
      const Eigen::MatrixXd P = fe_test::random_vector(c.size() * 3, 1.0, 2).reshaped(c.size(), 3);
      const Eigen::VectorXd q = fe_test::random_vector(c.size(), 1.0, 3);
      auto L = [&](const Eigen::VectorXd& v) {
        const softhd::PointCloud d = deformed_cloud(A, v, CloudPoints::kBoundaryNodes, vol);
        return d.points().cwiseProduct(P).sum() + d.volumes().dot(q);
      };
      const Eigen::VectorXd g = cloud_pullback(A, u, CloudPoints::kBoundaryNodes, vol, P, q);
      const Eigen::VectorXd w = fe_test::random_vector(u.size(), 1.0, 4);
      auto err = [&](double h) {
        return std::abs((L(u + h * w) - L(u - h * w)) / (2 * h) - g.dot(w));
      };
      EXPECT_LT(err(1e-6), 1e-7 * (1.0 + std::abs(g.dot(w))));
      if (vol == CloudVolumes::kDeformed) {
        const double e1 = err(1e-2), e2 = err(5e-3);
        ASSERT_GT(e1, 1e-11);  // the areas are not linear in u: the test can fail
        EXPECT_NEAR(std::log2(e1 / e2), 2.0, 0.2);
      }
    }
}

// Only 3D meshes have a boundary surface here; a wrong-sized u is refused.
TEST(Boundary, RefusesTwoDimensionsAndWrongSizes) {
  const Mesh m2 = fe_test::box(2, 1, {1.0, 1.0, 1.0}, {2, 2, 1});
  EXPECT_THROW(boundary_facets(m2), softhd::InvalidArgument);
  const Mesh m3 = fe_test::box(3, 1, {1.0, 1.0, 1.0}, {1, 1, 1});
  EXPECT_THROW(boundary_surface(m3, Eigen::VectorXd::Zero(5)), softhd::InvalidArgument);
}
