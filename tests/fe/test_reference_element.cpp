// The reference-element table (fe/reference_element.hpp): shape functions, quadrature, and
// the VTK and Gmsh node orders checked against those programs' own node coordinates.

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cfloat>
#include <cmath>
#include <random>
#include <vector>

#include "expect_error.hpp"
#include "softhd/error.hpp"
#include "softhd/fe/reference_element.hpp"

using namespace softhd::fe;

namespace {

const CellType kAll[] = {CellType::kQuad4, CellType::kQuad9, CellType::kTri3, CellType::kTri6,
                         CellType::kHex8,  CellType::kHex27, CellType::kTet4, CellType::kTet10};

// A random point of the reference cell.
Eigen::VectorXd random_point(const ReferenceElement& r, std::mt19937* rng) {
  std::uniform_real_distribution<double> U(0.0, 1.0);
  Eigen::VectorXd xi(r.dim);
  do {
    for (int k = 0; k < r.dim; ++k) xi[k] = r.simplex ? U(*rng) : 2.0 * U(*rng) - 1.0;
  } while (!inside_reference_cell(r.type, xi.data(), 0.0));
  return xi;
}

void shapes(CellType t, const Eigen::VectorXd& xi, Eigen::VectorXd* N, Eigen::MatrixXd* dN) {
  const ReferenceElement& r = reference_element(t);
  N->resize(r.nodes);
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> g(r.nodes, r.dim);
  shape_functions(t, xi.data(), N->data(), g.data());
  *dN = g;
}

double factorial(int n) { return n <= 1 ? 1.0 : n * factorial(n - 1); }

// Exact ∫ x^a y^b z^c over the reference cell: Π (1 − (−1)^{e+1})/(e+1) on [−1, 1]^d,
// a! b! c! / (a + b + c + d)! on the unit simplex.
double exact_monomial(const ReferenceElement& r, const int* e) {
  if (!r.simplex) {
    double v = 1.0;
    for (int k = 0; k < r.dim; ++k) v *= e[k] % 2 == 1 ? 0.0 : 2.0 / (e[k] + 1);
    return v;
  }
  double num = 1.0;
  int sum = 0;
  for (int k = 0; k < r.dim; ++k) {
    num *= factorial(e[k]);
    sum += e[k];
  }
  return num / factorial(sum + r.dim);
}

}  // namespace

TEST(ReferenceElement, KroneckerAtNodesAndTableConsistency) {
  for (CellType t : kAll) {
    const ReferenceElement& r = reference_element(t);
    EXPECT_EQ(r.type, t);
    EXPECT_EQ(parse_cell_type(to_string(t)), t);
    ASSERT_EQ(r.node_coordinates.rows(), r.nodes);
    ASSERT_EQ(static_cast<int>(r.node_support.size()), r.nodes);
    EXPECT_EQ(static_cast<int>(r.vertex_nodes.size()), reference_element(r.linear).nodes);
    EXPECT_EQ(reference_element(r.quadratic).order, 2);
    Eigen::VectorXd N;
    Eigen::MatrixXd dN;
    for (int b = 0; b < r.nodes; ++b) {
      shapes(t, r.node_coordinates.row(b).transpose(), &N, &dN);
      EXPECT_NEAR((N - Eigen::VectorXd::Unit(r.nodes, b)).norm(), 0.0, 1e-15) << to_string(t);
      // The node is the centroid of its support corners.
      Eigen::RowVectorXd c = Eigen::RowVectorXd::Zero(r.dim);
      for (int v : r.node_support[b]) c += r.node_coordinates.row(r.vertex_nodes[v]);
      c /= static_cast<double>(r.node_support[b].size());
      EXPECT_NEAR((c - r.node_coordinates.row(b)).norm(), 0.0, 1e-15) << to_string(t) << b;
    }
    // The linear cell's nodes are the vertices, in its own order.
    const ReferenceElement& lin = reference_element(r.linear);
    for (int v = 0; v < lin.nodes; ++v)
      EXPECT_EQ(r.node_coordinates.row(r.vertex_nodes[v]), lin.node_coordinates.row(v));
  }
  softhd::test::expect_error<softhd::InvalidArgument>([] { parse_cell_type("hex20"); },
                                                      "unknown cell type 'hex20'");
}

TEST(ReferenceElement, PartitionOfUnityAndGradientsByFiniteDifferences) {
  std::mt19937 rng(3);
  for (CellType t : kAll) {
    const ReferenceElement& r = reference_element(t);
    for (int trial = 0; trial < 20; ++trial) {
      const Eigen::VectorXd xi = random_point(r, &rng);
      Eigen::VectorXd N, Np, Nm;
      Eigen::MatrixXd dN, dh;
      shapes(t, xi, &N, &dN);
      EXPECT_NEAR(N.sum(), 1.0, 1e-14);
      EXPECT_NEAR(dN.colwise().sum().norm(), 0.0, 1e-13);
      for (int g = 0; g < r.dim; ++g) {  // central differences, exact for quadratics
        const double h = 1e-4;
        Eigen::VectorXd xp = xi, xm = xi;
        xp[g] += h;
        xm[g] -= h;
        shapes(t, xp, &Np, &dh);
        shapes(t, xm, &Nm, &dh);
        EXPECT_LT(((Np - Nm) / (2 * h) - dN.col(g)).cwiseAbs().maxCoeff(), 1e-9) << to_string(t);
      }
    }
  }
}

TEST(ReferenceElement, QuadratureIntegratesMonomialsUpToItsDegree) {
  for (CellType t : kAll) {
    const ReferenceElement& r = reference_element(t);
    for (int degree = 1; degree <= 10; ++degree) {
      Eigen::MatrixXd P;
      Eigen::VectorXd W;
      cell_quadrature(t, degree, &P, &W);
      ASSERT_EQ(P.rows(), W.size());
      EXPECT_GT(W.minCoeff(), 0.0) << to_string(t) << " degree " << degree;
      for (Eigen::Index q = 0; q < P.rows(); ++q) {  // strictly inside
        const Eigen::VectorXd xq = P.row(q).transpose();
        EXPECT_TRUE(inside_reference_cell(t, xq.data(), 0.0));
        if (r.simplex) {
          EXPECT_GT(P.row(q).minCoeff(), 0.0);
        }
      }
      // Every monomial of total degree (simplex) or degree per axis (tensor) <= degree.
      int e[3] = {0, 0, 0};
      const int top = r.dim == 3 ? degree : 0;
      for (e[2] = 0; e[2] <= top; ++e[2])
        for (e[1] = 0; e[1] <= degree; ++e[1])
          for (e[0] = 0; e[0] <= degree; ++e[0]) {
            if (r.simplex && e[0] + e[1] + e[2] > degree) continue;
            double sum = 0.0, magnitude = 0.0;
            for (Eigen::Index q = 0; q < P.rows(); ++q) {
              double m = 1.0;
              for (int k = 0; k < r.dim; ++k) m *= std::pow(P(q, k), e[k]);
              sum += W[q] * m;
              magnitude += std::abs(W[q] * m);
            }
            // Round-off only: the a-priori bound of summing nq products (each point and weight
            // itself within a few ulps) is nq·eps·Σ|w m|, with a factor 4 for the weights. The
            // 1e-14 this replaced was exceeded by clang's -O1 (8 − 1.3e-14 for 125 points).
            const double round_off =
                4.0 * static_cast<double>(P.rows()) * DBL_EPSILON * std::max(magnitude, 1.0);
            EXPECT_NEAR(sum, exact_monomial(r, e), round_off)
                << to_string(t) << " degree " << degree << " x^" << e[0] << " y^" << e[1] << " z^"
                << e[2];
          }
    }
  }
  // Point counts: (n)^d Gauss points for 2n − 1 >= degree; the symmetric simplex rules.
  Eigen::MatrixXd P;
  Eigen::VectorXd W;
  struct Count {
    CellType type;
    int degree, points;
  };
  const Count counts[] = {{CellType::kHex8, 3, 8},    {CellType::kHex27, 5, 27},
                          {CellType::kTet10, 2, 4},   {CellType::kTet10, 5, 14},
                          {CellType::kTet10, 8, 125}, {CellType::kTri6, 4, 6},
                          {CellType::kTri6, 5, 7},    {CellType::kTri6, 8, 25}};
  for (const Count& c : counts) {
    cell_quadrature(c.type, c.degree, &P, &W);
    EXPECT_EQ(W.size(), c.points) << to_string(c.type) << " degree " << c.degree;
  }
  EXPECT_THROW(cell_quadrature(CellType::kTet10, 0, &P, &W), softhd::InvalidArgument);
}

namespace {

// Gmsh's reference nodes (Gmsh manual, "Node ordering"): vertices, then one node per edge
// and per quadrangular face at their midpoints, in Gmsh's edge and face order, then the
// centre. Edges and faces are given by 0-based Gmsh vertex ids.
Eigen::MatrixXd gmsh_nodes(CellType t) {
  std::vector<std::vector<double>> v;
  std::vector<std::vector<int>> edges, faces;
  bool centre = false;
  switch (t) {
    case CellType::kQuad4:
    case CellType::kQuad9:
      v = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
      if (t == CellType::kQuad9) edges = {{0, 1}, {1, 2}, {2, 3}, {3, 0}}, centre = true;
      break;
    case CellType::kTri3:
    case CellType::kTri6:
      v = {{0, 0}, {1, 0}, {0, 1}};
      if (t == CellType::kTri6) edges = {{0, 1}, {1, 2}, {2, 0}};
      break;
    case CellType::kHex8:
    case CellType::kHex27:
      v = {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1},
           {-1, -1, 1},  {1, -1, 1},  {1, 1, 1},  {-1, 1, 1}};
      if (t == CellType::kHex27) {
        edges = {{0, 1}, {0, 3}, {0, 4}, {1, 2}, {1, 5}, {2, 3},
                 {2, 6}, {3, 7}, {4, 5}, {4, 7}, {5, 6}, {6, 7}};
        faces = {{0, 3, 2, 1}, {0, 1, 5, 4}, {0, 4, 7, 3},
                 {1, 2, 6, 5}, {2, 3, 7, 6}, {4, 5, 6, 7}};
        centre = true;
      }
      break;
    case CellType::kTet4:
    case CellType::kTet10:
      v = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
      if (t == CellType::kTet10) edges = {{0, 1}, {1, 2}, {2, 0}, {3, 0}, {3, 2}, {3, 1}};
      break;
  }
  const int dim = static_cast<int>(v[0].size());
  std::vector<std::vector<int>> groups;
  for (int i = 0; i < static_cast<int>(v.size()); ++i) groups.push_back({i});
  groups.insert(groups.end(), edges.begin(), edges.end());
  groups.insert(groups.end(), faces.begin(), faces.end());
  if (centre) {
    groups.emplace_back();
    for (int i = 0; i < static_cast<int>(v.size()); ++i) groups.back().push_back(i);
  }
  Eigen::MatrixXd X = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(groups.size()), dim);
  for (size_t g = 0; g < groups.size(); ++g) {
    for (int i : groups[g])
      for (int k = 0; k < dim; ++k) X(static_cast<Eigen::Index>(g), k) += v[i][k];
    X.row(static_cast<Eigen::Index>(g)) /= static_cast<double>(groups[g].size());
  }
  return X;
}

// VTK's parametric node coordinates (vtkQuad, vtkBiQuadraticQuad, vtkTriangle,
// vtkQuadraticTriangle, vtkHexahedron, vtkTriQuadraticHexahedron::GetParametricCoords,
// vtkTetra, vtkQuadraticTetra), in [0, 1]^d for quadrilaterals and hexahedra.
Eigen::MatrixXd vtk_nodes(CellType t) {
  std::vector<std::vector<double>> x;
  const double h = 0.5;
  switch (t) {
    case CellType::kQuad4:
      x = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
      break;
    case CellType::kQuad9:
      x = {{0, 0}, {1, 0}, {1, 1}, {0, 1}, {h, 0}, {1, h}, {h, 1}, {0, h}, {h, h}};
      break;
    case CellType::kTri3:
      x = {{0, 0}, {1, 0}, {0, 1}};
      break;
    case CellType::kTri6:
      x = {{0, 0}, {1, 0}, {0, 1}, {h, 0}, {h, h}, {0, h}};
      break;
    case CellType::kHex8:
    case CellType::kHex27:
      x = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1},
           {0, 1, 1}, {h, 0, 0}, {1, h, 0}, {h, 1, 0}, {0, h, 0}, {h, 0, 1}, {1, h, 1},
           {h, 1, 1}, {0, h, 1}, {0, 0, h}, {1, 0, h}, {1, 1, h}, {0, 1, h}, {0, h, h},
           {1, h, h}, {h, 0, h}, {h, 1, h}, {h, h, 0}, {h, h, 1}, {h, h, h}};
      if (t == CellType::kHex8) x.resize(8);
      break;
    case CellType::kTet4:
    case CellType::kTet10:
      x = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {h, 0, 0},
           {h, h, 0}, {0, h, 0}, {0, 0, h}, {h, 0, h}, {0, h, h}};
      if (t == CellType::kTet4) x.resize(4);
      break;
  }
  const bool box =
      t != CellType::kTri3 && t != CellType::kTri6 && t != CellType::kTet4 && t != CellType::kTet10;
  Eigen::MatrixXd X(static_cast<Eigen::Index>(x.size()), static_cast<Eigen::Index>(x[0].size()));
  for (Eigen::Index i = 0; i < X.rows(); ++i)
    for (Eigen::Index k = 0; k < X.cols(); ++k) X(i, k) = box ? 2.0 * x[i][k] - 1.0 : x[i][k];
  return X;
}

// order[i] is the internal node at the other program's node i (vtk_order) or the other
// program's node at internal node i (gmsh_order, inverse = false).
void expect_order(CellType t, const Eigen::MatrixXd& other, const std::vector<int>& order,
                  bool vtk) {
  const ReferenceElement& r = reference_element(t);
  ASSERT_EQ(other.rows(), r.nodes) << to_string(t);
  ASSERT_EQ(static_cast<int>(order.size()), r.nodes) << to_string(t);
  std::vector<int> seen(r.nodes, 0);
  Eigen::VectorXd N;
  Eigen::MatrixXd dN;
  for (int i = 0; i < r.nodes; ++i) {
    const int internal = vtk ? order[i] : i, external = vtk ? i : order[i];
    ++seen[order[i]];
    // N_a(ξ_b) = δ_ab at the other program's coordinates.
    shapes(t, other.row(external).transpose(), &N, &dN);
    EXPECT_NEAR((N - Eigen::VectorXd::Unit(r.nodes, internal)).norm(), 0.0, 1e-15)
        << to_string(t) << (vtk ? " VTK node " : " internal node ") << i;
  }
  for (int s : seen) EXPECT_EQ(s, 1) << to_string(t) << ": not a permutation";
}

}  // namespace

TEST(ReferenceElement, GmshOrderAtGmshsOwnCoordinates) {
  for (CellType t : kAll) expect_order(t, gmsh_nodes(t), reference_element(t).gmsh_order, false);
  const int codes[] = {3, 10, 2, 9, 5, 12, 4, 11};  // Gmsh element types
  for (int k = 0; k < 8; ++k) EXPECT_EQ(reference_element(kAll[k]).gmsh_type, codes[k]);
}

TEST(ReferenceElement, VtkOrderAtVtksOwnCoordinates) {
  for (CellType t : kAll) expect_order(t, vtk_nodes(t), reference_element(t).vtk_order, true);
  const int codes[] = {9, 28, 5, 22, 12, 29, 10, 24};  // VTK cell types
  for (int k = 0; k < 8; ++k) EXPECT_EQ(reference_element(kAll[k]).vtk_type, codes[k]);
}

TEST(ReferenceElement, InsideReferenceCell) {
  const double in[3] = {0.2, 0.2, 0.2}, out[3] = {0.5, 0.5, 0.1}, neg[3] = {-1e-3, 0.1, 0.1};
  EXPECT_TRUE(inside_reference_cell(CellType::kTet10, in, 0.0));
  EXPECT_FALSE(inside_reference_cell(CellType::kTet10, out, 0.0));
  EXPECT_TRUE(inside_reference_cell(CellType::kTri6, out, 0.0));
  EXPECT_FALSE(inside_reference_cell(CellType::kTet4, neg, 1e-4));
  EXPECT_TRUE(inside_reference_cell(CellType::kTet4, neg, 1e-2));
  const double edge[3] = {1.0 + 1e-12, -1.0, 0.0};
  EXPECT_TRUE(inside_reference_cell(CellType::kHex27, edge, 1e-10));
  EXPECT_FALSE(inside_reference_cell(CellType::kHex27, edge, 0.0));
}
