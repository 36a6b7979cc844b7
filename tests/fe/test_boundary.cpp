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
#include "softhd/fe/dofs.hpp"
#include "softhd/fe/gmsh_mesh.hpp"

using namespace softhd::fe;
using softhd::TriangleSurface;

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

// A body that nothing holds (docs/formulation.md §7): check_rigid_motions refuses constraints
// that leave a rigid motion of a connected part free. The cases' free motions are known by
// hand: a node fixes translations only; an edge along z leaves the rotation about z; planes
// held in their normal component (symmetry planes) x = 0 and y = 0 leave the translation
// along z; a second, disjoint box is held by nothing.
namespace {

Mesh unit_box(int dim) {
  return make_box_mesh(Eigen::VectorXd::Zero(dim), Eigen::VectorXd::Ones(dim),
                       Eigen::VectorXi::Constant(dim, 2), 1);
}

// The nodes of `m` where pred(X) holds, as the boundary set `name`.
template <class Pred>
void add_set(Mesh* m, const std::string& name, Pred pred) {
  std::vector<int>& s = m->boundary_nodes[name];
  for (Eigen::Index n = 0; n < m->num_nodes(); ++n)
    if (pred(Eigen::VectorXd(m->nodes.row(n).transpose()))) s.push_back(static_cast<int>(n));
}

std::string refusal(const Mesh& m, const std::vector<DirichletConstraint>& c) {
  try {
    check_rigid_motions(m, c);
  } catch (const softhd::InvalidArgument& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(RigidMotions, HeldBodiesPass) {
  Mesh m = unit_box(3);
  EXPECT_EQ(refusal(m, {{"x0", {}}}), "");
  // Three symmetry planes, each held in its normal component: all six motions fixed.
  EXPECT_EQ(refusal(m, {{"x0", {0}}, {"y0", {1}}, {"z0", {2}}}), "");
  EXPECT_EQ(refusal(unit_box(2), {{"x0", {}}}), "");
  // A face far smaller than the body still fixes it (rank, not size).
  Mesh slab = make_box_mesh(Eigen::Vector3d::Zero(), Eigen::Vector3d(100.0, 1.0, 1.0),
                            Eigen::Vector3i(100, 1, 1), 1);
  EXPECT_EQ(refusal(slab, {{"x0", {}}}), "");
}

TEST(RigidMotions, FreeMotionsAreRefusedNamingThePart) {
  Mesh m = unit_box(3);
  add_set(&m, "corner", [](const Eigen::VectorXd& X) { return X.norm() < 1e-12; });
  add_set(&m, "edge", [](const Eigen::VectorXd& X) { return X[0] == 0.0 && X[1] == 0.0; });
  m.boundary_nodes["pad"];  // a group with no node of the body
  std::string e = refusal(m, {{"corner", {}}});
  EXPECT_NE(e.find("'corner' leaves region 'body' free"), std::string::npos) << e;
  EXPECT_NE(e.find("3 of its 6 rigid motions"), std::string::npos) << e;
  e = refusal(m, {{"edge", {}}});
  EXPECT_NE(e.find("1 of its 6 rigid motions, e.g. a rotation about an axis along (0, 0, 1)"),
            std::string::npos)
      << e;
  e = refusal(m, {{"x0", {0}}, {"y0", {1}}});
  EXPECT_NE(e.find("'x0', 'y0' leave region 'body' free"), std::string::npos) << e;
  EXPECT_NE(e.find("1 of its 6 rigid motions, e.g. a translation along (0, 0, 1)"),
            std::string::npos)
      << e;
  e = refusal(m, {{"x0", {}}, {"pad", {}}});
  EXPECT_NE(e.find("group 'pad' has no node of the body"), std::string::npos) << e;
  Mesh flat = unit_box(2);
  add_set(&flat, "corner", [](const Eigen::VectorXd& X) { return X.norm() < 1e-12; });
  e = refusal(flat, {{"corner", {}}});
  EXPECT_NE(e.find("1 of its 3 rigid motions, e.g. a rotation"), std::string::npos) << e;
}

TEST(RigidMotions, EveryConnectedPartMustBeHeld) {
  // Two unit boxes 1 apart: "left" clamped at x = 0, "right" held by nothing.
  const Mesh a = unit_box(3);
  Mesh m = a;
  m.nodes.conservativeResize(2 * a.num_nodes(), 3);
  m.nodes.bottomRows(a.num_nodes()) = a.nodes.rowwise() + Eigen::RowVector3d(2.0, 0.0, 0.0);
  m.elements.conservativeResize(2 * a.num_elements(), Eigen::NoChange);
  m.elements.bottomRows(a.num_elements()) = a.elements.array() + static_cast<int>(a.num_nodes());
  m.element_region = Eigen::VectorXi::Zero(2 * a.num_elements());
  m.element_region.tail(a.num_elements()).setOnes();
  m.region_names = {"left", "right"};
  m.cells.resize(0);  // no longer the structured box
  EXPECT_NE(refusal(m, {{"x0", {}}}).find("nothing holds region 'right'"), std::string::npos);
  m.element_region.setZero();  // one region in two parts: the part is named by its place
  const std::string e = refusal(m, {{"x0", {}}});
  EXPECT_NE(e.find("nothing holds the part of region 'left' around (2.5, 0.5, 0.5)"),
            std::string::npos)
      << e;
  add_set(&m, "far", [](const Eigen::VectorXd& X) { return X[0] == 3.0; });
  EXPECT_EQ(refusal(m, {{"x0", {}}, {"far", {}}}), "");
}

TEST(RigidMotions, AVolumeGroupAsAClampIsNamedAsSuch) {
  Mesh m = unit_box(3);
  m.cells.resize(0);  // as from a Gmsh file, whose regions are physical volumes
  try {
    m.face("body");
    ADD_FAILURE();
  } catch (const softhd::InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("'body' is a region of the body (a physical volume), "
                                         "not a boundary group: a clamp needs a surface group"),
              std::string::npos)
        << e.what();
  }
}
