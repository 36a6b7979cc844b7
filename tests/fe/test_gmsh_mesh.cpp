// Meshes from Gmsh files (issue 30): regions and boundary sets from physical groups, order
// elevation against Gmsh's own second-order mesh, patch tests on every cell type read from
// Gmsh, a Gmsh-made hex27 box against the structured box, and scenes on file meshes.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <fstream>
#include <iterator>
#include <map>
#include <set>
#include <sstream>

#include "softhd/control/scene.hpp"
#include "softhd/error.hpp"
#include "softhd/fe/assembly.hpp"
#include "softhd/fe/forward.hpp"
#include "softhd/fe/gmsh_mesh.hpp"
#include "softhd/fe/newton.hpp"
#include "softhd/io/msh.hpp"

namespace softhd::fe {
namespace {

std::string mesh_path(const std::string& name) {
  return std::string(SOFTHD_SOURCE_DIR) + "/tests/data/meshes/" + name;
}

Mesh read(const std::string& name, int order = 0) {
  GmshMeshOptions o;
  o.order = order;
  return mesh_from_gmsh(io::read_msh(mesh_path(name)), o);
}

// The node coordinates of a mesh, rounded to 1e-9 and sorted (independent of numbering; the
// meshes' coordinates are multiples of 1/8, so rounding cannot split two equal nodes).
std::vector<std::vector<double>> sorted_nodes(const Mesh& m) {
  std::vector<std::vector<double>> v;
  for (Eigen::Index n = 0; n < m.num_nodes(); ++n) {
    std::vector<double> p;
    for (int d = 0; d < m.dim; ++d) p.push_back(std::round(m.nodes(n, d) * 1e9) / 1e9 + 0.0);
    v.push_back(p);
  }
  std::sort(v.begin(), v.end());
  return v;
}

double volume(const Mesh& m) { return ReferenceGeometry(m).weights().sum(); }

TEST(GmshMesh, RegionsAndBoundarySetsComeFromPhysicalGroups) {
  const Mesh m = read("cube_tet4_v41.msh");
  EXPECT_EQ(m.cell, CellType::kTet4);
  EXPECT_EQ(m.dim, 3);
  ASSERT_EQ(m.region_names, (std::vector<std::string>{"body", "layer"}));
  EXPECT_NEAR(volume(m), 1.0, 1e-12);
  const ReferenceGeometry g(m);
  double layer = 0.0;  // the layer is z > 0.6: volume 0.4
  for (Eigen::Index e = 0; e < m.num_elements(); ++e)
    if (m.element_region[e] == 1) layer += g.weights().row(e).sum();
  EXPECT_NEAR(layer, 0.4, 1e-12);
  for (int n : m.face("base")) EXPECT_NEAR(m.nodes(n, 0), 0.0, 1e-12);
  for (int n : m.face("tip")) EXPECT_NEAR(m.nodes(n, 0), 1.0, 1e-12);
  EXPECT_GE(m.face("base").size(), 9u);
  try {
    m.face("bottom");
    ADD_FAILURE();
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("base, tip"), std::string::npos) << e.what();
  }
}

// "order": 2 on the tet4 file puts midside nodes where Gmsh's own second-order mesh of the
// same geometry has them (Gmsh elevates the same first-order mesh, -order 2); "order": 1 on
// the tet10 file gives the tet4 mesh.
TEST(GmshMesh, OrderElevationMatchesGmshsSecondOrderMesh) {
  const Mesh p1 = read("cube_tet4_v41.msh"), p2 = read("cube_tet10_v41.msh");
  const Mesh up = read("cube_tet4_v41.msh", 2), down = read("cube_tet10_v41.msh", 1);
  EXPECT_EQ(up.cell, CellType::kTet10);
  EXPECT_EQ(down.cell, CellType::kTet4);
  EXPECT_EQ(sorted_nodes(up), sorted_nodes(p2));
  EXPECT_EQ(sorted_nodes(down), sorted_nodes(p1));
  EXPECT_EQ(up.face("base").size(), p2.face("base").size());
  EXPECT_EQ(up.num_vertices(), p1.num_nodes());
  EXPECT_NEAR(volume(up), 1.0, 1e-12);
}

// A patch test on meshes Gmsh made: the affine displacement u = A X gives F = I + A at every
// quadrature point of every element, to round-off (tet4, tet10, hex27 and hex8 from it, and
// the 2D plate's tri6 / quad9 halves are separate files of one cell type each).
TEST(GmshMesh, AffineDisplacementGivesAUniformF) {
  Eigen::Matrix3d A;
  A << 0.1, -0.2, 0.05, 0.03, 0.07, -0.11, 0.2, 0.01, -0.04;
  for (const auto& [name, order] :
       std::vector<std::pair<std::string, int>>{{"cube_tet4_v41.msh", 0},
                                                {"cube_tet10_v41.msh", 0},
                                                {"box_hex27_v41.msh", 0},
                                                {"box_hex27_v41.msh", 1}}) {
    SCOPED_TRACE(name + " order " + std::to_string(order));
    const Assembler a(read(name, order), std::make_shared<MooneyRivlin>(1.0, 0.2, 3.0),
                      Eigen::Vector3d::UnitX(), {});
    const Mesh& m = a.mesh();
    Eigen::VectorXd u(m.num_nodes() * 3);
    for (Eigen::Index n = 0; n < m.num_nodes(); ++n)
      u.segment<3>(3 * n) = A * m.nodes.row(n).transpose();
    double worst = 0.0;
    for (Eigen::Index e = 0; e < m.num_elements(); ++e)
      for (int q = 0; q < a.geometry().points_per_element(); ++q)
        worst = std::max(worst, (a.deformation_gradient(u, e, q) - Eigen::Matrix3d::Identity() - A)
                                    .cwiseAbs()
                                    .maxCoeff());
    EXPECT_LT(worst, 1e-12);
  }
}

// The Gmsh-made 27-node hexahedral box (transfinite, recombined) is the structured box: the
// same nodes, and the same forward solve to 1e-12.
TEST(GmshMesh, Hex27BoxFromGmshIsTheStructuredBox) {
  const Mesh g = read("box_hex27_v41.msh");
  const Mesh b =
      make_box_mesh(Eigen::Vector3d::Zero(), Eigen::Vector3d(2, 1, 1), Eigen::Vector3i(4, 2, 2), 2);
  ASSERT_EQ(g.cell, CellType::kHex27);
  ASSERT_EQ(sorted_nodes(g), sorted_nodes(b));
  // Gmsh's transfinite nodes lie up to 2.6e-12 off the grid (measured; its own geometry
  // round-off), which moves the bent solution by ~1e-13 relative: give the Gmsh mesh the grid's
  // exact coordinates, so that what is compared is the element numbering and node order alone.
  Mesh gx = g;
  double off_grid = 0.0;
  for (Eigen::Index n = 0; n < gx.num_nodes(); ++n)
    for (int d = 0; d < 3; ++d) {
      const double exact = std::round(gx.nodes(n, d) * 4.0) / 4.0;  // grid spacing 1/4
      off_grid = std::max(off_grid, std::abs(gx.nodes(n, d) - exact));
      gx.nodes(n, d) = exact;
    }
  EXPECT_LT(off_grid, 1e-11);
  auto solve = [](const Mesh& m, const std::string& clamp) {
    const Assembler a(m, std::make_shared<MooneyRivlin>(1.0, 0.2, 3.0), Eigen::Vector3d::UnitX(),
                      {{clamp, {}}});
    // Converged far below the comparison's 1e-12 (the two numberings round differently, so
    // the default relative tolerance 1e-9 would leave ~1e-13 between the two solutions).
    NewtonOptions o;
    o.relative_tolerance = 1e-12;
    NewtonSolver newton(a, o);
    State s = rest_state(a);
    const Eigen::MatrixXd m_qp =
        Eigen::MatrixXd::Constant(m.num_elements(), a.geometry().points_per_element(), -0.3);
    EXPECT_TRUE(newton.solve(m_qp, &s).converged());
    // displacement by node position
    std::map<std::vector<double>, Eigen::Vector3d> by_position;
    for (Eigen::Index n = 0; n < m.num_nodes(); ++n) {
      std::vector<double> p;
      for (int d = 0; d < 3; ++d) p.push_back(std::round(m.nodes(n, d) * 1e9) / 1e9);
      by_position[p] = s.u.segment<3>(3 * n);
    }
    return by_position;
  };
  const auto ug = solve(gx, "x0"), ub = solve(b, "x0");
  double scale = 0.0, worst = 0.0;
  for (const auto& [p, u] : ub) {
    scale = std::max(scale, u.cwiseAbs().maxCoeff());
    worst = std::max(worst, (ug.at(p) - u).cwiseAbs().maxCoeff());
  }
  EXPECT_GT(scale, 1e-2);
  EXPECT_LT(worst, 1e-12 * scale);
}

TEST(GmshMesh, BadMeshesAreRefusedWithOneLine) {
  // A file with only surface elements that are not planar: Gmsh wrote no volume elements.
  io::MshFile f = io::read_msh(mesh_path("cube_tet4_v41.msh"));
  f.blocks.erase(std::remove_if(f.blocks.begin(), f.blocks.end(),
                                [](const io::MshElementBlock& b) { return b.dim == 3; }),
                 f.blocks.end());
  try {
    mesh_from_gmsh(f);
    ADD_FAILURE();
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("add a Physical Volume"), std::string::npos) << e.what();
  }
}

// One element of `cell` (an affine image of the reference cell in the plane z = 0, or with
// `flat_x` in the plane x = 0) written with the Gmsh local order `row`, element tag 42.
io::MshFile one_element_file(CellType cell, const std::vector<int>& row, bool flat_x = false) {
  const ReferenceElement& r = reference_element(cell);
  io::MshFile f;
  f.version = 4.1;
  f.nodes.resize(r.nodes, 3);
  Eigen::Matrix2d A;
  A << 1.0, 0.3, -0.2, 0.9;
  for (int a = 0; a < r.nodes; ++a) {  // internal node a is Gmsh node gmsh_order[a]
    const Eigen::Vector2d x = A * r.node_coordinates.row(a).transpose() + Eigen::Vector2d(0.5, 1.5);
    f.nodes.row(r.gmsh_order[a]) =
        flat_x ? Eigen::RowVector3d(0.0, x[0], x[1]) : Eigen::RowVector3d(x[0], x[1], 0.0);
    f.node_tags.push_back(a + 1);
  }
  io::MshElementBlock b;
  b.gmsh_type = r.gmsh_type;
  b.dim = 2;
  b.entity = 1;
  b.nodes.resize(1, r.nodes);
  for (int g = 0; g < r.nodes; ++g) b.nodes(0, g) = row[g];
  b.element_tags = {42};
  f.blocks.push_back(b);
  return f;
}

// A 2D element whose outline runs clockwise (a Gmsh surface with a clockwise curve loop) is
// the same element: the clockwise copy of each cell type (its Gmsh node lists reversed by
// hand: corners backwards, edges backwards, centre) gives the same residual as the
// counter-clockwise one at a displacement and a tension.
TEST(GmshMesh, ClockwiseSurfaceElementsAreTheSameElements) {
  const std::map<CellType, std::pair<std::vector<int>, std::vector<int>>> rows = {
      {CellType::kTri3, {{0, 1, 2}, {0, 2, 1}}},
      {CellType::kTri6, {{0, 1, 2, 3, 4, 5}, {0, 2, 1, 5, 4, 3}}},
      {CellType::kQuad4, {{0, 1, 2, 3}, {0, 3, 2, 1}}},
      {CellType::kQuad9, {{0, 1, 2, 3, 4, 5, 6, 7, 8}, {0, 3, 2, 1, 7, 6, 5, 4, 8}}}};
  for (const auto& [cell, pair] : rows) {
    const Mesh ccw = mesh_from_gmsh(one_element_file(cell, pair.first));
    const Mesh cw = mesh_from_gmsh(one_element_file(cell, pair.second));
    ASSERT_EQ(ccw.nodes, cw.nodes);
    const auto mr =
        std::vector<std::shared_ptr<const Material>>{std::make_shared<MooneyRivlin>(1.0, 0.2, 3.0)};
    FiberField a0;
    a0.values = Eigen::Vector3d(0.8, 0.6, 0.0);
    const Assembler a(ccw, mr, a0, {}), b(cw, mr, a0, {});  // b threw "inverted" before
    const Eigen::VectorXd u = 0.05 * Eigen::VectorXd::Random(ccw.num_nodes() * 2);
    const Eigen::MatrixXd m = Eigen::MatrixXd::Constant(1, a.geometry().points_per_element(), -0.4);
    double Pa = 0.0, Pb = 0.0;
    Eigen::VectorXd Ra, Rb;
    ASSERT_TRUE(a.evaluate(u, m, &Pa, &Ra, nullptr));
    ASSERT_TRUE(b.evaluate(u, m, &Pb, &Rb, nullptr));
    EXPECT_NEAR(Pa, Pb, 1e-13 * std::abs(Pa)) << to_string(cell);
    EXPECT_LT((Ra - Rb).norm(), 1e-13 * Ra.norm()) << to_string(cell);
    EXPECT_NEAR(a.geometry().weights().sum(), b.geometry().weights().sum(), 1e-14);
  }
  // A flat mesh outside the plane z = const: the message says which plane it lies in.
  try {
    mesh_from_gmsh(one_element_file(CellType::kTri3, {0, 1, 2}, true));
    ADD_FAILURE();
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("in a plane with normal (1, 0, 0) rather than z = const"),
              std::string::npos)
        << e.what();
  }
}

// Messages about an element name its Gmsh tag: an inverted tetrahedron, a P2 element folded
// at a vertex (det dX/dξ < 0 there although positive at every quadrature point).
TEST(GmshMesh, BadElementsAreNamedByTheirGmshTag) {
  io::MshFile f = io::read_msh(mesh_path("cube_tet4_v41.msh"));
  io::MshElementBlock* body = nullptr;
  for (io::MshElementBlock& b : f.blocks)
    if (b.dim == 3 && !body) body = &b;
  ASSERT_NE(body, nullptr);
  ASSERT_GT(body->nodes.rows(), 3);
  std::swap(body->nodes(3, 1), body->nodes(3, 2));
  const std::string tag = std::to_string(body->element_tags[3]);
  ASSERT_NE(tag, "3");
  try {
    ReferenceGeometry g(mesh_from_gmsh(f));
    ADD_FAILURE();
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("element " + tag + " is inverted"), std::string::npos)
        << e.what();
  }
  // The reference tetrahedron with its edge node between vertices 0 and 1 at x = 0.22: along
  // that edge dX/dt = (2.4 t − 0.2, 0, 0) runs backwards for t < 1/12, where no quadrature
  // point lies (det dX/dξ > 0 at all of them, computed below).
  Mesh m;
  m.cell = CellType::kTet10;
  m.order = 2;
  m.nodes = reference_element(CellType::kTet10).node_coordinates;
  m.nodes(4, 0) = 0.22;
  m.elements = Connectivity(1, 10);
  for (int a = 0; a < 10; ++a) m.elements(0, a) = a;
  m.element_region = Eigen::VectorXi::Zero(1);
  m.element_tags = {77};
  Eigen::MatrixXd xi;
  Eigen::VectorXd w;
  cell_quadrature(CellType::kTet10, reference_element(CellType::kTet10).default_quadrature_degree,
                  &xi, &w);
  for (Eigen::Index q = 0; q < xi.rows(); ++q) {
    double N[10], dN[30];
    const Eigen::Vector3d p = xi.row(q).transpose();
    shape_functions(CellType::kTet10, p.data(), N, dN);
    Eigen::Matrix3d J = Eigen::Matrix3d::Zero();  // J_iK = Σ_a X_a,i dN_a/dξ_K
    for (int a = 0; a < 10; ++a)
      for (int i = 0; i < 3; ++i)
        for (int K = 0; K < 3; ++K) J(i, K) += m.nodes(a, i) * dN[a * 3 + K];
    EXPECT_GT(J.determinant(), 0.0) << q;
  }
  try {
    ReferenceGeometry g(m);
    ADD_FAILURE();
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("element 77 is folded at its local node 0"),
              std::string::npos)
        << e.what();
  }
}

// A $NodeData fibre field is a field of axes: with the signs of some nodes flipped, the
// nodes order 2 adds get the same axes; a zero vector is refused naming the node's tag.
TEST(GmshMesh, NodeDataFibresAreAxes) {
  io::MshFile f = io::read_msh(mesh_path("fields.msh"));
  io::MshDataBlock& d = f.data[0];
  ASSERT_EQ(d.name, "fibres");
  for (Eigen::Index k = 0; k < d.values.rows(); ++k) {
    const Eigen::RowVector3d X = f.nodes.row(static_cast<Eigen::Index>(d.tags[k]));
    d.values.row(k) << 1.0, 0.3 * X[1], 0.2 * X[2];
  }
  GmshMeshOptions two;
  two.order = 2;
  const FiberField aligned = gmsh_fiber_field(f, "fibres", two);
  d.values.row(1) *= -1.0;
  d.values.row(3) *= -1.0;
  const FiberField flipped = gmsh_fiber_field(f, "fibres", two);
  ASSERT_EQ(aligned.values.cols(), flipped.values.cols());
  ASSERT_GT(aligned.values.cols(), 5);
  for (Eigen::Index n = 0; n < aligned.values.cols(); ++n)
    EXPECT_NEAR(std::abs(aligned.values.col(n).dot(flipped.values.col(n))),
                aligned.values.col(n).squaredNorm(), 1e-14)
        << n;
  d.values.row(3).setZero();
  try {
    gmsh_fiber_field(f, "fibres", two);
    ADD_FAILURE();
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("node " + std::to_string(f.node_tags[d.tags[3]]) +
                                         " a zero or non-finite fibre"),
              std::string::npos)
        << e.what();
  }
}

// A scene on the two-part cube: materials per region, a clamp on a physical surface, solved;
// unknown names refused listing the file's.
TEST(GmshMesh, ASceneOnAFileMesh) {
  const std::string dir = ::testing::TempDir();
  const std::string scene = R"({
    "name": "cube",
    "mesh": {"type": "gmsh", "file": ")" +
                            mesh_path("cube_tet10_v41.msh") + R"("},
    "materials": {"body": {"model": "mooney_rivlin", "a": 1, "b": 0.2, "c": 3},
                  "layer": {"model": "mooney_rivlin", "a": 10, "b": 2, "c": 30}},
    "fibers": [1, 0, 0], "clamp": ["base"],
    "control": {"space": "vertex", "lower": -1, "upper": 0}})";
  const Scene s = parse_scene(scene, dir + "/cube.json");
  EXPECT_FALSE(s.body.is_box());
  EXPECT_NEAR(s.body.volume, 1.0, 1e-12);
  ASSERT_EQ(s.body.materials.size(), 2u);
  EXPECT_DOUBLE_EQ(s.body.materials[1]->a(), 10.0);
  const Assembler a = s.body.make_assembler();
  const ControlSpace c(a.mesh(), a.geometry(), s.body.control_kind);
  const ForwardResult r = solve_forward(s.body, a, c, Eigen::VectorXd::Constant(c.size(), -0.3));
  EXPECT_TRUE(r.summary.converged());
  auto refused = [&](const std::string& from, const std::string& to, const std::string& needle) {
    std::string t = scene;
    t.replace(t.find(from), from.size(), to);
    try {
      parse_scene(t, dir + "/cube.json");
      ADD_FAILURE() << to;
    } catch (const FileError& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  refused("\"clamp\": [\"base\"]", "\"clamp\": [\"bottom\"]", "base, tip");
  refused("\"layer\": {", "\"lyer\": {", "unknown region 'lyer'");
  refused("cube_tet10_v41.msh", "missing.msh", "missing.msh");
}

// {"file", "per": "node"} on a first-order file that "order": 2 elevates: one row per file
// node (vertex) is taken, the added nodes getting their edge's axis; a uniform ±x field so
// written (random signs) is the uniform field [1, 0, 0]. A zero row is refused naming the
// file and the row; a wrong count says how many rows either way.
TEST(GmshMesh, NodeFibreFilesOnAnElevatedMesh) {
  const std::string dir = ::testing::TempDir();
  const Eigen::Index vertices = read("cube_tet4_v41.msh").num_nodes();
  auto write = [&](Eigen::Index rows, Eigen::Index zero_row) {
    std::ofstream out(dir + "/fib.txt");
    for (Eigen::Index k = 0; k < rows; ++k)
      out << (k == zero_row ? 0 : (k * 5) % 3 == 1 ? -1 : 1) << " 0 0\n";
  };
  const std::string head =
      R"({"mesh": {"type": "gmsh", "order": 2, "file": ")" + mesh_path("cube_tet4_v41.msh") + R"("},
    "material": {"model": "mooney_rivlin", "a": 1, "b": 0.2, "c": 3}, "clamp": ["base"],
    "control": {"space": "vertex", "lower": -1, "upper": 0}, "fibers": )";
  write(vertices, -1);
  const Scene file = parse_scene(head + R"({"file": "fib.txt", "per": "node"}})", dir + "/c.json");
  const Scene uniform = parse_scene(head + "[1, 0, 0]}", dir + "/c.json");
  const Assembler a = file.body.make_assembler(), b = uniform.body.make_assembler();
  ASSERT_GT(a.mesh().num_nodes(), vertices);
  const Eigen::VectorXd u = a.dofs().expand(0.002 * Eigen::VectorXd::Random(a.dofs().num_free));
  const Eigen::MatrixXd m =
      Eigen::MatrixXd::Constant(a.mesh().num_elements(), a.geometry().points_per_element(), -0.5);
  double Pa = 0.0, Pb = 0.0;
  Eigen::VectorXd Ra, Rb;
  ASSERT_TRUE(a.evaluate(u, m, &Pa, &Ra, nullptr));
  ASSERT_TRUE(b.evaluate(u, m, &Pb, &Rb, nullptr));
  EXPECT_NEAR(Pa, Pb, 1e-13 * std::abs(Pb));
  EXPECT_LT((Ra - Rb).norm(), 1e-13 * Rb.norm());
  auto refused = [&](const std::vector<std::string>& needles) {
    try {
      parse_scene(head + R"({"file": "fib.txt", "per": "node"}})", dir + "/c.json");
      ADD_FAILURE();
    } catch (const FileError& e) {
      for (const std::string& n : needles)
        EXPECT_NE(std::string(e.what()).find(n), std::string::npos) << e.what();
    }
  };
  write(vertices, 2);
  refused({"fib.txt: row 3 is a zero or non-finite fibre vector"});
  write(vertices + 1, -1);
  refused({"fib.txt", "or one per vertex, " + std::to_string(vertices)});
}

// control.region: the control acts on the named volume only. On the two-part cube the
// layer is z > 0.6, so a vertex control acts exactly at the vertices with z >= 0.6 (checked
// from the coordinates, not from the element lists), m = 0 at the quadrature points of the
// body, the transpose map is the adjoint of the forward one, and values outside are refused.
TEST(GmshMesh, AControlRestrictedToARegionActsThereOnly) {
  const std::string dir = ::testing::TempDir();
  const std::string scene = R"({
    "mesh": {"type": "gmsh", "file": ")" +
                            mesh_path("cube_tet10_v41.msh") + R"("},
    "materials": {"body": {"model": "mooney_rivlin", "a": 1, "b": 0.2, "c": 3},
                  "layer": {"model": "mooney_rivlin", "a": 10, "b": 2, "c": 30}},
    "fibers": [1, 0, 0], "clamp": ["base"],
    "control": {"space": "vertex", "region": "layer", "lower": -1, "upper": 0}})";
  const Scene s = parse_scene(scene, dir + "/cube.json");
  ASSERT_EQ(s.body.control_regions, std::vector<int>{1});
  const Assembler a = s.body.make_assembler();
  const Mesh& mesh = a.mesh();
  const ControlSpace c = s.body.make_control_space(a);
  const Eigen::VectorXd ones = c.constant(1.0);
  int acting = 0;
  for (Eigen::Index k = 0; k < c.size(); ++k) {
    const double z = mesh.nodes(mesh.vertex_nodes[k], 2);
    EXPECT_EQ(ones[k], z >= 0.6 - 1e-12 ? 1.0 : 0.0) << "vertex " << k << " z " << z;
    acting += ones[k] == 1.0;
  }
  EXPECT_GT(acting, 0);
  EXPECT_LT(acting, c.size());
  // m = 1 on the layer's vertices: m_q = 1 in the layer (the P1 functions sum to 1), 0 in
  // the body, whatever the values at body-only vertices.
  const Eigen::VectorXd m = ones + (Eigen::VectorXd::Ones(c.size()) - ones) * 7.0;
  const Eigen::MatrixXd mq = c.to_quadrature(m);
  for (Eigen::Index e = 0; e < mesh.num_elements(); ++e)
    for (Eigen::Index q = 0; q < mq.cols(); ++q)
      EXPECT_NEAR(mq(e, q), mesh.element_region[e] == 1 ? 1.0 : 0.0, 1e-14) << e;
  // <v, T m> = <T' v, m> for random v and m.
  const Eigen::MatrixXd v = Eigen::MatrixXd::Random(mq.rows(), mq.cols());
  const Eigen::VectorXd r = Eigen::VectorXd::Random(c.size());
  EXPECT_NEAR((v.array() * c.to_quadrature(r).array()).sum(), c.from_quadrature(v).dot(r), 1e-11);
  // The regularisation integrates over the layer only: (M/2) ∫ 1² = M · 0.4 / 2.
  EXPECT_NEAR(c.regularisation(ones, 2.0, 0.0, nullptr), 0.4, 1e-12);
  // Bounds: [0, 0] outside the layer; a nonzero value there is refused, naming the region.
  EXPECT_NO_THROW(check_control_bounds(s.body, c, mesh, c.constant(-0.5)));
  try {
    check_control_bounds(s.body, c, mesh, Eigen::VectorXd::Constant(c.size(), -0.5));
    ADD_FAILURE() << "a control outside the region was accepted";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("outside control.region"), std::string::npos) << e.what();
  }
  // The layer alone bends less than the whole body, and the solve converges.
  const ForwardResult layer = solve_forward(s.body, a, c, c.constant(-0.3));
  Scene whole = s;
  whole.body.control_regions.clear();
  const ControlSpace cw = whole.body.make_control_space(a);
  const ForwardResult all = solve_forward(whole.body, a, cw, cw.constant(-0.3));
  ASSERT_TRUE(layer.summary.converged());
  ASSERT_TRUE(all.summary.converged());
  EXPECT_GT(layer.state.u.norm(), 0.0);
  EXPECT_LT(layer.state.u.norm(), all.state.u.norm());
  // Unknown names are refused listing the mesh's regions; a list of names is accepted.
  auto region = [&](const std::string& value) {
    std::string t = scene;
    const std::string from = "\"region\": \"layer\"";
    t.replace(t.find(from), from.size(), "\"region\": " + value);
    return parse_scene(t, dir + "/cube.json");
  };
  EXPECT_EQ(region("[\"layer\", \"body\"]").body.control_regions, (std::vector<int>{0, 1}));
  try {
    region("\"muscle\"");
    ADD_FAILURE() << "an unknown region was accepted";
  } catch (const FileError& e) {
    EXPECT_NE(std::string(e.what()).find("body, layer"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("control.region"), std::string::npos) << e.what();
  }
}

// Two unit cubes of six tetrahedra each (Kuhn's split along the main diagonal), "left" on
// [0, 1]³ and "right" on [1 + gap, 2 + gap] × [0, 1]², as MSH 2.2 text. `shared`: the right
// cube uses the left one's nodes at x = 1 (gap 0, a conforming mesh); otherwise it has nodes
// of its own. Lower-dimensional groups: "base" (the face x = 0), "corner" (a point at the
// origin), "edge" (the line x = y = 0), "pad" (a triangle on nodes no tetrahedron uses) and
// "empty" (a name without elements).
std::string two_cubes(double gap, bool shared) {
  std::vector<Eigen::Vector3d> X;
  std::vector<std::array<int, 8>> cube(2);  // node ids (1-based) by corner bits (x, y, z)
  for (int c = 0; c < 2; ++c)
    for (int k = 0; k < 8; ++k) {
      if (c == 1 && shared && !(k & 1)) {
        cube[1][k] = cube[0][k | 1];
        continue;
      }
      X.emplace_back(c * (1.0 + gap) + (k & 1), (k >> 1) & 1, (k >> 2) & 1);
      cube[c][k] = static_cast<int>(X.size());
    }
  const int pad = static_cast<int>(X.size()) + 1;
  for (const Eigen::Vector3d& p :
       {Eigen::Vector3d(5, 5, 5), Eigen::Vector3d(6, 5, 5), Eigen::Vector3d(5, 6, 5)})
    X.push_back(p);
  std::vector<std::string> el = {
      "15 2 3 3 " + std::to_string(cube[0][0]),
      "1 2 4 4 " + std::to_string(cube[0][0]) + " " + std::to_string(cube[0][4]),
      "2 2 11 11 " + std::to_string(cube[0][0]) + " " + std::to_string(cube[0][2]) + " " +
          std::to_string(cube[0][6]),
      "2 2 11 11 " + std::to_string(cube[0][0]) + " " + std::to_string(cube[0][6]) + " " +
          std::to_string(cube[0][4]),
      "2 2 12 12 " + std::to_string(pad) + " " + std::to_string(pad + 1) + " " +
          std::to_string(pad + 2)};
  const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (int c = 0; c < 2; ++c)
    for (const auto& p : perms) {
      std::array<int, 4> t = {0, 1 << p[0], (1 << p[0]) | (1 << p[1]), 7};
      auto at = [&](int k) { return X[cube[c][t[k]] - 1]; };
      if ((at(1) - at(0)).cross(at(2) - at(0)).dot(at(3) - at(0)) < 0) std::swap(t[2], t[3]);
      std::string line = "4 2 " + std::to_string(c + 1) + " " + std::to_string(c + 1);
      for (int k : t) line += " " + std::to_string(cube[c][k]);
      el.push_back(line);
    }
  std::ostringstream s;
  s << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n7\n0 3 \"corner\"\n"
    << "1 4 \"edge\"\n2 11 \"base\"\n2 12 \"pad\"\n2 13 \"empty\"\n3 1 \"left\"\n"
    << "3 2 \"right\"\n$EndPhysicalNames\n$Nodes\n"
    << X.size() << "\n";
  for (std::size_t n = 0; n < X.size(); ++n)
    s << n + 1 << " " << X[n][0] << " " << X[n][1] << " " << X[n][2] << "\n";
  s << "$EndNodes\n$Elements\n" << el.size() << "\n";
  for (std::size_t e = 0; e < el.size(); ++e) s << e + 1 << " " << el[e] << "\n";
  s << "$EndElements\n";
  return s.str();
}

// The scene on two_cubes(gap, shared), clamped at `clamp` (a JSON array); its error or "".
std::string scene_error(double gap, bool shared, const std::string& clamp) {
  const std::string dir = ::testing::TempDir();
  std::ofstream(dir + "/two_cubes.msh") << two_cubes(gap, shared);
  const std::string scene = R"({"mesh": {"type": "gmsh", "file": "two_cubes.msh"},
    "material": {"model": "mooney_rivlin", "a": 1, "b": 0.2, "c": 3},
    "fibers": [1, 0, 0], "clamp": )" +
                            clamp + R"(,
    "control": {"space": "vertex", "lower": -1, "upper": 0}})";
  try {
    parse_scene(scene, dir + "/two.json");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

// A body that nothing holds (docs/formulation.md §7) is refused before any solve, naming the
// group or the part: a clamp group with no node of the body, a clamp on a point or a line
// (rotations free), a second volume the clamp does not reach; a volume group as a clamp is
// named as such. The conforming two-cube body clamped at its base face is accepted.
TEST(GmshMesh, ABodyThatNothingHoldsIsRefused) {
  EXPECT_EQ(scene_error(0.0, true, R"(["base"])"), "");
  auto expect = [](const std::string& e, const std::string& needle) {
    EXPECT_NE(e.find(needle), std::string::npos) << e;
    EXPECT_EQ(e.find('\n'), std::string::npos) << e;
  };
  expect(scene_error(0.0, true, R"(["pad"])"),
         "key 'clamp/constraints' does not hold the body: group 'pad' has no node");
  expect(scene_error(0.0, true, R"(["base", "empty"])"), "group 'empty' has no node of the body");
  expect(scene_error(0.0, true, R"(["corner"])"),
         "'corner' leaves regions 'left', 'right' free to move rigidly (3 of its 6");
  expect(scene_error(0.0, true, R"(["edge"])"),
         "'edge' leaves regions 'left', 'right' free to move rigidly (1 of its 6 rigid motions, "
         "e.g. a rotation about an axis along (0, 0, 1))");
  expect(scene_error(0.5, false, R"(["base"])"), "nothing holds region 'right'");
  expect(scene_error(0.0, true, R"(["left"])"),
         "'left' is a region of the body (a physical volume), not a boundary group");
}

// Two volumes meshed without BooleanFragments touch at nodes they do not share: refused,
// naming both regions and the fix. The cube pair has 4 such pairs (the corners of x = 1).
TEST(GmshMesh, VolumesThatDoNotShareTheirInterfaceNodesAreRefused) {
  const io::MshFile conforming = io::parse_msh(two_cubes(0.0, true), "two.msh");
  EXPECT_EQ(mesh_from_gmsh(conforming).num_nodes(), 12);
  try {
    mesh_from_gmsh(io::parse_msh(two_cubes(0.0, false), "two.msh"));
    ADD_FAILURE() << "a non-conforming mesh was accepted";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(
        std::string(e.what()).find("regions 'left' and 'right' touch at 4 coincident nodes "
                                   "that they do not share (e.g. nodes 2 and 9 at (1, 0, 0))"),
        std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("BooleanFragments"), std::string::npos) << e.what();
  }
  // The same from Gmsh (tests/data/meshes/two_boxes.geo), with the file named.
  try {
    read_gmsh_mesh(mesh_path("two_boxes_nonconforming.msh"));
    ADD_FAILURE() << "a non-conforming mesh was accepted";
  } catch (const FileError& e) {
    EXPECT_NE(std::string(e.what()).find("two_boxes_nonconforming.msh: mesh: regions 'left' and "
                                         "'right' touch at"),
              std::string::npos)
        << e.what();
  }
}

// `what` throws an InvalidArgument whose message holds `needle`.
template <class F>
void expect_refused(F what, const std::string& needle) {
  try {
    what();
    ADD_FAILURE() << "accepted; expected: " << needle;
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
  }
}

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// A file written by `gmsh -save_all` with a volume in no physical group: its tetrahedra
// joined region 'body' silently. Refused, naming the entity, in the file's name.
TEST(GmshMesh, AVolumeInNoPhysicalGroupIsRefusedNamingIt) {
  const io::MshFile f = io::read_msh(mesh_path("save_all.msh"));
  expect_refused([&] { mesh_from_gmsh(f); },
                 "mesh: entity 2 of dimension 3 is in no physical group while other parts of the "
                 "body are (a file saved with -save_all?): add it to a Physical Volume");
  expect_refused([&] { read_gmsh_mesh(mesh_path("save_all.msh")); },
                 "save_all.msh: mesh: entity 2");
  // Without any physical group the whole file is the one region "body", as before.
  io::MshFile none = f;
  for (io::MshElementBlock& b : none.blocks) b.physical_tags.clear();
  EXPECT_EQ(mesh_from_gmsh(none).region_names, std::vector<std::string>{"body"});
}

// Two physical volumes of one name: "materials.body" named one and control.region acted on
// the first only. Refused when the mesh is read.
TEST(GmshMesh, TwoRegionsOfOneNameAreRefused) {
  std::string text = slurp(mesh_path("cube_tet4_v41.msh"));
  text.replace(text.find("3 2 \"layer\""), 11, "3 2 \"body\"");
  expect_refused([&] { mesh_from_gmsh(io::parse_msh(text, "twice.msh")); },
                 "mesh: physical groups 1 and 2 of dimension 3 are both named 'body': region "
                 "names must differ");
}

// An element listed twice (another tag, the same nodes in any order): the unit cube's volume
// was 1 + the element's. Refused naming both Gmsh tags.
TEST(GmshMesh, AnElementListedTwiceIsRefusedNamingItsTags) {
  io::MshFile f = io::read_msh(mesh_path("cube_tet4_v41.msh"));
  EXPECT_NEAR(volume(mesh_from_gmsh(f)), 1.0, 1e-12);
  std::int64_t last = 0, first = -1;
  for (const io::MshElementBlock& b : f.blocks)
    for (std::int64_t t : b.element_tags) last = std::max(last, t);
  for (const io::MshElementBlock& b : f.blocks)
    if (b.dim == 3 && first < 0) {
      io::MshElementBlock copy = b;
      copy.nodes = b.nodes.topRows(1);
      std::swap(copy.nodes(0, 0), copy.nodes(0, 3));  // the same nodes, another order
      copy.element_tags = {last + 1};
      first = b.element_tags[0];
      f.blocks.push_back(copy);
      break;
    }
  expect_refused([&] { mesh_from_gmsh(f); }, "mesh: elements " + std::to_string(first) + " and " +
                                                 std::to_string(last + 1) +
                                                 " have the same nodes (an element listed twice)");
}

// The scale: 1e-200 was reported as "inverted", 1e300 gave a volume of inf; both are outside
// the range the message gives. Coordinates that overflow or underflow once scaled are refused
// naming the span; a scene prints sizes with %g (1e-12, not 0.000000).
TEST(GmshMesh, TheScaleIsWithinARangeAndSizesAreShownWithExponents) {
  GmshMeshOptions o;
  for (double scale : {1e-200, 1e300, 0.0, -1.0}) {
    o.scale = scale;
    expect_refused([&] { read_gmsh_mesh(mesh_path("cube_tet4_v41.msh"), o); },
                   "scale must be in [1e-12, 1e12], got ");
  }
  o.scale = 1e-12;
  double v = 0.0;
  read_gmsh_mesh(mesh_path("cube_tet4_v41.msh"), o, &v);
  EXPECT_NEAR(v, 1e-36, 1e-48);  // (1e-12)^3
  io::MshFile f = io::read_msh(mesh_path("cube_tet4_v41.msh"));
  f.nodes *= 1e300;
  o.scale = 1e12;
  expect_refused([&] { mesh_from_gmsh(f, o); }, "mesh: the mesh spans inf (scale 1e+12)");
  f.nodes *= 1e-300;
  f.nodes *= 1e-150;  // coordinates up to 1e-150
  o.scale = 1e-12;
  expect_refused([&] { mesh_from_gmsh(f, o); }, "mesh: the mesh spans 1e-162 (scale 1e-12)");
  const std::string scene = R"({"mesh": {"type": "gmsh", "file": ")" +
                            mesh_path("cube_tet4_v41.msh") + R"(", "scale": SCALE},
    "material": {"model": "mooney_rivlin", "a": 1, "b": 0.2, "c": 3},
    "fibers": [1, 0, 0], "clamp": ["base"],
    "control": {"space": "vertex", "lower": -1, "upper": 0}})";
  auto with = [&](const std::string& scale) {
    std::string t = scene;
    t.replace(t.find("SCALE"), 5, scale);
    return parse_scene(t, ::testing::TempDir() + "/s.json");
  };
  expect_refused([&] { with("1e-200"); }, "key 'mesh.scale' must be in [1e-12, 1e12], got 1e-200");
  expect_refused([&] { with("1e-12"); }, "key 'mesh.scale' gives a body of size 1e-12: softhd");
  expect_refused([&] { with("1e12"); }, "key 'mesh.scale' gives a body of size 1e+12: softhd");
}

// The memory estimate from the file's counts: on a Gmsh hex27 box the box's own estimate
// (the same counts and bytes), and on the tetrahedral cube, at its order and elevated, the
// estimate from its exact counts (nodes, and node pairs sharing an element, counted here).
TEST(GmshMesh, TheMemoryEstimateFromTheCountsIsTheMeshes) {
  io::MshCounts counts;
  ASSERT_TRUE(io::scan_msh_counts(slurp(mesh_path("box_hex27_v41.msh")), &counts));
  const MeshSize box = box_mesh_size(Eigen::Vector3d(4, 2, 2), 2);
  const MeshSize file = gmsh_mesh_size(counts);
  EXPECT_EQ(file.nodes, box.nodes);
  EXPECT_EQ(file.elements, box.elements);
  EXPECT_EQ(file.dofs, box.dofs);
  EXPECT_EQ(file.quadrature_points, box.quadrature_points);
  EXPECT_DOUBLE_EQ(file.bytes, box.bytes);
  ASSERT_TRUE(io::scan_msh_counts(slurp(mesh_path("cube_tet4_v41.msh")), &counts));
  for (int order : {1, 2}) {
    GmshMeshOptions o;
    o.order = order;
    const Mesh m = read("cube_tet4_v41.msh", order);
    std::set<std::pair<int, int>> pairs;
    for (Eigen::Index e = 0; e < m.num_elements(); ++e)
      for (Eigen::Index a = 0; a < m.elements.cols(); ++a)
        for (Eigen::Index b = 0; b < m.elements.cols(); ++b)
          pairs.insert({m.elements(e, a), m.elements(e, b)});
    const ReferenceGeometry g(m);
    const MeshSize exact =
        mesh_size(3, static_cast<double>(m.num_nodes()), static_cast<double>(m.num_elements()),
                  m.nodes_per_element(), 4, static_cast<int>(g.weights().cols()),
                  static_cast<double>(pairs.size()));
    const MeshSize estimate = gmsh_mesh_size(counts, o);
    EXPECT_EQ(estimate.elements, m.num_elements());
    EXPECT_NEAR(estimate.nodes, m.num_nodes(), 0.25 * m.num_nodes()) << order;
    EXPECT_NEAR(estimate.bytes, exact.bytes, 0.25 * exact.bytes) << order;
  }
}

// A file mesh above the memory limit is refused with the box's message, from the counts,
// before its elements are parsed (a copy whose element rows are broken still gets it), in
// read_gmsh_mesh and in a scene (the CLI's --max-memory and Python's max_memory_gib).
TEST(GmshMesh, AFileMeshAboveTheMemoryLimitIsRefusedBeforeItsElementsAreRead) {
  const std::string path = ::testing::TempDir() + "/broken_elements.msh";
  std::string text = slurp(mesh_path("cube_tet4_v41.msh"));
  const std::size_t tets = text.find("\n3 1 4 ");  // the first tetrahedron block's header
  ASSERT_NE(tets, std::string::npos);
  const std::size_t row = text.find('\n', tets + 1) + 1;
  text.replace(row, text.find(' ', row) - row, "x");  // its first element tag
  std::ofstream(path, std::ios::binary) << text;
  expect_refused([&] { read_gmsh_mesh(path); }, "broken_elements.msh:");  // a FileError
  try {
    read_gmsh_mesh(path, {}, nullptr, 1e3);
    ADD_FAILURE() << "not refused";
  } catch (const ResourceError& e) {
    EXPECT_NE(std::string(e.what()).find(path + ": the mesh has 166 nodes and 481 elements: it "
                                                "needs about "),
              std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("GiB, above the memory limit of 9.31e-07 GiB (raise the "
                                         "limit: --max-memory GIB)"),
              std::string::npos)
        << e.what();
  }
  const std::string scene = R"({"mesh": {"type": "gmsh", "file": ")" + path + R"("},
    "material": {"model": "mooney_rivlin", "a": 1, "b": 0.2, "c": 3},
    "fibers": [1, 0, 0], "clamp": ["base"],
    "control": {"space": "vertex", "lower": -1, "upper": 0}})";
  EXPECT_THROW(parse_scene(scene, ::testing::TempDir() + "/s.json", 1e3), ResourceError);
}

}  // namespace
}  // namespace softhd::fe
