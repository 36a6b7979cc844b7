// Values and fields of ρ̃ (docs/formulation.md §2.1) against independent oracles: the naive formula
// in long double, brute-force nearest distances, analytic limits and invariances.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <numeric>

#include "expect_error.hpp"
#include "hausdorff_reference.hpp"
#include "softhd/error.hpp"
#include "softhd/hausdorff.hpp"

namespace softhd::test {
namespace {

HausdorffOptions options(double a, double b, double g, double e, int threads = 0) {
  HausdorffOptions o;
  o.params.alpha = a;
  o.params.beta = b;
  o.params.gamma = g;
  o.params.epsilon = e;
  o.threads = threads;
  return o;
}

HausdorffRequest fields() {
  HausdorffRequest r;
  r.fields = true;
  return r;
}

void expect_matches_reference(const PointCloud& X, const PointCloud& Y, const HausdorffOptions& o,
                              double tol) {
  const HausdorffResult r = hausdorff(X, Y, o, fields());
  const Reference ref = naive_hausdorff(X, Y, o.params);
  ASSERT_TRUE(std::isfinite(r.rho) && std::isfinite(r.A) && std::isfinite(r.B));
  if (!ref.representable) return;
  EXPECT_LE(relative_error(r.rho, ref.rho), tol);
  EXPECT_LE(relative_error(r.A, ref.A), tol);
  EXPECT_LE(relative_error(r.B, ref.B), tol);
  for (Eigen::Index j = 0; j < Y.size(); ++j)
    EXPECT_LE(relative_error(r.field_target[j], ref.field_target[j]), tol) << "target " << j;
  for (Eigen::Index i = 0; i < X.size(); ++i)
    EXPECT_LE(relative_error(r.field_moving[i], ref.field_moving[i]), tol) << "moving " << i;
}

TEST(HausdorffValue, MatchesLongDoubleReference) {
  for (int d : {2, 3}) {
    const PointCloud X = random_cloud(41, d, 1), Y = random_cloud(67, d, 2, 0.3, 1.4);
    expect_matches_reference(X, Y, HausdorffOptions{}, 1e-12);
    expect_matches_reference(X, Y, options(7.5, 2.5, 3.0, 1e-2), 1e-12);
    expect_matches_reference(Y, X, options(1.0, 1.0, 1.0, 0.1), 1e-12);
    // α = 16 and 64 take the kernel's unrolled powers (α = 4 above too), 7.5 and 1 its
    // general one (pair_kernel.cpp).
    expect_matches_reference(X, Y, options(16.0, 4.0, 2.0, 1e-2), 1e-12);
    expect_matches_reference(Y, X, options(64.0, 4.0, 2.0, 0.05), 1e-12);
  }
}

TEST(HausdorffValue, RegularisedDistanceBoundsTheNearestDistance) {
  const PointCloud X = random_cloud(50, 3, 3), Y = random_cloud(70, 3, 4, -0.5, 0.8);
  for (double a : {1.0, 4.0, 64.0})
    for (double e : {1e-1, 1e-3, 1e-9}) {
      const HausdorffResult r = hausdorff(X, Y, options(a, 4, 2, e), fields());
      for (Eigen::Index j = 0; j < Y.size(); ++j)
        EXPECT_GE(r.field_target[j], brute_nearest(X, Y.points().row(j).transpose()));
      for (Eigen::Index i = 0; i < X.size(); ++i)
        EXPECT_GE(r.field_moving[i], brute_nearest(Y, X.points().row(i).transpose()));
    }
}

// Two unit cubes sampled on the same 6×6×6 grid, the second shifted by t along X1:
// the Hausdorff distance between the clouds (and the cubes) is exactly t.
TEST(HausdorffValue, TendsToTheHausdorffDistanceOfTwoCubes) {
  const double t = 0.37;
  const int n = 6;
  Eigen::MatrixXd p(n * n * n, 3);
  for (int i = 0, row = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k, ++row) p.row(row) << (i + 0.5) / n, (j + 0.5) / n, (k + 0.5) / n;
  Eigen::MatrixXd q = p;
  q.col(0).array() += t;
  const PointCloud X(p), Y(q);
  HausdorffOptions exact_nn;
  exact_nn.method = Method::nearest;
  EXPECT_NEAR(hausdorff(X, Y, exact_nn).rho, t, 1e-15);

  double previous_error = INFINITY;
  const double exps[] = {4, 16, 64, 256, 1024, 1e4};
  const double epss[] = {1e-2, 1e-3, 1e-4, 1e-6, 1e-8, 1e-10};
  for (int s = 0; s < 6; ++s) {
    const double e =
        std::fabs(hausdorff(X, Y, options(exps[s], exps[s], exps[s], epss[s])).rho - t);
    EXPECT_LT(e, previous_error) << "step " << s;
    previous_error = e;
  }
  EXPECT_LT(previous_error, 2e-3 * t);
}

TEST(HausdorffValue, NearestEqualsBruteForceHausdorff) {
  for (int d : {2, 3}) {
    const PointCloud X = random_cloud(300, d, 5), Y = random_cloud(170, d, 6, 0.2, 1.5);
    double A = 0, B = 0;
    for (Eigen::Index j = 0; j < Y.size(); ++j)
      A = std::max(A, brute_nearest(X, Y.points().row(j).transpose()));
    for (Eigen::Index i = 0; i < X.size(); ++i)
      B = std::max(B, brute_nearest(Y, X.points().row(i).transpose()));
    HausdorffOptions o;
    o.method = Method::nearest;
    const HausdorffResult r = hausdorff(X, Y, o, fields());
    EXPECT_DOUBLE_EQ(r.A, A);
    EXPECT_DOUBLE_EQ(r.B, B);
    EXPECT_DOUBLE_EQ(r.rho, std::max(A, B));
    EXPECT_EQ(r.field_target.size(), Y.size());
  }
}

TEST(HausdorffValue, InvariantUnderRigidMotionAndPermutation) {
  const PointCloud X = random_cloud(40, 3, 7), Y = random_cloud(55, 3, 8, 0.1, 1.2);
  const double rho = hausdorff(X, Y).rho;
  // Rigid motion: a rotation (unit quaternion) and a translation applied to both.
  const Eigen::Matrix3d R = Eigen::Quaterniond(0.3, -0.5, 0.7, 0.2).normalized().toRotationMatrix();
  const Eigen::RowVector3d shift(2.5, -1.0, 0.75);
  auto move = [&](const PointCloud& c) {
    Eigen::MatrixXd p = c.points() * R.transpose();
    p.rowwise() += shift;
    return PointCloud(p, c.volumes());
  };
  EXPECT_LE(relative_error(hausdorff(move(X), move(Y)).rho, rho), 1e-12);
  // Permutation of the moving points.
  std::vector<int> perm(X.size());
  std::iota(perm.begin(), perm.end(), 0);
  std::reverse(perm.begin(), perm.end());
  std::swap(perm[3], perm[17]);
  Eigen::MatrixXd p(X.size(), 3);
  Eigen::VectorXd v(X.size());
  for (Eigen::Index i = 0; i < X.size(); ++i) {
    p.row(i) = X.points().row(perm[i]);
    v[i] = X.volumes()[perm[i]];
  }
  EXPECT_LE(relative_error(hausdorff(PointCloud(p, v), Y).rho, rho), 1e-13);
}

TEST(HausdorffValue, SplittingAPointIntoTwoHalvesChangesNothing) {
  const PointCloud X = random_cloud(30, 2, 9), Y = random_cloud(35, 2, 10);
  Eigen::MatrixXd p(X.size() + 1, 2);
  Eigen::VectorXd v(X.size() + 1);
  p.topRows(X.size()) = X.points();
  v.head(X.size()) = X.volumes();
  p.row(X.size()) = X.points().row(4);
  v[4] *= 0.5;
  v[X.size()] = v[4];
  const PointCloud split(p, v);
  EXPECT_LE(relative_error(hausdorff(split, Y).rho, hausdorff(X, Y).rho), 1e-13);
  EXPECT_LE(relative_error(hausdorff(Y, split).rho, hausdorff(Y, X).rho), 1e-13);
}

// α, β, γ up to 1e4, ε down to 1e-12, coordinates scaled 1e-6 … 1e6, duplicates and
// single points: always finite, and equal to the long-double reference where that
// reference is representable.
TEST(HausdorffValue, StaysFiniteAndAccurateUnderStress) {
  const double exps[] = {1, 4, 16, 64, 256, 1024, 1e4};
  const double epss[] = {1e-1, 1e-3, 1e-6, 1e-9, 1e-12};
  const double scales[] = {1e-6, 1e-3, 1.0, 1e3, 1e6};
  Eigen::MatrixXd px = random_cloud(12, 3, 11).points();
  px.row(5) = px.row(2);  // a duplicate
  Eigen::MatrixXd py = random_cloud(9, 3, 12, 0.2, 1.1).points();
  py.row(0) = px.row(1);  // a point coincident with the other cloud
  const Eigen::MatrixXd single = px.topRows(1);
  int compared = 0, total = 0;
  for (double s : scales)
    for (double a : exps)
      for (double bg : exps)
        for (double e : epss) {
          const PointCloud X(s * px), Y(s * py), P(s * single);
          const HausdorffOptions o = options(a, bg, bg, e);
          for (auto [x, y] : {std::pair{&X, &Y}, std::pair{&P, &Y}, std::pair{&X, &P}}) {
            const HausdorffResult r = hausdorff(*x, *y, o, fields());
            ++total;
            ASSERT_TRUE(std::isfinite(r.rho) && r.field_target.allFinite() &&
                        r.field_moving.allFinite())
                << "scale " << s << " alpha " << a << " beta " << bg << " eps " << e;
            const Reference ref = naive_hausdorff(*x, *y, o.params);
            if (!ref.representable) continue;
            ++compared;
            ASSERT_LE(relative_error(r.rho, ref.rho), 1e-10)
                << "scale " << s << " alpha " << a << " beta " << bg << " eps " << e;
          }
        }
  // The reference must cover most of the grid, or the comparison proves little.
  EXPECT_GT(compared, total / 2) << compared << " of " << total << " compared";
}

TEST(HausdorffValue, SinglePointCloudsAgreeWithTheirDistance) {
  // One point each: d̃ = |x − y| exactly, so ρ̃ is the distance.
  const PointCloud X(Eigen::RowVector3d(1, 2, 3)), Y(Eigen::RowVector3d(1, 2, 3.5));
  EXPECT_NEAR(hausdorff(X, Y).rho, 0.5, 1e-15);
  EXPECT_EQ(hausdorff(X, X).rho, 0.0);
}

TEST(HausdorffValue, OneAndTwoThreadsGiveTheSameResult) {
  const PointCloud X = random_cloud(900, 3, 13), Y = random_cloud(700, 3, 14);
  HausdorffRequest req = fields();
  req.gradient_points = req.gradient_volumes = req.gradient_target = true;
  const HausdorffResult r1 = hausdorff(X, Y, options(4, 4, 2, 1e-3, 1), req);
  const HausdorffResult r2 = hausdorff(X, Y, options(4, 4, 2, 1e-3, 2), req);
  EXPECT_LE(relative_error(r1.rho, r2.rho), 1e-14);
  EXPECT_LE((r1.gradient_points - r2.gradient_points).norm(), 1e-14 * r1.gradient_points.norm());
  EXPECT_LE((r1.gradient_target - r2.gradient_target).norm(), 1e-14 * r1.gradient_target.norm());
  EXPECT_LE((r1.gradient_volumes - r2.gradient_volumes).norm(), 1e-14 * r1.gradient_volumes.norm());
}

TEST(HausdorffValue, ReportsKernelEvaluationsAndComputesOnlyWhatIsAsked) {
  const PointCloud X = random_cloud(20, 3, 15), Y = random_cloud(30, 3, 16);
  const HausdorffResult r = hausdorff(X, Y);
  EXPECT_EQ(r.kernel_evaluations, 2 * 20 * 30);
  EXPECT_EQ(r.field_target.size(), 0);
  EXPECT_EQ(r.gradient_points.size(), 0);
  HausdorffRequest req;
  req.gradient_target = true;
  EXPECT_EQ(hausdorff(X, Y, {}, req).kernel_evaluations, 3 * 20 * 30);
}

TEST(HausdorffValue, RejectsBadParametersAndMismatchedInput) {
  const PointCloud X = random_cloud(5, 3, 1), Y = random_cloud(5, 3, 2), Z = random_cloud(5, 2, 3);
  expect_error<InvalidArgument>([&] { hausdorff(X, Y, options(0, 4, 2, 1e-3)); },
                                "alpha must be finite and > 0");
  expect_error<InvalidArgument>([&] { hausdorff(X, Y, options(4, -1, 2, 1e-3)); },
                                "beta must be finite and > 0");
  expect_error<InvalidArgument>([&] { hausdorff(X, Y, options(4, 4, NAN, 1e-3)); },
                                "gamma must be finite");
  expect_error<InvalidArgument>([&] { hausdorff(X, Y, options(4, 4, 2, 0)); },
                                "epsilon must be finite and > 0");
  expect_error<InvalidArgument>([&] { hausdorff(X, Z); },
                                "moving cloud is 3D but the target is 2D");
  expect_error<InvalidArgument>([&] { method_from_string("fast"); }, "unknown method 'fast'");
  HausdorffOptions nearest;
  nearest.method = Method::nearest;
  HausdorffRequest grad;
  grad.gradient_points = true;
  expect_error<InvalidArgument>([&] { hausdorff(X, Y, nearest, grad); }, "computes no gradient");
  HausdorffRequest mask;
  mask.differentiate.setConstant(4, true);
  expect_error<InvalidArgument>([&] { hausdorff(X, Y, {}, mask); },
                                "mask has 4 entries for 5 moving points");
}

}  // namespace
}  // namespace softhd::test
