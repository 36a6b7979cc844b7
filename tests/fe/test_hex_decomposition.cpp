// The sub-hexahedra of a 3D mesh (lib/src/fe/hex_decomposition.hpp): conforming (their
// boundary is a closed, consistently oriented surface), positively oriented, exact on affine
// cells (their volume and their boundary's enclosed volume are the box's), and converging at
// second order on curved cells (a body of known volume).

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>

#include "common/surface_bvh.hpp"
#include "fe/hex_decomposition.hpp"
#include "fe/unstructured_meshes.hpp"
#include "hausdorff/cell_distance.hpp"
#include "softhd/error.hpp"

using namespace softhd;
using fe::HexDecomposition;

namespace {

// The box [0,1]² × [0, 0.5] meshed by n³ cells of a 3D type (tetrahedra: Kuhn's 6 per cube).
fe::Mesh body(fe::CellType type, int n) {
  const std::array<double, 3> len = {1.0, 1.0, 0.5};
  if (type == fe::CellType::kTet4 || type == fe::CellType::kTet10)
    return fe_test::tet_box(type == fe::CellType::kTet4 ? 1 : 2, {n, n, n}, len);
  return fe::make_box_mesh(Eigen::Vector3d::Zero(), Eigen::Vector3d(len[0], len[1], len[2]),
                           Eigen::Vector3i(n, n, n), type == fe::CellType::kHex8 ? 1 : 2);
}

// The volume of trilinear hexahedra by the 2×2×2 Gauss rule (exact: det J is of degree 2 in
// each reference coordinate), checking det J > 0 at the rule's points and the corners.
double hex_volume(const Eigen::MatrixXd& x, const Eigen::Matrix<int, Eigen::Dynamic, 8>& cells) {
  const double g = 1.0 / std::sqrt(3.0);
  const int sx[8] = {-1, 1, 1, -1, -1, 1, 1, -1}, sy[8] = {-1, -1, 1, 1, -1, -1, 1, 1},
            sz[8] = {-1, -1, -1, -1, 1, 1, 1, 1};
  double volume = 0.0;
  for (Eigen::Index c = 0; c < cells.rows(); ++c)
    for (double t : {g, 1.0})  // the Gauss points, then the corners
      for (int q = 0; q < 8; ++q) {
        const double xi[3] = {sx[q] * t, sy[q] * t, sz[q] * t};
        Eigen::Matrix3d J = Eigen::Matrix3d::Zero();
        for (int a = 0; a < 8; ++a) {
          const double f[3] = {1 + sx[a] * xi[0], 1 + sy[a] * xi[1], 1 + sz[a] * xi[2]};
          const Eigen::Vector3d d(sx[a] * f[1] * f[2], sy[a] * f[0] * f[2], sz[a] * f[0] * f[1]);
          J += x.row(cells(c, a)).transpose() * d.transpose() / 8.0;
        }
        EXPECT_GT(J.determinant(), 0.0) << "sub-hexahedron " << c;
        if (t == g) volume += J.determinant();
      }
  return volume;
}

}  // namespace

TEST(HexDecomposition, AffineCellsAreFilledExactlyByConformingHexahedra) {
  for (auto type :
       {fe::CellType::kHex8, fe::CellType::kHex27, fe::CellType::kTet4, fe::CellType::kTet10}) {
    SCOPED_TRACE(fe::to_string(type));
    const fe::Mesh mesh = body(type, 2);
    const HexDecomposition d = fe::hex_decomposition(mesh);
    const int per_cell = type == fe::CellType::kHex8 ? 1 : type == fe::CellType::kHex27 ? 8 : 4;
    ASSERT_EQ(d.cells.rows(), per_cell * mesh.num_elements());
    const Eigen::MatrixXd x = d.map * mesh.nodes;
    // 1e-12: the round-off of summing ≤ 1536 determinants (a missing or doubled sub-hexahedron
    // moves the sum by ≥ 0.5/1536 ≈ 3e-4).
    EXPECT_NEAR(hex_volume(x, d.cells), 0.5, 1e-12);
    // Conforming: the faces of one sub-hexahedron only form a closed, consistently oriented
    // surface (SurfaceDistance refuses anything else) enclosing the box.
    const TriangleSurface s = detail::hex_boundary({x, d.cells});
    EXPECT_NO_THROW(detail::SurfaceDistance{s});
    EXPECT_NEAR(detail::enclosed_volume(s), 0.5, 1e-12);
    // Its points are vertices, edge, face and cell points shared between elements: for
    // tetrahedra V + E + F + C of the Kuhn box (27 + 98 + 120 + 48 at n = 2; V − E + F − C = 1),
    // for the hex27 box its nodes, for the hex8 box its vertices.
    const Eigen::Index expected = type == fe::CellType::kTet4 || type == fe::CellType::kTet10
                                      ? 27 + 98 + 120 + 48
                                      : mesh.num_nodes();
    EXPECT_EQ(d.map.rows(), expected);
  }
}

TEST(HexDecomposition, CurvedCellsConvergeAtSecondOrder) {
  // z ↦ z (1 + a sin(π x)) on [0,1]² × [0, 0.5]: det = 1 + a sin(π x), so the volume is
  // 0.5 (1 + 2a/π); the top face is curved, the others stay flat.
  const double a = 0.3, exact = 0.5 * (1.0 + 2.0 * a / M_PI);
  for (auto type : {fe::CellType::kHex27, fe::CellType::kTet10}) {
    SCOPED_TRACE(fe::to_string(type));
    double error[2];
    for (int level = 0; level < 2; ++level) {
      fe::Mesh mesh = body(type, 2 << level);
      for (Eigen::Index i = 0; i < mesh.num_nodes(); ++i)
        mesh.nodes(i, 2) *= 1.0 + a * std::sin(M_PI * mesh.nodes(i, 0));
      const HexDecomposition d = fe::hex_decomposition(mesh);
      error[level] = std::abs(hex_volume(d.map * mesh.nodes, d.cells) - exact);
    }
    // Second order (measured 4.0 per halving: bilinear faces through points of the map), and
    // at n = 4 below the split through the cells' corners alone (hex27: 1.23e-3 against
    // 4.96e-3, the value of n = 2 here, which has the same points).
    EXPECT_GT(error[0] / error[1], 3.5) << error[0] << " " << error[1];
    EXPECT_LT(error[1], 2e-3);
  }
}

TEST(HexDecomposition, RefusesTwoDimensionalMeshes) {
  const fe::Mesh mesh =
      fe::make_box_mesh(Eigen::Vector2d::Zero(), Eigen::Vector2d::Ones(), Eigen::Vector2i(2, 2), 1);
  EXPECT_THROW(fe::hex_decomposition(mesh), InvalidArgument);
}
