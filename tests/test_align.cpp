// align() (softhd/scan/align.hpp): the pose of an exact, rigidly moved subset of the body
// recovered from random rotations; a similarity; the twist gradient against a Taylor test;
// the composed pose of a moved scan; refusals.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "expect_error.hpp"
#include "scan/align_internal.hpp"
#include "softhd/scan/align.hpp"

namespace softhd::scan {
namespace {

/// An asymmetric body: a 1 × 0.6 × 0.3 slab with a 0.2 × 0.2 × 0.25 block on one corner,
/// random points (fixed seed), so no rotation but the identity maps it onto itself.
PointCloud asymmetric_body(int n, unsigned seed) {
  std::mt19937_64 gen(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Eigen::MatrixXd p(n, 3);
  for (int i = 0; i < n; ++i) {
    if (i % 6 == 0)
      p.row(i) << 0.8 + 0.2 * u(gen), 0.4 + 0.2 * u(gen), 0.3 + 0.25 * u(gen);
    else
      p.row(i) << u(gen), 0.6 * u(gen), 0.3 * u(gen);
  }
  return PointCloud(p);
}

Pose random_pose(std::mt19937_64& gen, double scale = 1.0) {
  std::normal_distribution<double> n;
  Eigen::Quaterniond q(n(gen), n(gen), n(gen), n(gen));
  Pose p;
  p.R = q.normalized().toRotationMatrix();
  p.t = Eigen::Vector3d(n(gen), n(gen), n(gen));
  p.s = scale;
  return p;
}

/// The rows of `body` picked by every `stride`-th index, moved into the camera frame by
/// P⁻¹ (so that P takes them back onto the body).
PointCloud camera_subset(const PointCloud& body, const Pose& P, int stride) {
  Eigen::MatrixXd rows((body.size() + stride - 1) / stride, 3);
  for (Eigen::Index k = 0; k < rows.rows(); ++k) rows.row(k) = body.points().row(k * stride);
  return PointCloud(apply_points(P.inverse(), rows));
}

AlignOptions fast_options() {
  AlignOptions o;
  o.distance.params.epsilon = 1e-3;
  o.threads = 2;
  return o;
}

TEST(Align, ExactSubsetRecoveredFromTenRandomRotations) {
  const PointCloud body = asymmetric_body(600, 1);
  const double L = body_size(body);
  std::mt19937_64 gen(11);
  for (int k = 0; k < 10; ++k) {
    const Pose P = random_pose(gen);
    const PointCloud scan = camera_subset(body, P, 2);
    const AlignSummary s = align(body, scan, fast_options());
    EXPECT_LT(rotation_angle_between(s.pose.R, P.R), 1e-6) << "pose " << k;
    EXPECT_LT((s.pose.t - P.t).norm(), 1e-6 * L) << "pose " << k;
    EXPECT_EQ(s.overlap, 1.0);
    EXPECT_LT(s.residuals.maxCoeff(), 1e-6 * L);
  }
}

// Without the nearest-point finish the minimiser of the symmetric ρ̃ (ε = 1e-3, spacing
// ≈ 0.06 L) is close but biased: for the whole body moved (stride 1) only by rounding and
// ρ̃'s flatness, for half its points (stride 2) by B, which pulls the scan towards the body
// points it lacks. The errors are measured here (formulation §8.5); the finish removes them.
TEST(Align, DistanceMinimiserAloneIsCloseButBiased) {
  const PointCloud body = asymmetric_body(600, 1);
  const double L = body_size(body);
  AlignOptions o = fast_options();
  o.nearest_iterations = 0;
  for (int stride : {1, 2}) {
    std::mt19937_64 gen(21);
    double worst_r = 0.0, worst_t = 0.0;
    for (int k = 0; k < 2; ++k) {
      const Pose P = random_pose(gen);
      const AlignSummary s = align(body, camera_subset(body, P, stride), o);
      worst_r = std::max(worst_r, rotation_angle_between(s.pose.R, P.R));
      worst_t = std::max(worst_t, (s.pose.t - P.t).norm() / L);
    }
    std::printf("stride %d, no nearest-point finish: rotation error %.3g rad, translation %.3g L\n",
                stride, worst_r, worst_t);
    EXPECT_LT(worst_r, stride == 1 ? 1e-8 : 1e-2);
    EXPECT_LT(worst_t, stride == 1 ? 1e-8 : 1e-2);
  }
}

// A one-sided view: the body's points on one side of a plane, exactly moved. With
// scan_to_body (ρ̃ = A) the hidden side is not punished; the pose is recovered exactly.
TEST(Align, OneSidedSubsetRecoveredWithScanToBody) {
  const PointCloud body = asymmetric_body(600, 8);
  const double L = body_size(body);
  std::mt19937_64 gen(18);
  AlignOptions o = fast_options();
  o.form.sides = Sides::scan_to_body;
  for (int k = 0; k < 3; ++k) {
    const Pose P = random_pose(gen);
    std::vector<Eigen::Index> side;
    for (Eigen::Index i = 0; i < body.size(); ++i)
      if (body.points()(i, 0) + 0.5 * body.points()(i, 1) > 0.45) side.push_back(i);
    Eigen::MatrixXd rows(static_cast<Eigen::Index>(side.size()), 3);
    for (size_t j = 0; j < side.size(); ++j)
      rows.row(static_cast<Eigen::Index>(j)) = body.points().row(side[j]);
    const AlignSummary s = align(body, PointCloud(apply_points(P.inverse(), rows)), o);
    EXPECT_LT(rotation_angle_between(s.pose.R, P.R), 1e-6) << "pose " << k;
    EXPECT_LT((s.pose.t - P.t).norm(), 1e-6 * L) << "pose " << k;
  }
}

TEST(Align, SimilarityRecovered) {
  const PointCloud body = asymmetric_body(600, 2);
  const double L = body_size(body);
  std::mt19937_64 gen(12);
  AlignOptions o = fast_options();
  o.kind = PoseKind::similarity;
  for (int k = 0; k < 3; ++k) {
    const Pose P = random_pose(gen, k == 0 ? 1.3 : k == 1 ? 0.8 : 1.05);
    const AlignSummary s = align(body, camera_subset(body, P, 1), o);
    EXPECT_LT(rotation_angle_between(s.pose.R, P.R), 1e-6) << "pose " << k;
    EXPECT_LT((s.pose.t - P.t).norm(), 1e-6 * L) << "pose " << k;
    EXPECT_NEAR(s.pose.s, P.s, 1e-6) << "pose " << k;
  }
}

// f(Q(h d)) − f(Q) − h ∇f·d = O(h²) for the twist step about the moved centroid.
TEST(Align, TwistGradientPassesTaylorTest) {
  const PointCloud body = asymmetric_body(200, 3);
  std::mt19937_64 gen(13);
  const PointCloud scan = camera_subset(asymmetric_body(300, 4), random_pose(gen), 1);
  HausdorffOptions d;
  d.params.epsilon = 0.01;
  const detail::PoseObjective f(body.points(), body.volumes(), scan, d, DistanceForm{});
  for (int n : {6, 7}) {
    Pose Q = random_pose(gen, 1.1);
    Q.t = scan.points().colwise().mean().transpose() - Q.s * Q.R * Eigen::Vector3d(0.5, 0.3, 0.2);
    Eigen::VectorXd g(n), dir(n);
    Eigen::Vector3d c;
    const double f0 = f.value(Q, &g, &c);
    std::normal_distribution<double> nd;
    for (int k = 0; k < n; ++k) dir[k] = nd(gen);
    std::vector<double> rem;
    for (double h : {1e-2, 5e-3, 2.5e-3, 1.25e-3}) {
      const double fh = f.value(detail::twist_step(Q, h * dir, c), nullptr, nullptr);
      rem.push_back(std::abs(fh - f0 - h * g.dot(dir)));
    }
    for (size_t k = 1; k < rem.size(); ++k) {
      const double order = std::log2(rem[k - 1] / rem[k]);
      EXPECT_NEAR(order, 2.0, 0.1) << n << " variables, step " << k;
    }
  }
}

TEST(Align, MovedScanGivesComposedPose) {
  const PointCloud body = asymmetric_body(600, 5);
  const double L = body_size(body);
  std::mt19937_64 gen(14);
  const Pose P = random_pose(gen);
  // A noisy, partial scan (every third point, noise 0.3 % of L).
  PointCloud exact = camera_subset(body, P, 3);
  std::normal_distribution<double> noise(0.0, 0.003 * L);
  Eigen::MatrixXd pts = exact.points();
  for (Eigen::Index i = 0; i < pts.size(); ++i) pts.data()[i] += noise(gen);
  const PointCloud scan(pts);
  const AlignSummary a = align(body, scan, fast_options());
  const Pose M = random_pose(gen);  // scan' = M(scan) has the pose P' = P ∘ M⁻¹
  const AlignSummary b = align(body, M.apply(scan, true), fast_options());
  const Pose expected = compose(a.pose, M.inverse());
  EXPECT_LT(rotation_angle_between(b.pose.R, expected.R), 1e-7);
  EXPECT_LT((b.pose.t - expected.t).norm(), 1e-7 * L);
  EXPECT_LT(rotation_angle_between(a.pose.R, P.R), 0.01);  // and near the truth
}

TEST(Align, OptionsRefusedNamingTheField) {
  const PointCloud body = asymmetric_body(50, 6);
  AlignOptions o;
  o.scale_min = 1.2;
  test::expect_error<InvalidArgument>([&] { align(body, body, o); }, "scale_min");
  o = AlignOptions{};
  o.scale_max = 0.9;
  test::expect_error<InvalidArgument>([&] { align(body, body, o); }, "scale_max");
  o = AlignOptions{};
  o.keep = 0;
  test::expect_error<InvalidArgument>([&] { align(body, body, o); }, "keep");
  o = AlignOptions{};
  o.form.sides = Sides::visible;
  test::expect_error<InvalidArgument>([&] { align(body, body, o); }, "visible");
  o = AlignOptions{};
  o.form.cap.c = -1.0;
  test::expect_error<InvalidArgument>([&] { align(body, body, o); }, "cap.c");
  test::expect_error<InvalidArgument>([] { pose_kind_from_string("affine"); }, "align 'affine'");
  const PointCloud flat(Eigen::MatrixXd::Ones(4, 3));
  test::expect_error<InvalidArgument>([&] { align(flat, body, AlignOptions{}); }, "coincide");
}

}  // namespace
}  // namespace softhd::scan
