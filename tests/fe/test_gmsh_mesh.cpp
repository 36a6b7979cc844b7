// Meshes from Gmsh files (issue 30): regions and boundary sets from physical groups, order
// elevation against Gmsh's own second-order mesh, patch tests on every cell type read from
// Gmsh, a Gmsh-made hex27 box against the structured box, and scenes on file meshes.

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <algorithm>
#include <fstream>
#include <map>
#include <set>

#include "softhd/error.hpp"
#include "softhd/fe/assembly.hpp"
#include "softhd/fe/forward.hpp"
#include "softhd/fe/gmsh_mesh.hpp"
#include "softhd/fe/newton.hpp"
#include "softhd/fe/scene.hpp"
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
  EXPECT_FALSE(s.is_box());
  EXPECT_NEAR(s.volume, 1.0, 1e-12);
  ASSERT_EQ(s.materials.size(), 2u);
  EXPECT_DOUBLE_EQ(s.materials[1]->a(), 10.0);
  const Assembler a = s.make_assembler();
  const ControlSpace c(a.mesh(), a.geometry(), s.control_kind);
  const ForwardResult r = solve_forward(s, a, c, Eigen::VectorXd::Constant(c.size(), -0.3));
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
  const Assembler a = file.make_assembler(), b = uniform.make_assembler();
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
  ASSERT_EQ(s.control_regions, std::vector<int>{1});
  const Assembler a = s.make_assembler();
  const Mesh& mesh = a.mesh();
  const ControlSpace c = s.make_control_space(a);
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
  EXPECT_NO_THROW(check_control_bounds(s, c, mesh, c.constant(-0.5)));
  try {
    check_control_bounds(s, c, mesh, Eigen::VectorXd::Constant(c.size(), -0.5));
    ADD_FAILURE() << "a control outside the region was accepted";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("outside control.region"), std::string::npos) << e.what();
  }
  // The layer alone bends less than the whole body, and the solve converges.
  const ForwardResult layer = solve_forward(s, a, c, c.constant(-0.3));
  Scene whole = s;
  whole.control_regions.clear();
  const ControlSpace cw = whole.make_control_space(a);
  const ForwardResult all = solve_forward(whole, a, cw, cw.constant(-0.3));
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
  EXPECT_EQ(region("[\"layer\", \"body\"]").control_regions, (std::vector<int>{0, 1}));
  try {
    region("\"muscle\"");
    ADD_FAILURE() << "an unknown region was accepted";
  } catch (const FileError& e) {
    EXPECT_NE(std::string(e.what()).find("body, layer"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("control.region"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace softhd::fe
