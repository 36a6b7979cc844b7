// Grid sequencing (lib/src/fe/grid_sequencing.cpp): the transfers are exact on the fields
// their shape functions reproduce, the level count follows the documented rule, and the
// sequenced start leads Newton to the state it reaches from rest.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "softhd/error.hpp"
#include "softhd/fe/grid_sequencing.hpp"

using namespace softhd::fe;

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

TEST(GridSequencing, ProlongationReproducesQuadraticFields) {
  const Eigen::Vector3d lo(0, 0, 0), hi(2.0, 1.0, 0.5);
  const Mesh coarse = make_box_mesh(lo, hi, Eigen::Vector3i(2, 2, 1), 2);
  const Mesh fine = make_box_mesh(lo, hi, Eigen::Vector3i(4, 4, 2), 2);
  Eigen::VectorXd uc(coarse.num_nodes() * 3);
  for (Eigen::Index n = 0; n < coarse.num_nodes(); ++n)
    uc.segment<3>(3 * n) = quadratic(coarse.nodes.row(n).transpose());
  const Eigen::VectorXd uf = prolongate(coarse, uc, fine);
  for (Eigen::Index n = 0; n < fine.num_nodes(); ++n) {
    const Eigen::Vector3d expected = quadratic(fine.nodes.row(n).transpose());
    EXPECT_LT((uf.segment<3>(3 * n) - expected).norm(), 1e-13) << "node " << n;
  }
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
  ASSERT_EQ(cells_of(s.cells), std::vector<int>({50, 4, 2}));
  EXPECT_EQ(cells_of(coarsened(s).cells), std::vector<int>({25, 2, 1}));
  GridSequencingOptions automatic;
  // 25 x 2 x 1 = 50 elements >= 32; the next, 25 x 1 x 1 = 25, is too small.
  EXPECT_EQ(grid_levels(s, automatic), 1);
  automatic.min_elements = 51;
  EXPECT_EQ(grid_levels(s, automatic), 0);
  GridSequencingOptions explicit_levels;
  explicit_levels.levels = 2;  // 25 x 1 x 1 is allowed when asked for
  EXPECT_EQ(grid_levels(s, explicit_levels), 2);
  explicit_levels.levels = 3;  // 25 x 1 x 1 has no even axis
  EXPECT_THROW(grid_levels(s, explicit_levels), softhd::InvalidArgument);
  explicit_levels.levels = -2;
  EXPECT_THROW(grid_levels(s, explicit_levels), softhd::InvalidArgument);
}

TEST(GridSequencing, SequencedStartReachesTheStateNewtonReachesFromRest) {
  Scene s = load_scene(kTorsion);
  s.cells.resize(3);
  s.cells << 8, 2, 2;
  const Assembler a = s.make_assembler();
  const ControlSpace c(a.mesh(), a.geometry(), s.control_kind);
  const Eigen::VectorXd m = Eigen::VectorXd::Constant(c.size(), -2e5);
  NewtonOptions options;
  options.displacement_tolerance = 1e-10;
  GridSequencingOptions grid;
  grid.levels = 1;
  GridSequencingReport report;
  State start = grid_sequenced_start(s, a, m, options, grid, &report);
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
