#include <gtest/gtest.h>
#include <omp.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <cmath>
#include <string>

#include "fe_test_util.hpp"
#include "softhd/error.hpp"
#include "softhd/fe/assembly.hpp"
#include "softhd/fe/control.hpp"
#include "softhd/fe/grid_sequencing.hpp"
#include "unstructured_meshes.hpp"

using namespace softhd::fe;

namespace {

struct Discretisation {
  int dim, order;
};

std::vector<Discretisation> setups() { return {{2, 1}, {2, 2}, {3, 1}, {3, 2}}; }

Assembler make(const Discretisation& s, std::vector<DirichletConstraint> bc = {{"x0", {}}}) {
  const Mesh mesh = fe_test::box(s.dim, s.order, {2.0, 1.0, 0.5}, {3, 2, 2});
  const Eigen::Vector3d a0 = s.dim == 3 ? Eigen::Vector3d(1, 0.5, 0.2) : Eigen::Vector3d(1, 0.5, 0);
  return Assembler(mesh, fe_test::mooney_rivlin(), a0, bc);
}

Eigen::VectorXd admissible_u(const Assembler& A, unsigned seed) {
  return A.dofs().expand(fe_test::random_vector(A.dofs().num_free, 0.04, seed));
}

}  // namespace

// R = dΠ/du and K = dR/du by central differences along random directions, with the
// observed second order of the difference error.
TEST(Assembly, ResidualAndTangentMatchFiniteDifferences) {
  for (const Discretisation& s : setups()) {
    const Assembler A = make(s);
    const DofMap& d = A.dofs();
    const Eigen::MatrixXd m =
        fe_test::random_vector(A.mesh().num_elements() * A.geometry().points_per_element(), 0.5, 9)
            .reshaped(A.mesh().num_elements(), A.geometry().points_per_element());
    const Eigen::VectorXd u = admissible_u(A, 1);
    Eigen::VectorXd R;
    SparseMatrix K = A.tangent_pattern();
    double Pi;
    ASSERT_TRUE(A.evaluate(u, m, &Pi, &R, &K));
    const Eigen::VectorXd v = fe_test::random_vector(d.num_free, 1.0, 2);
    const Eigen::VectorXd Kv = K.selfadjointView<Eigen::Lower>() * v;
    auto errors = [&](double h) {
      double Pp, Pm;
      Eigen::VectorXd Rp, Rm;
      A.evaluate(u + h * d.expand(v), m, &Pp, &Rp, nullptr);
      A.evaluate(u - h * d.expand(v), m, &Pm, &Rm, nullptr);
      return std::make_pair(std::abs((Pp - Pm) / (2 * h) - R.dot(v)),
                            ((Rp - Rm) / (2 * h) - Kv).norm());
    };
    const auto [eR0, eK0] = errors(1e-6);
    EXPECT_LT(eR0, 1e-7 * R.norm() * v.norm()) << s.dim << "D Q" << s.order;
    EXPECT_LT(eK0, 1e-6 * Kv.norm()) << s.dim << "D Q" << s.order;
    const auto [eR1, eK1] = errors(4e-3);
    const auto [eR2, eK2] = errors(2e-3);
    EXPECT_GT(std::log2(eR1 / eR2), 1.8) << s.dim << "D Q" << s.order;
    EXPECT_GT(std::log2(eK1 / eK2), 1.8) << s.dim << "D Q" << s.order;
  }
}

TEST(Assembly, RigidRotationIsStressFree) {
  for (const Discretisation& s : setups()) {
    const Assembler A = make(s, {});
    const Eigen::Index N = A.mesh().num_nodes();
    Eigen::Matrix3d Q =
        Eigen::AngleAxisd(0.7, Eigen::Vector3d(0.2, -0.4, 1).normalized()).toRotationMatrix();
    if (s.dim == 2) Q = Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    Eigen::VectorXd u(N * s.dim);
    for (Eigen::Index n = 0; n < N; ++n) {
      Eigen::Vector3d X = Eigen::Vector3d::Zero();
      X.head(s.dim) = A.mesh().nodes.row(n).transpose();
      const Eigen::Vector3d x = Q * X - X;
      for (int k = 0; k < s.dim; ++k) u[n * s.dim + k] = x[k];
    }
    const Eigen::MatrixXd m0 =
        Eigen::MatrixXd::Zero(A.mesh().num_elements(), A.geometry().points_per_element());
    double Pi;
    Eigen::VectorXd R;
    ASSERT_TRUE(A.evaluate(u, m0, &Pi, &R, nullptr));
    EXPECT_NEAR(Pi, 0.0, 1e-12);
    EXPECT_LT(R.norm(), 1e-12);
    EXPECT_NEAR(A.deformed_volume(u), s.dim == 3 ? 1.0 : 2.0, 1e-12);
  }
}

// 160 Q2 elements: two passes (157 elements in 8 MB of element matrices, then 3), the first
// above the serial cut-off of 8, so the two-thread evaluation really splits elements
// between threads.
TEST(Assembly, SameResultForOneAndTwoThreads) {
  const Assembler A(fe_test::box(3, 2, {2.0, 1.0, 0.5}, {10, 4, 4}), fe_test::mooney_rivlin(),
                    Eigen::Vector3d(1, 0.5, 0.2), {{"x0", {}}});
  ASSERT_EQ(A.mesh().num_elements(), 160);
  const Eigen::MatrixXd m =
      Eigen::MatrixXd::Constant(A.mesh().num_elements(), A.geometry().points_per_element(), -0.3);
  const Eigen::VectorXd u = admissible_u(A, 4);
  double P1, P2;
  Eigen::VectorXd R1, R2;
  SparseMatrix K1 = A.tangent_pattern(), K2 = A.tangent_pattern();
  const int saved = omp_get_max_threads();
  omp_set_num_threads(1);
  A.evaluate(u, m, &P1, &R1, &K1);
  omp_set_num_threads(2);
  ASSERT_EQ(omp_get_max_threads(), 2);
  A.evaluate(u, m, &P2, &R2, &K2);
  omp_set_num_threads(saved);
  EXPECT_EQ(P1, P2);
  EXPECT_EQ((R1 - R2).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ((K1 - K2).cwiseAbs().sum(), 0.0);
}

namespace {

// Sums the element tangents it receives into a dense free-by-free matrix, in the order
// received, and checks that the passes come in element order without gaps.
class DenseSink final : public ElementMatrixSink {
 public:
  explicit DenseSink(const Assembler& A)
      : A_(A), K_(Eigen::MatrixXd::Zero(A.dofs().num_free, A.dofs().num_free)) {}
  void add(Eigen::Index first, Eigen::Index count, const double* Ke) override {
    EXPECT_EQ(first, next_);
    next_ = first + count;
    ++passes_;
    const int dim = A_.mesh().dim, nd = A_.mesh().nodes_per_element() * dim;
    for (Eigen::Index i = 0; i < count; ++i)
      for (int r = 0; r < nd; ++r)
        for (int c = 0; c < nd; ++c) {
          const int fr =
              A_.dofs().free_index[A_.mesh().elements(first + i, r / dim) * dim + r % dim];
          const int fc =
              A_.dofs().free_index[A_.mesh().elements(first + i, c / dim) * dim + c % dim];
          if (fr >= 0 && fc >= 0) K_(fr, fc) += Ke[(i * nd + r) * nd + c];
        }
  }
  const Eigen::MatrixXd& matrix() const { return K_; }
  Eigen::Index elements_seen() const { return next_; }
  int passes() const { return passes_; }

 private:
  const Assembler& A_;
  Eigen::MatrixXd K_;
  Eigen::Index next_ = 0;
  int passes_ = 0;
};

}  // namespace

// The element tangents handed to a sink, summed in element order, are the assembled
// tangent bit for bit (lower triangle; the upper one mirrors it exactly).
TEST(Assembly, ElementSinkSumsToTheAssembledTangent) {
  const Assembler A(fe_test::box(3, 2, {2.0, 1.0, 0.5}, {10, 4, 4}), fe_test::mooney_rivlin(),
                    Eigen::Vector3d(1, 0.5, 0.2), {{"x0", {}}});  // 160 Q2: two passes
  const Eigen::MatrixXd m =
      Eigen::MatrixXd::Constant(A.mesh().num_elements(), A.geometry().points_per_element(), -0.3);
  const Eigen::VectorXd u = 0.25 * admissible_u(A, 5);  // small enough for the thin elements
  double P1, P2;
  Eigen::VectorXd R1, R2;
  SparseMatrix K = A.tangent_pattern();
  ASSERT_TRUE(A.evaluate(u, m, &P1, &R1, &K));
  DenseSink sink(A);
  ASSERT_TRUE(A.evaluate_elements(u, m, &P2, &R2, &sink));
  EXPECT_EQ(sink.elements_seen(), 160);
  EXPECT_EQ(sink.passes(), 2);
  EXPECT_EQ(P1, P2);
  EXPECT_EQ((R1 - R2).cwiseAbs().maxCoeff(), 0.0);
  const Eigen::MatrixXd D = sink.matrix();
  EXPECT_EQ((D - D.transpose()).cwiseAbs().maxCoeff(), 0.0);
  const Eigen::MatrixXd KA = Eigen::MatrixXd(K);  // lower triangle
  EXPECT_EQ((KA - Eigen::MatrixXd(D.triangularView<Eigen::Lower>())).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_GT(KA.cwiseAbs().maxCoeff(), 0.0);
}

namespace {

class PassCounter final : public ElementMatrixSink {
 public:
  void add(Eigen::Index, Eigen::Index count, const double*) override { ++passes, seen += count; }
  int passes = 0;
  Eigen::Index seen = 0;
};

}  // namespace

// 1536 P2 tetrahedra: a P2 tetrahedron's matrix is 1/7 of a Q2 hexahedron's, so a pass holds
// 1127 of them (8 MB), not 157: two passes, both split between two threads, and the result
// is the one-thread result bit for bit.
TEST(Assembly, TetrahedraInTwoPassesSameResultForOneAndTwoThreads) {
  const Assembler A(fe_test::tet_box(2, {8, 8, 4}, {8.0, 8.0, 4.0}), fe_test::mooney_rivlin(),
                    Eigen::Vector3d(1, 0.5, 0.2), {});
  ASSERT_EQ(A.mesh().num_elements(), 1536);
  const Eigen::MatrixXd m =
      Eigen::MatrixXd::Constant(A.mesh().num_elements(), A.geometry().points_per_element(), -0.3);
  const Eigen::VectorXd u = admissible_u(A, 8);
  double P1, P2, P3;
  Eigen::VectorXd R1, R2, R3;
  SparseMatrix K1 = A.tangent_pattern(), K2 = A.tangent_pattern();
  const int saved = omp_get_max_threads();
  omp_set_num_threads(1);
  ASSERT_TRUE(A.evaluate(u, m, &P1, &R1, &K1));
  omp_set_num_threads(2);
  ASSERT_TRUE(A.evaluate(u, m, &P2, &R2, &K2));
  PassCounter sink;
  ASSERT_TRUE(A.evaluate_elements(u, m, &P3, &R3, &sink));
  omp_set_num_threads(saved);
  EXPECT_EQ(sink.passes, 2);
  EXPECT_EQ(sink.seen, 1536);
  EXPECT_EQ(P1, P2);
  EXPECT_EQ(P1, P3);
  EXPECT_EQ((R1 - R2).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ((K1 - K2).cwiseAbs().sum(), 0.0);
  EXPECT_GT(K1.cwiseAbs().sum(), 0.0);
}

// A lean assembler (no pattern, dN/dX recomputed per point) evaluates the same energy,
// residual, tangent and point quantities as the full one, to rounding (its 3 by 3 inverse
// is by cofactors, the stored gradients' by LU), in 2D and 3D, Q1 and Q2.
TEST(Assembly, LeanAssemblerEqualsFullToRounding) {
  for (const Discretisation& s : setups()) {
    const Assembler A = make(s);
    const Assembler B(A.mesh(), fe_test::mooney_rivlin(), A.fiber(0, 0), {{"x0", {}}},
                      AssemblerStorage::kLean);
    EXPECT_TRUE(A.geometry().stores_gradients());
    EXPECT_FALSE(B.geometry().stores_gradients());
    EXPECT_THROW(B.tangent_pattern(), softhd::InvalidArgument);
    const Eigen::MatrixXd m =
        Eigen::MatrixXd::Constant(A.mesh().num_elements(), A.geometry().points_per_element(), -0.3);
    const Eigen::VectorXd u = admissible_u(A, 6), lambda = admissible_u(A, 7);
    SparseMatrix KB;
    EXPECT_THROW(B.evaluate(u, m, nullptr, nullptr, &KB), softhd::InvalidArgument);
    double PA, PB;
    Eigen::VectorXd RA, RB;
    DenseSink sa(A), sb(B);
    ASSERT_TRUE(A.evaluate_elements(u, m, &PA, &RA, &sa));
    ASSERT_TRUE(B.evaluate_elements(u, m, &PB, &RB, &sb));
    const std::string where = std::to_string(s.dim) + "D Q" + std::to_string(s.order);
    EXPECT_NEAR(PA, PB, 1e-13 * std::abs(PA)) << where;
    EXPECT_LE((RA - RB).cwiseAbs().maxCoeff(), 1e-12 * RA.cwiseAbs().maxCoeff()) << where;
    const double kmax = sa.matrix().cwiseAbs().maxCoeff();
    EXPECT_LE((sa.matrix() - sb.matrix()).cwiseAbs().maxCoeff(), 1e-12 * kmax) << where;
    EXPECT_GT(kmax, 0.0);
    EXPECT_LE((A.jacobians(u) - B.jacobians(u)).cwiseAbs().maxCoeff(), 1e-13) << where;
    const Eigen::MatrixXd fa = A.fiber_sensitivity(u, lambda), fb = B.fiber_sensitivity(u, lambda);
    EXPECT_LE((fa - fb).cwiseAbs().maxCoeff(), 1e-12 * fa.cwiseAbs().maxCoeff()) << where;
  }
}

TEST(Assembly, InvertedElementIsReportedNotEvaluated) {
  const Assembler A = make({3, 1});
  Eigen::VectorXd u = Eigen::VectorXd::Zero(A.dofs().num_dofs);
  for (Eigen::Index n = 0; n < A.mesh().num_nodes(); ++n)
    u[n * 3 + 0] = -2.0 * A.mesh().nodes(n, 0);  // x ↦ −x
  const Eigen::MatrixXd m0 =
      Eigen::MatrixXd::Zero(A.mesh().num_elements(), A.geometry().points_per_element());
  double Pi = 0.0;
  EXPECT_FALSE(A.evaluate(u, m0, &Pi, nullptr, nullptr));
  EXPECT_TRUE(std::isinf(Pi));
  EXPECT_LT(A.min_jacobian(u), 0.0);
}

// Q1 interpolation reproduces affine fields; from_quadrature is the transpose of
// to_quadrature; the regularisation gradient matches central differences.
TEST(Control, InterpolationTransposeAndRegularisation) {
  for (const Discretisation& s : setups()) {
    const Assembler A = make(s);
    for (ControlKind kind : {ControlKind::kVertex, ControlKind::kElement}) {
      const ControlSpace c(A.mesh(), A.geometry(), kind);
      const Eigen::MatrixXd P = c.positions(A.mesh());
      const Eigen::MatrixXd Xq = quadrature_points(A.mesh(), A.geometry());
      if (kind == ControlKind::kVertex) {
        const Eigen::VectorXd m = 1.0 + 2.0 * P.col(0).array() - 3.0 * P.col(1).array();
        const Eigen::MatrixXd mq = c.to_quadrature(m);
        const int nq = A.geometry().points_per_element();
        for (Eigen::Index e = 0; e < mq.rows(); ++e)
          for (int q = 0; q < nq; ++q)
            EXPECT_NEAR(mq(e, q), 1.0 + 2.0 * Xq(e * nq + q, 0) - 3.0 * Xq(e * nq + q, 1), 1e-13);
      }
      const Eigen::VectorXd m = fe_test::random_vector(c.size(), 1.0, 5);
      const Eigen::MatrixXd v =
          fe_test::random_vector(A.geometry().weights().size(), 1.0, 6)
              .reshaped(A.mesh().num_elements(), A.geometry().points_per_element());
      EXPECT_NEAR(c.to_quadrature(m).cwiseProduct(v).sum(), m.dot(c.from_quadrature(v)), 1e-12);
      Eigen::VectorXd g;
      c.regularisation(m, 0.7, 0.3, &g);
      const Eigen::VectorXd dm = fe_test::random_vector(c.size(), 1.0, 7);
      const double h = 1e-5;
      const double fd = (c.regularisation(m + h * dm, 0.7, 0.3, nullptr) -
                         c.regularisation(m - h * dm, 0.7, 0.3, nullptr)) /
                        (2 * h);
      EXPECT_NEAR(fd, g.dot(dm), 1e-8 * (1.0 + std::abs(fd)));
    }
  }
  EXPECT_THROW(parse_control_kind("nodal"), softhd::InvalidArgument);
}

// On curved P2 tetrahedra the gradient term ∫ |∇m|² of vertex controls uses each element's
// own isoparametric map: it equals the quadrature of |∇m|² with ∇m by central differences of
// the control field in X (located and inverted by the point locator: independent code).
// With the map of the vertices alone it differs by about the warp (0.1).
TEST(Control, GradientTermIsExactOnCurvedElements) {
  softhd::fe::Mesh mesh = fe_test::tet_box(2, {2, 2, 2}, {1.0, 1.0, 1.0});
  fe_test::warp(&mesh, 0.1);
  const ReferenceGeometry g(mesh);
  const ControlSpace c(mesh, g, ControlKind::kVertex);
  const Eigen::VectorXd m = fe_test::random_vector(c.size(), 1.0, 11);
  const Eigen::MatrixXd Xq = quadrature_positions(mesh, g);
  const double h = 1e-6;
  Eigen::MatrixXd grad(Xq.rows(), 3);
  for (int d = 0; d < 3; ++d) {
    Eigen::MatrixXd plus = Xq, minus = Xq;
    plus.col(d).array() += h;
    minus.col(d).array() -= h;
    grad.col(d) = (control_at(mesh, ControlKind::kVertex, m, plus) -
                   control_at(mesh, ControlKind::kVertex, m, minus)) /
                  (2 * h);
  }
  const Eigen::VectorXd w = g.weights().transpose().reshaped();  // row e·nq + q
  const double fd = 0.5 * w.dot(grad.rowwise().squaredNorm());
  EXPECT_NEAR(c.regularisation(m, 0.0, 1.0, nullptr), fd, 1e-6 * fd);
}

namespace {

// One element of `cell`, its reference nodes moved by the affine map X = A ξ + b (det A > 0).
Mesh one_element(CellType cell) {
  const ReferenceElement& r = reference_element(cell);
  Mesh m;
  m.dim = r.dim;
  m.order = r.order;
  m.cell = cell;
  Eigen::MatrixXd A(r.dim, r.dim);
  if (r.dim == 3)
    A << 1.0, 0.2, 0.1, -0.1, 0.8, 0.3, 0.05, -0.2, 1.3;
  else
    A << 1.0, 0.3, -0.2, 0.9;
  m.nodes = r.node_coordinates * A.transpose();
  m.nodes.rowwise() += Eigen::RowVectorXd::LinSpaced(r.dim, 0.5, 1.5);
  m.elements.resize(1, r.nodes);
  for (int a = 0; a < r.nodes; ++a) m.elements(0, a) = a;
  const int nv = static_cast<int>(r.vertex_nodes.size());
  m.element_vertices.resize(1, nv);
  m.vertex_nodes.resize(nv);
  for (int v = 0; v < nv; ++v) {
    m.element_vertices(0, v) = v;
    m.vertex_nodes[v] = r.vertex_nodes[v];
  }
  m.element_region = Eigen::VectorXi::Zero(1);
  return m;
}

// Zero eigenvalues of the free element's tangent at rest (the linearised stiffness): the
// rigid motions (6 in 3D, 3 in 2D) and, if the quadrature is too weak, spurious modes.
int zero_modes(CellType cell, int degree) {
  const Mesh mesh = one_element(cell);
  const Assembler A(mesh, {fe_test::mooney_rivlin()}, FiberField{}, {}, AssemblerStorage::kFull,
                    degree);
  SparseMatrix K = A.tangent_pattern();
  double Pi = 0.0;
  Eigen::VectorXd R;
  const Eigen::VectorXd u = Eigen::VectorXd::Zero(mesh.num_nodes() * mesh.dim);
  const Eigen::MatrixXd m = Eigen::MatrixXd::Zero(1, A.geometry().points_per_element());
  EXPECT_TRUE(A.evaluate(u, m, &Pi, &R, &K));
  const Eigen::MatrixXd I = Eigen::MatrixXd::Identity(K.rows(), K.cols());
  const Eigen::MatrixXd Kd = K.selfadjointView<Eigen::Lower>() * I;
  const Eigen::VectorXd lambda = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(Kd).eigenvalues();
  int zeros = 0;
  for (Eigen::Index k = 0; k < lambda.size(); ++k)
    zeros += std::abs(lambda[k]) < 1e-9 * lambda.maxCoeff();
  return zeros;
}

}  // namespace

// The default quadrature of every cell type has no spurious zero-energy modes: an
// unconstrained element's stiffness at rest has exactly the rigid motions as its kernel.
// A one-point rule on the quadratic cells has many, so the count can fail.
TEST(Quadrature, TheDefaultRuleHasNoSpuriousModes) {
  const CellType all[] = {CellType::kQuad4, CellType::kQuad9, CellType::kTri3, CellType::kTri6,
                          CellType::kHex8,  CellType::kHex27, CellType::kTet4, CellType::kTet10};
  for (CellType cell : all) {
    const int rigid = reference_element(cell).dim == 3 ? 6 : 3;
    EXPECT_EQ(zero_modes(cell, 0), rigid) << to_string(cell);
  }
  EXPECT_GT(zero_modes(CellType::kTet10, 1), 6);
  EXPECT_GT(zero_modes(CellType::kTri6, 1), 3);
  EXPECT_GT(zero_modes(CellType::kHex27, 1), 6);
}

// spurious_zero_modes (the rank of the stacked symmetric gradients, which the scene's
// mesh.quadrature_degree is checked with) counts what the assembled stiffness of a free
// element shows at every degree the scene accepts, and smallest_stable_degree is never
// above the default.
TEST(Quadrature, SpuriousModesAreThoseOfTheAssembledStiffness) {
  const CellType all[] = {CellType::kQuad4, CellType::kQuad9, CellType::kTri3, CellType::kTri6,
                          CellType::kHex8,  CellType::kHex27, CellType::kTet4, CellType::kTet10};
  for (CellType cell : all) {
    const int rigid = reference_element(cell).dim == 3 ? 6 : 3;
    for (int degree = 1; degree <= 8; ++degree)
      EXPECT_EQ(spurious_zero_modes(cell, degree), zero_modes(cell, degree) - rigid)
          << to_string(cell) << " degree " << degree;
    EXPECT_LE(smallest_stable_degree(cell), reference_element(cell).default_quadrature_degree);
    EXPECT_EQ(spurious_zero_modes(cell, smallest_stable_degree(cell)), 0);
  }
  EXPECT_GT(spurious_zero_modes(CellType::kHex27, 3), 0);  // 2 by 2 by 2 Gauss points
  EXPECT_GT(spurious_zero_modes(CellType::kQuad4, 1), 0);  // one point: hourglass modes
  try {
    check_quadrature_degree(CellType::kTet10, 1);
    ADD_FAILURE();
  } catch (const softhd::InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("on tet10"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("use degree " +
                                         std::to_string(smallest_stable_degree(CellType::kTet10))),
              std::string::npos)
        << e.what();
  }
}

namespace {

// A node fibre field on `mesh` varying smoothly, and the same with the signs of some nodes'
// vectors flipped (the same axes).
void fibre_fields(const Mesh& mesh, FiberField* aligned, FiberField* flipped) {
  aligned->kind = flipped->kind = FiberField::Kind::kNode;
  aligned->values.resize(3, mesh.num_nodes());
  for (Eigen::Index n = 0; n < mesh.num_nodes(); ++n)
    aligned->values.col(n) = Eigen::Vector3d(1.0, 0.3 * mesh.nodes(n, 1), 0.2 * mesh.nodes(n, 0));
  flipped->values = aligned->values;
  for (Eigen::Index n = 0; n < mesh.num_nodes(); ++n)
    if ((n * 7) % 3 == 1) flipped->values.col(n) *= -1.0;
}

}  // namespace

// A fibre is an axis: flipping the sign of some nodes' vectors changes nothing (energy,
// residual, hence the state) on P2 and Q2 meshes, where interpolating the vectors would
// average opposite ones; a pure ±x field is the uniform x field.
TEST(Assembly, NodeFibresAreAxesNotVectors) {
  const Mesh meshes[] = {fe_test::tet_box(2, {2, 1, 1}, {2.0, 1.0, 1.0}),
                         fe_test::box(3, 2, {2.0, 1.0, 1.0}, {2, 1, 1})};
  for (const Mesh& mesh : meshes) {
    FiberField aligned, flipped, pm, uniform;
    fibre_fields(mesh, &aligned, &flipped);
    pm.kind = FiberField::Kind::kNode;
    pm.values = flipped.values.cwiseSign().row(0).replicate(3, 1);
    pm.values.bottomRows(2).setZero();  // ±x
    const auto mr = std::vector<std::shared_ptr<const Material>>{fe_test::mooney_rivlin()};
    const Assembler a(mesh, mr, aligned, {}), b(mesh, mr, flipped, {});
    const Assembler c(mesh, mr, pm, {}), d(mesh, mr, uniform, {});
    const Eigen::VectorXd u = admissible_u(a, 5);
    const Eigen::MatrixXd m =
        Eigen::MatrixXd::Constant(mesh.num_elements(), a.geometry().points_per_element(), -0.7);
    double Pa = 0.0, Pb = 0.0, Pc = 0.0, Pd = 0.0;
    Eigen::VectorXd Ra, Rb, Rc, Rd;
    ASSERT_TRUE(a.evaluate(u, m, &Pa, &Ra, nullptr));
    ASSERT_TRUE(b.evaluate(u, m, &Pb, &Rb, nullptr));
    ASSERT_TRUE(c.evaluate(u, m, &Pc, &Rc, nullptr));
    ASSERT_TRUE(d.evaluate(u, m, &Pd, &Rd, nullptr));
    EXPECT_NEAR(Pa, Pb, 1e-13 * std::abs(Pa)) << to_string(mesh.cell);
    EXPECT_LT((Ra - Rb).norm(), 1e-13 * Ra.norm()) << to_string(mesh.cell);
    EXPECT_NEAR(Pc, Pd, 1e-13 * std::abs(Pd)) << to_string(mesh.cell);
    EXPECT_LT((Rc - Rd).norm(), 1e-13 * Rd.norm()) << to_string(mesh.cell);
  }
}
