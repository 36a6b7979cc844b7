// Hessian-vector products of ρ̃ w.r.t. the moving points (docs/formulation.md §2.7): the gradient's
// Taylor remainder falls as h², central differences of the gradient, symmetry, the Gauss–Newton
// part positive semi-definite and above the full Hessian, and a limit where both are known.

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <random>
#include <vector>

#include "expect_error.hpp"
#include "hausdorff_reference.hpp"
#include "softhd/hausdorff.hpp"

namespace softhd::test {
namespace {

struct Case {
  int dim;
  Sides sides;
  bool capped;
  Method method;
};

void PrintTo(const Case& c, std::ostream* os) {
  *os << c.dim << "D " << to_string(c.sides) << (c.capped ? " capped " : " ")
      << to_string(c.method);
}

HausdorffParams odd_params() {
  HausdorffParams p;  // non-default; α = 2.5 takes the generic power, integers the unrolled one
  p.alpha = 2.5;
  p.beta = 2.5;
  p.gamma = 1.5;
  p.epsilon = 0.02;
  return p;
}

// A moving and a target cloud, a request of the case's form, the target prepared.
struct Scene {
  PointCloud X, Y;
  HausdorffRequest req;
  HausdorffTarget target;

  Scene(const Case& c, HausdorffParams prm, int n = 29, int m = 37)
      : X(random_cloud(n, c.dim, 5 + c.dim, 0.0, 1.0)),
        Y(random_cloud(m, c.dim, 71 + c.dim, 0.15, 1.25)),
        target(Y, options(c, prm)) {
    req.form.sides = c.sides;
    if (c.sides == Sides::visible) {
      req.form.camera_mask.setConstant(X.size(), false);
      for (Eigen::Index i = 0; i < X.size(); i += 2) req.form.camera_mask[i] = true;
    }
    if (c.capped) {  // the cap near the median field: active on about half the points
      HausdorffRequest fields;
      fields.fields = true;
      req.form.cap.c = cap_from_quantile(target.evaluate(X, fields).field_target, 0.5, 1.0);
      req.form.cap.q = 3.0;
    }
  }
  static HausdorffOptions options(const Case& c, HausdorffParams prm) {
    HausdorffOptions o;
    o.params = prm;
    o.method = c.method;
    o.tolerance = 1e-13;
    o.tree_fallback = false;  // the tree's far field, not all pairs
    return o;
  }
  PointCloud moved(const Eigen::MatrixXd& dx) const {
    return PointCloud(X.points() + dx, X.volumes());
  }
  Eigen::MatrixXd gradient(const Eigen::MatrixXd& dx) const {
    HausdorffRequest r = req;
    r.gradient_points = true;
    return target.evaluate(moved(dx), r).gradient_points;
  }
  HausdorffResult at() const {
    HausdorffRequest r = req;
    r.gradient_points = true;
    r.hessian_points = true;
    return target.evaluate(X, r);
  }
  Eigen::MatrixXd zero() const { return Eigen::MatrixXd::Zero(X.size(), X.dim()); }
};

Eigen::MatrixXd random_direction(Eigen::Index n, int d, unsigned seed) {
  std::mt19937_64 gen(seed);
  std::normal_distribution<double> normal;
  Eigen::MatrixXd v(n, d);
  for (Eigen::Index i = 0; i < v.size(); ++i) v.data()[i] = normal(gen);
  return v;
}

double inner(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) { return a.cwiseProduct(b).sum(); }

std::vector<Case> all_cases() {
  std::vector<Case> cases;
  for (int dim : {2, 3})
    for (Sides s : {Sides::symmetric, Sides::scan_to_body, Sides::visible})
      for (bool capped : {false, true})
        for (Method m : {Method::exact, Method::tree}) cases.push_back({dim, s, capped, m});
  return cases;
}

class HessianTest : public ::testing::TestWithParam<Case> {};

// ‖g(x + hv) − g(x) − h H v‖ = O(h²): the observed order between successive halvings ≥ 1.9.
TEST_P(HessianTest, GradientRemainderFallsAsHSquared) {
  const Scene s(GetParam(), odd_params());
  const HausdorffResult r = s.at();
  const Eigen::MatrixXd v = random_direction(s.X.size(), s.X.dim(), 3);
  const Eigen::MatrixXd Hv = s.target.hessian_product(r, v);
  ASSERT_TRUE(Hv.allFinite());
  const Eigen::MatrixXd g0 = s.gradient(s.zero());
  ASSERT_EQ(g0, r.gradient_points);  // the Hessian's request leaves the gradient alone
  double previous = 0.0;
  for (double h : {1e-3, 5e-4, 2.5e-4, 1.25e-4}) {
    const double rem = (s.gradient(h * v) - g0 - h * Hv).norm();
    const double first = (s.gradient(h * v) - g0).norm();
    EXPECT_LT(rem, 0.2 * first) << "h " << h;  // H v carries the first-order change
    if (previous > 0.0) {
      EXPECT_GE(std::log2(previous / rem), 1.9) << "h " << h;
    }
    previous = rem;
  }
}

// H v against central differences of the gradient along v (h = 1e-5).
TEST_P(HessianTest, MatchesCentralDifferences) {
  const Scene s(GetParam(), odd_params());
  const HausdorffResult r = s.at();
  const Eigen::MatrixXd v = random_direction(s.X.size(), s.X.dim(), 9);
  const Eigen::MatrixXd Hv = s.target.hessian_product(r, v);
  const double h = 1e-5;
  const Eigen::MatrixXd fd = (s.gradient(h * v) - s.gradient(-h * v)) / (2.0 * h);
  EXPECT_LT((fd - Hv).norm(), 1e-6 * Hv.norm()) << "|Hv| " << Hv.norm();
}

// ⟨a, H b⟩ = ⟨b, H a⟩ to round-off, for H and H_GN; H_GN ⪰ 0 and H_GN ⪰ H on random v.
TEST_P(HessianTest, SymmetricAndGaussNewtonBoundsIt) {
  const Scene s(GetParam(), odd_params());
  const HausdorffResult r = s.at();
  const Eigen::MatrixXd a = random_direction(s.X.size(), s.X.dim(), 21);
  const Eigen::MatrixXd b = random_direction(s.X.size(), s.X.dim(), 22);
  for (HessianPart part : {HessianPart::full, HessianPart::gauss_newton}) {
    const Eigen::MatrixXd Ha = s.target.hessian_product(r, a, part);
    const Eigen::MatrixXd Hb = s.target.hessian_product(r, b, part);
    const double scale = a.norm() * Hb.norm() + b.norm() * Ha.norm();
    EXPECT_NEAR(inner(a, Hb), inner(b, Ha), 1e-13 * scale);
  }
  for (unsigned seed = 100; seed < 120; ++seed) {
    const Eigen::MatrixXd v = random_direction(s.X.size(), s.X.dim(), seed);
    const Eigen::MatrixXd Hv = s.target.hessian_product(r, v);
    const Eigen::MatrixXd Gv = s.target.hessian_product(r, v, HessianPart::gauss_newton);
    const double round = 1e-13 * v.norm() * (Hv.norm() + Gv.norm());
    EXPECT_GE(inner(v, Gv), -round) << "seed " << seed;
    EXPECT_GE(inner(v, Gv - Hv), -round) << "seed " << seed;
  }
}

INSTANTIATE_TEST_SUITE_P(Forms, HessianTest, ::testing::ValuesIn(all_cases()));

// Every column of the Hessian against central differences of the gradient (2D, 12 points,
// α = 4: the unrolled power), symmetric form with a cap.
TEST(HessianMatrix, ColumnsMatchCentralDifferences) {
  HausdorffParams prm = odd_params();
  prm.alpha = 4.0;
  const Scene s({2, Sides::symmetric, true, Method::exact}, prm, 12, 15);
  const HausdorffResult r = s.at();
  const double h = 1e-5;
  Eigen::MatrixXd H(s.X.size() * 2, s.X.size() * 2), F(H.rows(), H.cols());
  for (Eigen::Index k = 0; k < H.cols(); ++k) {
    Eigen::MatrixXd e = s.zero();
    e.data()[k] = 1.0;
    const Eigen::MatrixXd col = s.target.hessian_product(r, e);
    const Eigen::MatrixXd fd = (s.gradient(h * e) - s.gradient(-h * e)) / (2.0 * h);
    H.col(k) = Eigen::Map<const Eigen::VectorXd>(col.data(), col.size());
    F.col(k) = Eigen::Map<const Eigen::VectorXd>(fd.data(), fd.size());
  }
  EXPECT_LT((H - F).norm(), 1e-6 * H.norm());
  EXPECT_LT((H - H.transpose()).norm(), 1e-13 * H.norm());
  // Not positive semi-definite here (the soft min's covariance): the test of H_GN ⪰ 0 has teeth.
  Eigen::MatrixXd G(H.rows(), H.cols());
  for (Eigen::Index k = 0; k < G.cols(); ++k) {
    Eigen::MatrixXd e = s.zero();
    e.data()[k] = 1.0;
    const Eigen::MatrixXd col = s.target.hessian_product(r, e, HessianPart::gauss_newton);
    G.col(k) = Eigen::Map<const Eigen::VectorXd>(col.data(), col.size());
  }
  EXPECT_LT(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(H).eigenvalues().minCoeff(), 0.0);
  EXPECT_GE(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(G).eigenvalues().minCoeff(),
            -1e-12 * G.norm());
}

// One moving point, scan_to_body, β = 1, no cap: A = Σ_j w_j |x − y_j| exactly (the soft min over
// one point is the distance), so H = Σ_j w_j (I − u_j u_jᵀ)/r_j, and H_GN = H (no soft-min
// covariance, no β- or γ-curvature).
TEST(HessianLimit, OnePointScanToBodyIsTheDistancesCurvature) {
  HausdorffParams prm;
  prm.alpha = 3.0;
  prm.beta = 1.0;
  prm.epsilon = 0.01;
  const PointCloud Y = random_cloud(9, 3, 41, 0.0, 1.0);
  Eigen::MatrixXd x(1, 3);
  x << 0.3, 1.7, -0.4;
  const PointCloud X(x, Eigen::VectorXd::Ones(1));
  HausdorffOptions o;
  o.params = prm;
  const HausdorffTarget target(Y, o);
  HausdorffRequest req;
  req.form.sides = Sides::scan_to_body;
  req.hessian_points = true;
  const HausdorffResult r = target.evaluate(X, req);
  EXPECT_EQ(r.gradient_points.size(), 0);  // not asked for
  Eigen::Matrix3d expected = Eigen::Matrix3d::Zero();
  const Eigen::VectorXd w = Y.volumes() / Y.total_volume();
  for (Eigen::Index j = 0; j < Y.size(); ++j) {
    const Eigen::Vector3d d = (x.row(0) - Y.points().row(j)).transpose();
    const double rj = d.norm();
    const Eigen::Vector3d u = d / rj;
    expected += w[j] * (Eigen::Matrix3d::Identity() - u * u.transpose()) / rj;
  }
  for (HessianPart part : {HessianPart::full, HessianPart::gauss_newton}) {
    Eigen::Matrix3d H;
    for (int k = 0; k < 3; ++k) {
      Eigen::MatrixXd e = Eigen::MatrixXd::Zero(1, 3);
      e(0, k) = 1.0;
      H.col(k) = target.hessian_product(r, e, part).row(0).transpose();
    }
    EXPECT_LT((H - expected).norm(), 1e-12 * expected.norm()) << static_cast<int>(part);
  }
}

// β < 1 and γ < 1: their means' curvature is negative and left out of H_GN, which stays ⪰ 0.
TEST(HessianGaussNewton, PositiveForConcaveMeans) {
  HausdorffParams prm = odd_params();
  prm.beta = 0.7;
  prm.gamma = 0.8;
  const Scene s({3, Sides::symmetric, true, Method::exact}, prm);
  const HausdorffResult r = s.at();
  for (unsigned seed = 1; seed < 11; ++seed) {
    const Eigen::MatrixXd v = random_direction(s.X.size(), 3, seed);
    const Eigen::MatrixXd Hv = s.target.hessian_product(r, v);
    const Eigen::MatrixXd Gv = s.target.hessian_product(r, v, HessianPart::gauss_newton);
    const double round = 1e-13 * v.norm() * (Hv.norm() + Gv.norm());
    EXPECT_GE(inner(v, Gv), -round);
    EXPECT_GE(inner(v, Gv - Hv), -round);
  }
  const Eigen::MatrixXd v = random_direction(s.X.size(), 3, 77);
  const double h = 1e-5;
  const Eigen::MatrixXd fd = (s.gradient(h * v) - s.gradient(-h * v)) / (2.0 * h);
  EXPECT_LT((fd - s.target.hessian_product(r, v)).norm(), 1e-6 * fd.norm());
}

// Points not differentiated: zero rows, their direction ignored; the rest is the Hessian of ρ̃
// in the other points (Taylor remainder with the masked rows of v zero).
TEST(HessianMask, MaskedRowsAreZeroAndTheRestExact) {
  const Scene base({3, Sides::symmetric, false, Method::exact}, odd_params());
  Scene s({3, Sides::symmetric, false, Method::exact}, odd_params());
  s.req.differentiate.setConstant(s.X.size(), true);
  for (Eigen::Index i = 0; i < s.X.size(); i += 3) s.req.differentiate[i] = false;
  const HausdorffResult r = s.at();
  Eigen::MatrixXd v = random_direction(s.X.size(), 3, 5);
  const Eigen::MatrixXd Hv = s.target.hessian_product(r, v);
  for (Eigen::Index i = 0; i < s.X.size(); i += 3) {
    EXPECT_EQ(Hv.row(i).norm(), 0.0);
    v.row(i).setZero();
  }
  EXPECT_EQ(Hv, s.target.hessian_product(r, v));  // the masked rows of v are ignored
  const HausdorffResult full = base.at();
  Eigen::MatrixXd expected = base.target.hessian_product(full, v);
  for (Eigen::Index i = 0; i < s.X.size(); i += 3) expected.row(i).setZero();
  EXPECT_LT((Hv - expected).norm(), 1e-13 * expected.norm());
}

// The same bits for any thread count.
TEST(HessianThreads, DeterministicAcrossThreadCounts) {
  Eigen::MatrixXd products[2];
  for (int t : {1, 2}) {
    const PointCloud X = random_cloud(200, 3, 1, 0.0, 1.0), Y = random_cloud(150, 3, 2, 0.1, 1.1);
    HausdorffOptions o;
    o.threads = t;
    const HausdorffTarget target(Y, o);
    HausdorffRequest req;
    req.hessian_points = true;
    products[t - 1] = target.hessian_product(target.evaluate(X, req), random_direction(200, 3, 4));
  }
  EXPECT_EQ(products[0], products[1]);
}

TEST(HessianErrors, RefusesMissingStateOtherTargetAndShape) {
  const PointCloud X = random_cloud(10, 2, 1), Y = random_cloud(12, 2, 2);
  const HausdorffTarget target(Y), other(Y);
  HausdorffRequest req;
  req.gradient_points = true;
  const Eigen::MatrixXd v = Eigen::MatrixXd::Ones(10, 2);
  expect_error<InvalidArgument>([&] { (void)target.hessian_product(target.evaluate(X, req), v); },
                                "no Hessian state");
  req.hessian_points = true;
  const HausdorffResult r = target.evaluate(X, req);
  expect_error<InvalidArgument>([&] { (void)other.hessian_product(r, v); }, "another target");
  expect_error<InvalidArgument>(
      [&] { (void)target.hessian_product(r, Eigen::MatrixXd::Ones(10, 3)); }, "10 by 3");
  HausdorffOptions nearest;
  nearest.method = Method::nearest;
  expect_error<InvalidArgument>([&] { (void)HausdorffTarget(Y, nearest).evaluate(X, req); },
                                "no gradient");
}

}  // namespace
}  // namespace softhd::test
