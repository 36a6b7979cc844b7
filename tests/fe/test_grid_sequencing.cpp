// Grid sequencing (lib/src/fe/grid_sequencing.cpp): the transfers are exact on the fields
// their shape functions reproduce, the level count follows the documented rule, and the
// sequenced start leads Newton to the state it reaches from rest; for box halving and for
// p-sequencing of file meshes (P1 on the vertices of curved P2 cells).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "softhd/control/scene.hpp"
#include "softhd/error.hpp"
#include "softhd/fe/grid_sequencing.hpp"
#include "softhd/fe/interpolation.hpp"

using namespace softhd::fe;
using softhd::load_scene;
using softhd::parse_scene;
using softhd::Scene;

namespace {

const std::string kTorsion = std::string(SOFTHD_SOURCE_DIR) + "/data/scenes/torsion.json";

// A quadratic field per component (reproduced exactly by Q2 shape functions).
Eigen::Vector3d quadratic(const Eigen::Vector3d& X) {
  const double x = X[0], y = X[1], z = X[2];
  return {1.0 + 0.3 * x - 0.2 * x * x + 0.1 * x * y, -0.5 * y * z + 0.7 * z * z,
          0.2 + x * z - 0.4 * y * y};
}

std::vector<int> cells_of(const Eigen::VectorXi& cells) {
  return std::vector<int>(cells.data(), cells.data() + cells.size());
}

}  // namespace

// The largest error at the fine nodes of the quadratic field prolongated from the Q2 box of
// `coarse_cells` to the one of `fine_cells` (the same box).
double prolongation_error(const Eigen::Vector3i& coarse_cells, const Eigen::Vector3i& fine_cells) {
  const Eigen::Vector3d lo(0, 0, 0), hi(2.0, 1.0, 0.5);
  const Mesh coarse = make_box_mesh(lo, hi, coarse_cells, 2);
  const Mesh fine = make_box_mesh(lo, hi, fine_cells, 2);
  Eigen::VectorXd uc(coarse.num_nodes() * 3);
  for (Eigen::Index n = 0; n < coarse.num_nodes(); ++n)
    uc.segment<3>(3 * n) = quadratic(coarse.nodes.row(n).transpose());
  const Eigen::VectorXd uf = prolongate(coarse, uc, fine);
  double worst = 0.0;
  for (Eigen::Index n = 0; n < fine.num_nodes(); ++n)
    worst =
        std::max(worst, (uf.segment<3>(3 * n) - quadratic(fine.nodes.row(n).transpose())).norm());
  return worst;
}

TEST(GridSequencing, ProlongationReproducesQuadraticFields) {
  EXPECT_LT(prolongation_error(Eigen::Vector3i(2, 2, 1), Eigen::Vector3i(4, 4, 2)), 1e-13);
}

// A rounded level (Halving::rounded: 5 x 3 x 1 is not nested in 9 x 5 x 1) is reached by
// interpolation at points: still exact on the fields its shape functions reproduce.
TEST(GridSequencing, ProlongationFromANonNestedBoxReproducesQuadraticFields) {
  EXPECT_LT(prolongation_error(Eigen::Vector3i(5, 3, 1), Eigen::Vector3i(9, 5, 1)), 1e-12);
}

TEST(GridSequencing, ControlFieldsAreEvaluatedByTheirOwnInterpolation) {
  const Mesh mesh = make_box_mesh(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(3, 1, 1),
                                  Eigen::Vector3i(3, 1, 1), 2);
  // Vertex controls: a trilinear field is reproduced at any point.
  auto trilinear = [](const Eigen::Vector3d& X) {
    return 2.0 - X[0] + 0.5 * X[1] * X[2] + 0.25 * X[0] * X[1] * X[2];
  };
  Eigen::VectorXd mv(mesh.num_vertices());
  for (Eigen::Index k = 0; k < mv.size(); ++k)
    mv[k] = trilinear(mesh.nodes.row(mesh.vertex_nodes[k]).transpose());
  Eigen::MatrixXd X(3, 3);
  X << 0.3, 0.2, 0.9, 1.7, 0.5, 0.5, 2.99, 0.01, 0.4;
  const Eigen::VectorXd v = control_at(mesh, ControlKind::kVertex, mv, X);
  for (int p = 0; p < 3; ++p) EXPECT_NEAR(v[p], trilinear(X.row(p).transpose()), 1e-14);
  // Element controls: the value of the containing element.
  const Eigen::VectorXd me = Eigen::Vector3d(-1.0, -2.0, -3.0);
  const Eigen::VectorXd w = control_at(mesh, ControlKind::kElement, me, X);
  EXPECT_EQ(w[0], -1.0);
  EXPECT_EQ(w[1], -2.0);
  EXPECT_EQ(w[2], -3.0);
  EXPECT_THROW(control_at(mesh, ControlKind::kElement, me, Eigen::RowVector3d(4.0, 0.5, 0.5)),
               softhd::InvalidArgument);
}

TEST(GridSequencing, LevelsHalveTheEvenAxesWhileTheCoarseMeshIsLargeEnough) {
  Scene s = load_scene(kTorsion);  // 50 x 4 x 2
  ASSERT_EQ(cells_of(s.body.cells), std::vector<int>({50, 4, 2}));
  EXPECT_EQ(cells_of(coarsened(s.body).cells), std::vector<int>({25, 2, 1}));
  GridSequencingOptions automatic;
  // 25 x 2 x 1 = 50 elements >= 32; the next, 25 x 1 x 1 = 25, is too small.
  EXPECT_EQ(grid_levels(s.body, automatic), 1);
  automatic.min_elements = 51;
  EXPECT_EQ(grid_levels(s.body, automatic), 0);
  GridSequencingOptions explicit_levels;
  explicit_levels.levels = 2;  // 25 x 1 x 1 is allowed when asked for
  EXPECT_EQ(grid_levels(s.body, explicit_levels), 2);
  explicit_levels.levels = 3;  // 25 x 1 x 1 has no even axis
  EXPECT_THROW(grid_levels(s.body, explicit_levels), softhd::InvalidArgument);
  explicit_levels.levels = -2;
  EXPECT_THROW(grid_levels(s.body, explicit_levels), softhd::InvalidArgument);
}

// Halving::rounded halves the even axes as nested does, and a box with none every axis of
// at least 4 cells to (n + 1) / 2 (the bending plate: 50 x 5 x 2 -> 25 x 5 x 1 -> 13 x 3 x 1);
// coarser_levels counts while the level keeps min_elements (125, 39, then 7 x 3 x 1 = 21).
TEST(GridSequencing, RoundedHalvingCoarsensABoxWithNoEvenAxis) {
  Scene s = load_scene(kTorsion);
  s.body.cells = (Eigen::VectorXi(3) << 50, 5, 2).finished();
  EXPECT_EQ(cells_of(coarsened(s.body, Halving::rounded).cells), std::vector<int>({25, 5, 1}));
  s.body.cells = (Eigen::VectorXi(3) << 25, 5, 1).finished();
  EXPECT_THROW(coarsened(s.body), softhd::InvalidArgument);  // nested: no even axis
  EXPECT_EQ(cells_of(coarsened(s.body, Halving::rounded).cells), std::vector<int>({13, 3, 1}));
  s.body.cells = (Eigen::VectorXi(3) << 3, 1, 1).finished();
  EXPECT_THROW(coarsened(s.body, Halving::rounded), softhd::InvalidArgument);
  s.body.cells = (Eigen::VectorXi(3) << 50, 5, 2).finished();
  EXPECT_EQ(coarser_levels(s.body, Halving::rounded, 32), 2);
  EXPECT_EQ(coarser_levels(s.body, Halving::rounded, 40), 1);
  EXPECT_EQ(coarser_levels(s.body, Halving::nested, 32), 1);  // 25 x 5 x 1, then no even axis
}

// A MeshHierarchy is the body and its levels coarsened() in turn (level 0 the body itself);
// asking for more levels than the body has is refused saying how many it has.
TEST(GridSequencing, MeshHierarchyIsTheBodyCoarsenedInTurn) {
  Scene s = load_scene(kTorsion);
  s.body.cells = (Eigen::VectorXi(3) << 50, 5, 2).finished();
  const MeshHierarchy rounded(s.body, Halving::rounded, 3);
  ASSERT_EQ(rounded.size(), 4);
  EXPECT_EQ(cells_of(rounded.level(0).cells), std::vector<int>({50, 5, 2}));
  EXPECT_EQ(cells_of(rounded.level(1).cells), std::vector<int>({25, 5, 1}));
  EXPECT_EQ(cells_of(rounded.level(2).cells), std::vector<int>({13, 3, 1}));
  EXPECT_EQ(cells_of(rounded.level(3).cells), std::vector<int>({7, 3, 1}));  // 3 < 4 kept
  EXPECT_EQ(MeshHierarchy(s.body, Halving::nested, 0).size(), 1);
  try {
    MeshHierarchy(s.body, Halving::nested, 2);  // 25 x 5 x 1 has no even axis
    ADD_FAILURE() << "two nested levels of 50 x 5 x 2 accepted";
  } catch (const softhd::InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("2 coarser levels asked for, but the body has 1"),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW(MeshHierarchy(s.body, Halving::nested, -1), softhd::InvalidArgument);
}

TEST(GridSequencing, SequencedStartReachesTheStateNewtonReachesFromRest) {
  Scene s = load_scene(kTorsion);
  s.body.cells.resize(3);
  s.body.cells << 8, 2, 2;
  const Assembler a = s.body.make_assembler();
  const ControlSpace c(a.mesh(), a.geometry(), s.body.control_kind);
  const Eigen::VectorXd m = Eigen::VectorXd::Constant(c.size(), -2e5);
  NewtonOptions options;
  options.displacement_tolerance = 1e-10;
  GridSequencingOptions grid;
  grid.levels = 1;
  GridSequencingReport report;
  State start = grid_sequenced_start(s.body, a, m, options, grid, &report);
  ASSERT_EQ(report.levels.size(), 1u);
  EXPECT_EQ(cells_of(report.levels[0].cells), std::vector<int>({4, 1, 1}));
  EXPECT_TRUE(report.levels[0].newton.converged());
  EXPECT_FALSE(report.fell_back_to_rest);
  EXPECT_GT(start.u.norm(), 0.0);
  State rest = rest_state(a);
  NewtonSolver n1(a, options), n2(a, options);
  const Eigen::MatrixXd m_qp = c.to_quadrature(m);
  const NewtonSummary from_start = n1.solve(m_qp, &start);
  const NewtonSummary from_rest = n2.solve(m_qp, &rest);
  ASSERT_TRUE(from_start.converged() && from_rest.converged());
  EXPECT_LT(from_start.newton_iterations, from_rest.newton_iterations);
  EXPECT_LT((start.u - rest.u).lpNorm<Eigen::Infinity>(), 1e-9 * rest.u.lpNorm<Eigen::Infinity>());
}

// p-sequencing (a file mesh of order 2: P1/Q1 on its vertices first, docs/formulation.md
// §3.7).
namespace {

std::string mesh_path(const std::string& name) {
  return std::string(SOFTHD_SOURCE_DIR) + "/tests/data/meshes/" + name;
}

// The curved tet10 cylinder (radius 0.5, length 2 along x; midside nodes on the mantle lie
// on the circle), clamped at x = 0.
const std::string kCylinder = mesh_path("cylinder_tet10_v41.msh");

// A scene on a mesh file: `mesh_keys` after "file", the control space, the materials, the
// clamped group.
Scene file_scene(const std::string& file, const std::string& mesh_keys, const std::string& space,
                 const std::string& materials, const std::string& clamp = "base") {
  const std::string text =
      R"({"name": "p", "mesh": {"type": "gmsh", "file": ")" + file + "\"" + mesh_keys +
      R"(}, "materials": )" + materials + R"(, "fibers": [1, 0, 0], "clamp": [")" + clamp +
      R"("], "control": {"space": ")" + space + R"(", "lower": -1, "upper": 0}})";
  return parse_scene(text, ::testing::TempDir() + "/p.json");
}

const std::string kOneMaterial =
    R"({"body": {"model": "mooney_rivlin", "a": 1, "b": 0.2, "c": 3}})";
const std::string kTwoMaterials =
    R"({"body": {"model": "mooney_rivlin", "a": 1, "b": 0.2, "c": 3},
        "layer": {"model": "mooney_rivlin", "a": 10, "b": 2, "c": 30}})";

// A linear field per component, X ↦ A X + b.
Eigen::MatrixXd linear_field(const Eigen::MatrixXd& X) {
  Eigen::Matrix3d A;
  A << 0.3, -0.2, 0.5, 0.1, 0.7, -0.4, -0.6, 0.25, 0.15;
  return (X * A.transpose()).rowwise() + Eigen::RowVector3d(0.1, -0.2, 0.3);
}

}  // namespace

TEST(PSequencing, TheLinearMeshIsTheVerticesOfTheSameCurvedCells) {
  const Scene s = file_scene(kCylinder, "", "vertex", kOneMaterial);
  const Mesh& p2 = *s.body.file_mesh;
  ASSERT_EQ(p2.cell, CellType::kTet10);
  const Mesh p1 = linear_mesh(p2);
  EXPECT_EQ(p1.cell, CellType::kTet4);
  EXPECT_EQ(p1.num_nodes(), p2.num_vertices());
  EXPECT_TRUE(same_cells(p1, p2));
  EXPECT_TRUE(same_cells(p2, p1));
  EXPECT_FALSE(same_cells(p2, make_box_mesh(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 1, 1),
                                            Eigen::Vector3i(1, 1, 1), 2)));
  // Boundary sets: the vertices among each set's nodes.
  for (const char* name : {"base", "tip"}) {
    std::vector<int> expected;
    for (Eigen::Index k = 0; k < p2.num_vertices(); ++k) {
      const std::vector<int>& set = p2.face(name);
      if (std::binary_search(set.begin(), set.end(), p2.vertex_nodes[k]))
        expected.push_back(static_cast<int>(k));
    }
    EXPECT_FALSE(expected.empty());
    EXPECT_EQ(p1.face(name), expected) << name;
  }
  // The mesh is curved: some P2 nodes lie outside the straight-sided P1 mesh, where a point
  // search would fail.
  const PointLocator locator(p1);
  Eigen::VectorXd xi;
  int outside = 0;
  for (Eigen::Index n = 0; n < p2.num_nodes(); ++n)
    outside += locator.locate(p2.nodes.row(n).transpose(), &xi) < 0;
  EXPECT_GT(outside, 10);
  EXPECT_THROW(interpolate_nodal(p1, locator, linear_field(p1.nodes), p2.nodes, nullptr),
               softhd::InvalidArgument);
}

TEST(PSequencing, VertexFieldsAreInterpolatedExactlyThroughTheReferenceCoordinates) {
  const Scene s = file_scene(kCylinder, "", "vertex", kOneMaterial);
  const Mesh& p2 = *s.body.file_mesh;
  const Mesh p1 = linear_mesh(p2);
  const Eigen::MatrixXd f = linear_field(p1.nodes);
  const Eigen::MatrixXd u = transfer_nodal(p1, f, p2);
  // Vertices keep their values; an edge node gets the mean of its edge's two vertices (the
  // P1 field is linear along the edge in reference coordinates; tet10 edges 4:(0,1) 5:(1,2)
  // 6:(2,0) 7:(3,0) 8:(3,2) 9:(3,1)), wherever the curved edge put the node.
  const int edges[6][2] = {{0, 1}, {1, 2}, {2, 0}, {3, 0}, {3, 2}, {3, 1}};
  double moved = 0.0;  // the largest distance of an edge node from its chord's midpoint
  for (Eigen::Index e = 0; e < p2.num_elements(); ++e) {
    for (int k = 0; k < 4; ++k) EXPECT_EQ(u.row(p2.elements(e, k)), f.row(p1.elements(e, k))) << e;
    for (int k = 0; k < 6; ++k) {
      const int a = p1.elements(e, edges[k][0]), b = p1.elements(e, edges[k][1]);
      const Eigen::RowVector3d mean = 0.5 * (f.row(a) + f.row(b));
      EXPECT_LT((u.row(p2.elements(e, 4 + k)) - mean).norm(), 1e-15 * (1 + mean.norm()));
      moved = std::max(
          moved,
          (p2.nodes.row(p2.elements(e, 4 + k)) - 0.5 * (p1.nodes.row(a) + p1.nodes.row(b))).norm());
    }
  }
  EXPECT_GT(moved, 1e-3);  // curved: the nodes are off the chords
  // The P2 field equals the P1 field at any reference point of every element.
  double N2[10], dN2[30], N1[4], dN1[12];
  for (Eigen::Index e = 0; e < p2.num_elements(); ++e) {
    const double xi[3] = {0.1 + 0.003 * (e % 50), 0.2, 0.15 + 0.002 * (e % 40)};
    shape_functions(CellType::kTet10, xi, N2, dN2);
    shape_functions(CellType::kTet4, xi, N1, dN1);
    Eigen::RowVector3d v2 = Eigen::RowVector3d::Zero(), v1 = Eigen::RowVector3d::Zero();
    for (int a = 0; a < 10; ++a) v2 += N2[a] * u.row(p2.elements(e, a));
    for (int b = 0; b < 4; ++b) v1 += N1[b] * f.row(p1.elements(e, b));
    EXPECT_LT((v2 - v1).norm(), 1e-14 * (1 + v1.norm())) << e;
  }
  // Back onto the vertices: the P2 field's vertex values, exactly.
  EXPECT_EQ(transfer_nodal(p2, u, p1), f);
  // prolongate (the grid-sequencing transfer) takes this path: no point search.
  const Eigen::VectorXd uf = prolongate(p1, f.transpose().reshaped(), p2);
  EXPECT_EQ(uf, Eigen::VectorXd(u.transpose().reshaped()));
}

TEST(PSequencing, StraightSidedP2ReproducesALinearFieldAtEveryNode) {
  // A first-order file with "order": 2: straight-sided P2, midside nodes on the chords.
  const Scene s =
      file_scene(mesh_path("cube_tet4_v41.msh"), R"(, "order": 2)", "vertex", kTwoMaterials);
  const Mesh& p2 = *s.body.file_mesh;
  ASSERT_EQ(p2.cell, CellType::kTet10);
  const Mesh p1 = linear_mesh(p2);
  const Eigen::MatrixXd u = transfer_nodal(p1, linear_field(p1.nodes), p2);
  const Eigen::MatrixXd expected = linear_field(p2.nodes);
  EXPECT_LT((u - expected).lpNorm<Eigen::Infinity>(), 1e-14);
}

TEST(PSequencing, FileMeshesOfOrderTwoGetOneLinearLevel) {
  Scene s = file_scene(kCylinder, "", "vertex", kOneMaterial);
  GridSequencingOptions automatic, one, two;
  one.levels = 1;
  two.levels = 2;
  EXPECT_EQ(grid_levels(s.body, automatic), 1);
  EXPECT_EQ(grid_levels(s.body, one), 1);
  try {  // P1 has no coarser level: the message says how many levels there are
    grid_levels(s.body, two);
    ADD_FAILURE();
  } catch (const softhd::InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("2 coarser levels asked for, but the body has 1"),
              std::string::npos)
        << e.what();
  }
  automatic.min_elements = static_cast<int>(s.body.file_mesh->num_elements()) + 1;
  EXPECT_EQ(grid_levels(s.body, automatic), 0);
  // Fibres per node are restricted to the vertices.
  s.body.fiber_field.kind = FiberField::Kind::kNode;
  s.body.fiber_field.values.resize(3, s.body.file_mesh->num_nodes());
  for (Eigen::Index n = 0; n < s.body.file_mesh->num_nodes(); ++n)
    s.body.fiber_field.values.col(n) =
        Eigen::Vector3d(1.0, 0.2 * s.body.file_mesh->nodes(n, 1), 0.1);
  const Body c = coarsened(s.body);
  EXPECT_EQ(c.order, 1);
  EXPECT_FALSE(c.is_box());
  ASSERT_EQ(c.fiber_field.values.cols(), s.body.file_mesh->num_vertices());
  for (Eigen::Index k = 0; k < s.body.file_mesh->num_vertices(); ++k)
    EXPECT_EQ(c.fiber_field.values.col(k),
              s.body.fiber_field.values.col(s.body.file_mesh->vertex_nodes[k]));
  EXPECT_EQ(c.make_assembler().mesh().cell, CellType::kTet4);
  // A first-order file has no coarser level.
  const Scene p1 = file_scene(mesh_path("cube_tet4_v41.msh"), "", "vertex", kTwoMaterials);
  EXPECT_EQ(grid_levels(p1.body, GridSequencingOptions{}), 0);
  EXPECT_THROW(grid_levels(p1.body, one), softhd::InvalidArgument);
  try {
    coarsened(p1.body);
    ADD_FAILURE();
  } catch (const softhd::InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("of order 1"), std::string::npos) << e.what();
  }
}

namespace {

// The p-sequenced start and the start from rest reach the same state (Newton's tolerance).
void expect_p_sequencing_reaches_the_state_from_rest(const Scene& s, const Eigen::VectorXd& m,
                                                     const GridSequencingOptions& grid = {}) {
  const Assembler a = s.body.make_assembler();
  const ControlSpace c(a.mesh(), a.geometry(), s.body.control_kind);
  ASSERT_EQ(m.size(), c.size());
  NewtonOptions options;
  options.displacement_tolerance = 1e-10;
  options.absolute_tolerance = s.body.residual_floor();
  GridSequencingReport report;
  State start = grid_sequenced_start(s.body, a, m, options, grid, &report);
  ASSERT_EQ(report.levels.size(), 1u);
  const CellType linear = reference_element(a.mesh().cell).linear;
  EXPECT_EQ(report.levels[0].cell, linear);
  EXPECT_EQ(report.levels[0].nodes, a.mesh().num_vertices());
  EXPECT_TRUE(report.levels[0].newton.converged());
  EXPECT_FALSE(report.fell_back_to_rest);
  const std::string line = std::string("coarse level (") +
                           (linear == CellType::kTet4 ? "P1" : "Q1") +
                           " on the vertices: " + to_string(linear);
  EXPECT_NE(report.BriefReport().find(line), std::string::npos) << report.BriefReport();
  EXPECT_GT(start.u.norm(), 0.0);
  State rest = rest_state(a);
  NewtonSolver n1(a, options), n2(a, options);
  const Eigen::MatrixXd m_qp = c.to_quadrature(m);
  const NewtonSummary from_start = n1.solve(m_qp, &start);
  const NewtonSummary from_rest = n2.solve(m_qp, &rest);
  ASSERT_TRUE(from_start.converged() && from_rest.converged());
  EXPECT_LT((start.u - rest.u).lpNorm<Eigen::Infinity>(), 1e-9 * rest.u.lpNorm<Eigen::Infinity>());
}

}  // namespace

TEST(PSequencing, CurvedP2WithVertexControlsReachesTheStateFromRest) {
  const Scene s = file_scene(kCylinder, "", "vertex", kOneMaterial);
  Eigen::VectorXd m(s.body.file_mesh->num_vertices());
  for (Eigen::Index k = 0; k < m.size(); ++k)  // stronger towards the top: bends and stretches
    m[k] = -0.3 - 0.4 * (s.body.file_mesh->nodes(s.body.file_mesh->vertex_nodes[k], 2) + 0.5);
  expect_p_sequencing_reaches_the_state_from_rest(s, m);
}

TEST(PSequencing, TwoMaterialsWithElementControlsReachTheStateFromRest) {
  const Scene s =
      file_scene(mesh_path("cube_tet4_v41.msh"), R"(, "order": 2)", "element", kTwoMaterials);
  Eigen::VectorXd m(s.body.file_mesh->num_elements());
  for (Eigen::Index e = 0; e < m.size(); ++e)
    m[e] = -0.2 - 0.5 * s.body.file_mesh->nodes(s.body.file_mesh->elements(e, 0), 1);
  expect_p_sequencing_reaches_the_state_from_rest(s, m);
}

TEST(PSequencing, Hex27FromGmshStartsFromItsQ1Level) {
  // 4 x 2 x 2 hexahedra: fewer than the automatic choice's 32 elements, so asked for.
  const Scene s = file_scene(mesh_path("box_hex27_v41.msh"), "", "vertex", kOneMaterial, "x0");
  ASSERT_EQ(s.body.file_mesh->cell, CellType::kHex27);
  EXPECT_EQ(grid_levels(s.body, GridSequencingOptions{}), 0);
  GridSequencingOptions one;
  one.levels = 1;
  Eigen::VectorXd m(s.body.file_mesh->num_vertices());
  for (Eigen::Index k = 0; k < m.size(); ++k)
    m[k] = -0.2 - 0.4 * s.body.file_mesh->nodes(s.body.file_mesh->vertex_nodes[k], 2);
  expect_p_sequencing_reaches_the_state_from_rest(s, m, one);
}
