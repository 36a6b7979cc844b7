// align() (softhd/scan/align.hpp): the pose of an exact, rigidly moved subset of the body
// recovered from random rotations; a similarity; the twist gradient against a Taylor test;
// the composed pose of a moved scan; refusals.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <utility>
#include <vector>

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

/// A bent bar (volumetric grid, spacing h = 0.05): arm 1 the box [0, 1] × [0, 0.3] × [0, 0.1],
/// arm 2 the same box turned 40° about the y axis at x = 1 (bent away from +z), and a knob
/// 0.15 high under arm 1's back face z = 0. The scan of the front face z = 0.1 lies as well
/// on the back face (the flip: a half turn about arm 1's long axis), where the knob's points
/// add to the field and make ρ̃ a little lower.
PointCloud bent_bar() {
  std::vector<Eigen::Vector3d> p;
  const double h = 0.05, a = 40.0 * M_PI / 180.0;
  for (int i = 0; i <= 20; ++i)
    for (int j = 0; j <= 6; ++j)
      for (int k = 0; k <= 2; ++k) {
        const Eigen::Vector3d q(i * h, j * h, k * h);
        p.push_back(q);  // arm 1
        if (i > 0)       // arm 2: x ↦ 1 + (x cos a, ·, −x sin a) + z (sin a, ·, cos a)
          p.emplace_back(1.0 + q.x() * std::cos(a) + q.z() * std::sin(a), q.y(),
                         -q.x() * std::sin(a) + q.z() * std::cos(a));
      }
  for (int i = 0; i <= 3; ++i)
    for (int j = 0; j <= 3; ++j)
      for (int k = 1; k <= 3; ++k) p.emplace_back(0.2 + i * h, 0.0 + j * h, -k * h);  // the knob
  Eigen::MatrixXd m(static_cast<Eigen::Index>(p.size()), 3);
  for (size_t i = 0; i < p.size(); ++i) m.row(static_cast<Eigen::Index>(i)) = p[i].transpose();
  return PointCloud(m);
}

/// A half view of bent_bar(): the camera 3 above arm 1 looking down −z sees only arm 1's
/// front face z = 0.1 (the body's nodes there, noise-free); the scan in the camera's frame
/// and its true pose P (camera → body).
PointCloud bent_bar_half_view(Pose* P) {
  Eigen::Matrix3d axes;  // columns: the camera's x (right), y (down), z (forward) in the body
  axes << 1, 0, 0, 0, -1, 0, 0, 0, -1;
  P->R = axes;
  P->t = Eigen::Vector3d(0.5, 0.15, 3.0);
  Eigen::MatrixXd rows(21 * 7, 3);
  for (int i = 0; i <= 20; ++i)
    for (int j = 0; j <= 6; ++j) rows.row(i * 7 + j) << 0.05 * i, 0.05 * j, 0.1;
  return PointCloud(apply_points(P->inverse(), rows));
}

// The flip of a one-sided view (formulation §8.5): the scan of arm 1's front face lies as well
// (to ρ̃: better) on its back face, the bar turned over; both poses are local minima of ρ̃
// (scan_to_body), which does not see the knob (the scan over it is as near the body). The
// coverage score does: turned over, the camera sees the knob 0.15 before the scan.
TEST(Align, CoverageScoreTellsAFlippedHalfViewApart) {
  const PointCloud body = bent_bar();
  const double L = body_size(body);
  Pose P;
  const PointCloud scan = bent_bar_half_view(&P);
  // The flip: a half turn about arm 1's long axis (x, through its centre y = 0.15, z = 0.05).
  Pose half_turn;
  half_turn.R = Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()).toRotationMatrix();
  half_turn.t = Eigen::Vector3d(0.0, 0.15, 0.05) - half_turn.R * Eigen::Vector3d(0.0, 0.15, 0.05);
  const Pose flipped = compose(half_turn, P);
  HausdorffOptions d;
  d.params.epsilon = 0.01 * L;
  d.threads = 1;
  AlignOptions o;  // ρ̃ = A (scan_to_body), as for a partial view
  o.form.sides = Sides::scan_to_body;
  o.threads = 1;
  const detail::PoseObjective rho(body.points(), body.volumes(), scan, d, o.form);
  detail::LocalSettings st;
  st.size = L;
  st.max_iterations = 10;
  // ρ̃ is lower at the flipped pose; both are local minima.
  EXPECT_LT(rho.value(flipped.inverse(), nullptr, nullptr),
            rho.value(P.inverse(), nullptr, nullptr));
  std::vector<detail::LocalResult> refined;
  for (const Pose& start : {P, flipped}) {
    refined.push_back(detail::minimise_pose(rho, start.inverse(), st));
    EXPECT_LT(rotation_angle_between(refined.back().pose.R, start.inverse().R), 1e-3);
    EXPECT_LT((refined.back().pose.t - start.inverse().t).norm(), 1e-3 * L);
  }
  EXPECT_LT(refined[1].rho, refined[0].rho);
  // The coverage score: near 0 at the true pose, 5 times more turned over.
  const detail::CoverageScore score(body.points(), scan.points(), L, 0.05, 1);
  const double s_true = score.value(P.inverse()), s_flip = score.value(flipped.inverse());
  EXPECT_LT(s_true, 1e-3);
  EXPECT_GT(s_flip, 5.0 * s_true);
  // align()'s choice between the two: by ρ̃ (score rho, the old rule) the flip, by the
  // coverage score (after each candidate's nearest-point fit) the true pose.
  o.score = CandidateScore::rho;
  std::vector<detail::LocalResult> copy = refined;
  EXPECT_EQ(detail::choose_candidate(body, scan, L, o, nullptr, nullptr, &copy), 1u);
  o.score = CandidateScore::coverage;
  copy = refined;
  const size_t chosen = detail::choose_candidate(body, scan, L, o, nullptr, nullptr, &copy);
  EXPECT_EQ(chosen, 0u);
  EXPECT_LT(rotation_angle_between(copy[chosen].pose.R, P.inverse().R), 1e-3);
  EXPECT_LT((copy[chosen].pose.t - P.inverse().t).norm(), 1e-3 * L);
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
  o.inlier_distance = 1.5;  // a fraction of L: 1 or more measures no overlap
  test::expect_error<InvalidArgument>([&] { align(body, body, o); },
                                      "inlier_distance must be in (0, 1)");
  o = AlignOptions{};
  o.form.sides = Sides::visible;
  test::expect_error<InvalidArgument>([&] { align(body, body, o); }, "visible");
  EXPECT_EQ(candidate_score_from_string("coverage"), CandidateScore::coverage);
  EXPECT_EQ(to_string(CandidateScore::coverage), "coverage");
  // the retired spelling names the new one
  test::expect_error<InvalidArgument>([] { candidate_score_from_string("visible"); },
                                      "\"visible\" is now \"coverage\"");
  o = AlignOptions{};
  o.form.cap.c = -1.0;
  test::expect_error<InvalidArgument>([&] { align(body, body, o); }, "cap.c");
  o = AlignOptions{};
  o.score_truncation = 0.0;
  test::expect_error<InvalidArgument>([&] { align(body, body, o); }, "score_truncation");
  test::expect_error<InvalidArgument>([] { pose_kind_from_string("affine"); }, "align 'affine'");
  test::expect_error<InvalidArgument>([] { candidate_score_from_string("best"); }, "score 'best'");
  const PointCloud flat(Eigen::MatrixXd::Ones(4, 3));
  test::expect_error<InvalidArgument>([&] { align(flat, body, AlignOptions{}); }, "coincide");
  o = AlignOptions{};
  o.initial = Pose();
  o.initial->s = 1.5;  // a rigid alignment from a scaled start
  test::expect_error<InvalidArgument>([&] { align(body, body, o); }, "initial pose has scale 1.5");
  o.kind = PoseKind::similarity;
  EXPECT_NO_THROW(align(body, body, o));
}

// A scan that fixes no pose: one point, coincident points, collinear points (exactly, and to
// 1e-9 of their length), refused; points spanning a plane are not.
TEST(Align, ScanThatFixesNoPoseIsRefused) {
  const PointCloud body = asymmetric_body(60, 7);
  auto refused = [&](const Eigen::MatrixXd& points, const std::string& needle) {
    test::expect_error<InvalidArgument>([&] { align(body, PointCloud(points), AlignOptions{}); },
                                        "align: the scan: " + needle);
  };
  refused(Eigen::RowVector3d(0.2, 0.1, 0.0), "it has a single point");
  refused(Eigen::MatrixXd::Constant(5, 3, 0.3), "its 5 points coincide");
  Eigen::MatrixXd line(4, 3);
  line << 0, 0, 0, 1, 2, 3, 2, 4, 6, -1, -2, -3;
  refused(line, "its 4 points are collinear");
  line(3, 0) += 1e-9;  // a spread across the line of about 2e-10 of the length along it
  refused(line, "its 4 points are collinear");
  line(3, 0) += 1e-3;
  EXPECT_NO_THROW(check_fixes_pose(PointCloud(line), "scan"));
  test::expect_error<InvalidArgument>(
      [&] { align(PointCloud(Eigen::MatrixXd::Ones(3, 3)), body, AlignOptions{}); },
      "align: the body: its 3 points coincide");
}

// With the global start, `initial` is one more candidate: without refinement (0 iterations, no
// nearest-point finish) the exact pose given as `initial` wins over the global start's, whose
// minimiser of ρ̃ is biased for half the body's points (DistanceMinimiserAloneIsCloseButBiased).
TEST(Align, InitialCompetesWithTheGlobalStart) {
  const PointCloud body = asymmetric_body(300, 3);
  std::mt19937_64 gen(5);
  const Pose P = random_pose(gen);
  const PointCloud scan = camera_subset(body, P, 2);
  AlignOptions o = fast_options();
  o.rotations = 0;
  o.keep = 1;
  o.max_iterations = 0;
  o.nearest_iterations = 0;
  const AlignSummary global = align(body, scan, o);
  EXPECT_GT((global.pose.matrix() - P.matrix()).norm(), 1e-9);  // the global start alone
  o.initial = P;
  const AlignSummary s = align(body, scan, o);
  EXPECT_LT((s.pose.matrix() - P.matrix()).norm(), 1e-12);
}

/// A bar bent by a cubic, its nodes and closed surface: the nodes of an 11 × 3 × 3 grid of
/// [0, 1] × [0, 0.2] × [0, 0.1] moved by (x, y, z) ↦ (x, y, z + 0.4 x³) (Jacobian determinant
/// 1: the boundary stays closed and outward; no rotation but the identity maps it onto itself)
/// and the outward triangles of the grid's boundary quadrilaterals, each cut by a diagonal.
TriangleSurface cubic_bent_bar() {
  const int n[3] = {11, 3, 3};
  const double size[3] = {1.0, 0.2, 0.1};
  const auto id = [&](int i, int j, int k) { return (i * n[1] + j) * n[2] + k; };
  TriangleSurface s;
  s.points.resize(n[0] * n[1] * n[2], 3);
  for (int i = 0; i < n[0]; ++i)
    for (int j = 0; j < n[1]; ++j)
      for (int k = 0; k < n[2]; ++k) {
        const double x = size[0] * i / (n[0] - 1), y = size[1] * j / (n[1] - 1),
                     z = size[2] * k / (n[2] - 1);
        s.points.row(id(i, j, k)) << x, y, z + 0.4 * x * x * x;
      }
  std::vector<Eigen::Vector3i> tri;
  // The face of axis a at index side (0 or n_a − 1): quads over the other two axes b < c, the
  // corners in the order that turns by +e_a (outward on the high side) for (a, b, c) cyclic.
  for (int a = 0; a < 3; ++a)
    for (int side : {0, n[a] - 1}) {
      const int b = (a + 1) % 3, c = (a + 2) % 3;
      for (int u = 0; u + 1 < n[b]; ++u)
        for (int v = 0; v + 1 < n[c]; ++v) {
          int q[4];
          const int du[4] = {0, 1, 1, 0}, dv[4] = {0, 0, 1, 1};
          for (int m = 0; m < 4; ++m) {
            int ijk[3];
            ijk[a] = side, ijk[b] = u + du[m], ijk[c] = v + dv[m];
            q[m] = id(ijk[0], ijk[1], ijk[2]);
          }
          if (side == 0) std::swap(q[1], q[3]);  // outward is −e_a
          tri.emplace_back(q[0], q[1], q[2]);
          tri.emplace_back(q[0], q[2], q[3]);
        }
    }
  s.triangles.resize(static_cast<Eigen::Index>(tri.size()), 3);
  for (size_t t = 0; t < tri.size(); ++t)
    s.triangles.row(static_cast<Eigen::Index>(t)) = tri[t].transpose();
  return s;
}

/// `count` points uniform on the surface s (a triangle drawn with probability proportional to
/// its area, a point uniform in it), fixed seed.
Eigen::MatrixXd surface_samples(const TriangleSurface& s, int count, unsigned seed) {
  std::vector<double> area(static_cast<size_t>(s.triangles.rows()));
  for (Eigen::Index t = 0; t < s.triangles.rows(); ++t) {
    const Eigen::Vector3d a = s.points.row(s.triangles(t, 0)), b = s.points.row(s.triangles(t, 1)),
                          c = s.points.row(s.triangles(t, 2));
    area[static_cast<size_t>(t)] = 0.5 * (b - a).cross(c - a).norm();
  }
  std::mt19937_64 gen(seed);
  std::discrete_distribution<Eigen::Index> pick(area.begin(), area.end());
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Eigen::MatrixXd out(count, 3);
  for (int j = 0; j < count; ++j) {
    const Eigen::Index t = pick(gen);
    const double r = std::sqrt(u(gen)), w = u(gen);  // a (1 − r) + b r (1 − w) + c r w
    out.row(j) = (1.0 - r) * s.points.row(s.triangles(t, 0)) +
                 r * (1.0 - w) * s.points.row(s.triangles(t, 1)) +
                 r * w * s.points.row(s.triangles(t, 2));
  }
  return out;
}

// An exact copy of a bent body's surface (formulation §8.5): 300 area-weighted samples of the
// cubic-bent bar's surface (not its nodes), moved by a random rotation and a translation of
// L/2. With the body's surface (body_triangles), the defaults recover the pose to rounding
// with either score: every scan point lies on the surface at the true pose, so the
// point-to-plane fit's residual is zero there and Gauss–Newton converges quadratically to it
// (observed below 1e-14 rad and L; asserted to 1e-9, the step tolerance 1e-10 L with room).
// With the nodes alone the same scan is not recovered (each scan point is paired with a node
// up to L/20 away: observed 3e-2 rad off), which is what the surface
// is for.
TEST(Align, ExactCopyOfABentSurfaceRecovered) {
  const TriangleSurface surface = cubic_bent_bar();
  const PointCloud body(surface.points);
  const double L = body_size(body);
  const Eigen::MatrixXd samples = surface_samples(surface, 300, 5);
  std::mt19937_64 gen(31);
  std::normal_distribution<double> n;
  AlignOptions o;
  o.distance.params.epsilon = 1e-3 * L;  // softhd align's default: L/1000
  o.threads = 2;
  for (int k = 0; k < 2; ++k) {
    Pose P = random_pose(gen);  // scan → body; the scan at a translation of L/2
    const Eigen::Vector3d shift = Eigen::Vector3d(n(gen), n(gen), n(gen)).normalized() * 0.5 * L;
    P.t = -(P.R * shift);
    const PointCloud scan(apply_points(P.inverse(), samples));
    o.score = k == 0 ? CandidateScore::coverage : CandidateScore::rho;
    o.body_triangles = surface.triangles;
    const AlignSummary s = align(body, scan, o);
    EXPECT_LT(rotation_angle_between(s.pose.R, P.R), 1e-9) << "pose " << k;
    EXPECT_LT((s.pose.t - P.t).norm(), 1e-9 * L) << "pose " << k;
    EXPECT_EQ(s.overlap, 1.0);
    EXPECT_LT(s.residuals.maxCoeff(), 1e-9 * L);
    if (k > 0) continue;
    o.body_triangles.resize(0, 3);  // the nodes alone
    const AlignSummary p = align(body, scan, o);
    const double without = rotation_angle_between(p.pose.R, P.R);
    std::printf("nodes alone: rotation error %.3g rad\n", without);
    EXPECT_GT(without, 1e-6);
  }
}

TEST(Align, BodyTrianglesRefusedNamingTheField) {
  const TriangleSurface surface = cubic_bent_bar();
  const PointCloud body(surface.points);
  AlignOptions o;
  o.body_triangles = surface.triangles;
  o.body_triangles(3, 1) = static_cast<int>(body.size());  // no such point
  test::expect_error<InvalidArgument>([&] { align(body, body, o); },
                                      "body_triangles must name the body's points");
  o.body_triangles = surface.triangles.topRows(surface.triangles.rows() - 1);  // open
  test::expect_error<InvalidArgument>([&] { align(body, body, o); }, "align: body_triangles: ");
}

/// bent_bar() on a table 0.05 under its lowest point, {z = z_min − 0.05}: the fixture.
Fixture bent_bar_fixture(const PointCloud& body) {
  Fixture f;
  f.normal = Eigen::Vector3d(0.0, 0.0, 2.0);  // not a unit vector: the plane is n·x = offset
  f.offset = 2.0 * (body.points().col(2).minCoeff() - 0.05);
  return f;
}

/// Every other point of `body` and a grid of the table {z = z_table} under it (spacing 0.05,
/// the body's footprint inflated by 0.3), moved into the camera's frame by P⁻¹.
PointCloud with_table(const PointCloud& body, double z_table, const Pose& P) {
  std::vector<Eigen::Vector3d> p;
  for (Eigen::Index i = 0; i < body.size(); i += 2) p.push_back(body.points().row(i).transpose());
  const Eigen::Vector3d lo = body.points().colwise().minCoeff(),
                        hi = body.points().colwise().maxCoeff();
  for (double x = lo.x() - 0.3; x <= hi.x() + 0.3; x += 0.05)
    for (double y = lo.y() - 0.3; y <= hi.y() + 0.3; y += 0.05) p.emplace_back(x, y, z_table);
  Eigen::MatrixXd m(static_cast<Eigen::Index>(p.size()), 3);
  for (size_t i = 0; i < p.size(); ++i) m.row(static_cast<Eigen::Index>(i)) = p[i].transpose();
  return PointCloud(apply_points(P.inverse(), m));
}

// The fixture (formulation §8.12): an exact copy of a bent body on a table, turned about the
// table's normal by any of 8 angles after a fixed tilt and shift, its table found by RANSAC in
// the scan and removed: align with the fixture (every other angle with the clamp's side too)
// recovers the pose to rounding (the exact pairs of the constrained nearest-point fit; observed
// 4e-16 to 2e-15 rad, asserted to 1e-9), and every pose keeps the table's tilt and height to
// rounding (asserted to 1e-12).
TEST(AlignFixture, BentBodyRecoveredAtAnyAngleAboutTheTable) {
  const PointCloud body = bent_bar();
  const double L = body_size(body);
  const Fixture fixture = bent_bar_fixture(body);
  std::mt19937_64 gen(11);
  const Pose G = random_pose(gen);  // the tilt and shift of the camera
  PlaneRemoval plane;
  plane.distance = 0.01;
  AlignOptions o = fast_options();
  o.fixture = fixture;
  o.rotations = 12;       // angles about the table's normal (every 30°): enough for an exact copy
  o.refine_points = 300;  // the refinement's clouds; the nearest-point finish takes every point
  for (int k = 0; k < 8; ++k) {
    Pose turn;  // about the table's normal (z) by 2πk/8 + 0.3
    turn.R = Eigen::AngleAxisd(2.0 * M_PI * k / 8 + 0.3, Eigen::Vector3d::UnitZ()).matrix();
    const Pose P = compose(turn, G);
    const PointCloud raw = with_table(body, fixture.offset / 2.0, P);
    o.table = find_dominant_plane(raw, plane);
    const PointCloud scan = select(raw, remove_dominant_plane(raw, plane));
    EXPECT_EQ(scan.size(), (body.size() + 1) / 2);
    // Odd angles with the clamp's side: arm 1's end x = 0 (−x), seen where P⁻¹ shows it, the
    // direction turned by 60° about the table as a user's coarse hint would be.
    o.fixture->clamp = k % 2 ? Eigen::Vector3d(-1.0, 0.0, 0.0) : Eigen::Vector3d::Zero();
    o.fixture->clamp_seen =
        k % 2 ? Eigen::Vector3d(P.R.transpose() *
                                Eigen::AngleAxisd(M_PI / 3, Eigen::Vector3d::UnitZ()).matrix() *
                                o.fixture->clamp)
              : Eigen::Vector3d::Zero();
    const AlignSummary s = align(body, scan, o);
    EXPECT_LT(rotation_angle_between(s.pose.R, P.R), 1e-9) << "angle " << k;
    EXPECT_LT((s.pose.t - P.t).norm(), 1e-9 * L) << "angle " << k;
    // The constraint: R n_s = n_b and n_b·t = d_b − d_s.
    const FixtureConstraint c(fixture, *o.table, scan.points());
    EXPECT_LT((s.pose.R * c.scan_normal() - c.body_normal()).norm(), 1e-12);
    EXPECT_LT(std::abs(c.body_normal().dot(s.pose.t) - c.body_offset() + c.scan_offset()),
              1e-12 * L);
  }
}

// The constrained least-squares fit (FixtureConstraint::fit) of exact pairs gives back a pose
// on the constraint to rounding; pairs off it by a rotation about the table's normal and a
// shift along the table are the same problem; and project() puts any pose on the constraint.
TEST(AlignFixture, ConstrainedFitAndProjection) {
  std::mt19937_64 gen(3);
  Fixture f;
  f.normal = Eigen::Vector3d(0.3, -0.2, 1.0);
  f.offset = -0.4;
  Plane table;
  table.normal = Eigen::Vector3d(-0.5, 0.8, 0.1);  // its sign is turned towards the points
  table.offset = 0.7;
  const Eigen::MatrixXd y = Eigen::MatrixXd::Random(40, 3);  // Eigen's fixed generator
  const FixtureConstraint c(f, table, y);
  // A pose Q on the constraint: start() at some angle, its inverse P the scan → body pose.
  const Pose Q = c.start(1.1, Eigen::Vector3d(0.2, 0.1, -0.3), Eigen::Vector3d(1.0, 2.0, 3.0));
  EXPECT_LT((Q.R * c.body_normal() - c.scan_normal()).norm(), 1e-15 * 10);
  EXPECT_LT(std::abs(c.scan_normal().dot(Q.t) - c.scan_offset() + c.body_offset()), 1e-14);
  const Pose P = Q.inverse();
  const Pose fitted = c.fit(y, apply_points(P, y));
  EXPECT_LT(rotation_angle_between(fitted.R, P.R), 1e-13);
  EXPECT_LT((fitted.t - P.t).norm(), 1e-13);
  // project(): a random pose ends on the constraint; one already on it stays.
  const Pose off = random_pose(gen);
  const Pose on = c.project(off, Eigen::Vector3d(0.5, 0.5, 0.5));
  EXPECT_LT((on.R * c.body_normal() - c.scan_normal()).norm(), 1e-14);
  EXPECT_LT(std::abs(c.scan_normal().dot(on.t) - c.scan_offset() + c.body_offset()), 1e-14);
  const Pose same = c.project(Q, Eigen::Vector3d(0.5, 0.5, 0.5));
  EXPECT_LT((same.matrix() - Q.matrix()).norm(), 1e-14);
  // The clamp's side: allowed while R_Q clamp, on the table, is within 90° of clamp_seen.
  EXPECT_TRUE(c.allows(Q));  // no side given
  Fixture sided = f;
  sided.clamp = Eigen::Vector3d(1.0, 0.0, 0.0);
  const Eigen::Vector3d seen = Q.R * sided.clamp;
  for (double sign : {1.0, -1.0}) {
    sided.clamp_seen = sign * seen;
    EXPECT_EQ(FixtureConstraint(sided, table, y).allows(Q), sign > 0);
  }
  // The tangent: 3 orthonormal twists, ω along n_s.
  const Eigen::MatrixXd B = c.tangent();
  EXPECT_LT((B.transpose() * B - Eigen::Matrix3d::Identity()).norm(), 1e-15 * 10);
}

TEST(AlignFixture, BadInputRefusedNamingTheField) {
  const PointCloud body = asymmetric_body(60, 8);
  AlignOptions o;
  o.fixture = Fixture{};
  test::expect_error<InvalidArgument>([&] { align(body, body, o); }, "table");
  Plane table;
  table.normal = Eigen::Vector3d::UnitZ();
  o.table = table;
  o.fixture->normal.setZero();
  test::expect_error<InvalidArgument>([&] { align(body, body, o); },
                                      "fixture.normal has zero length");
  o.fixture->normal = Eigen::Vector3d(0.0, std::nan(""), 1.0);
  test::expect_error<InvalidArgument>([&] { align(body, body, o); }, "fixture.normal");
  o.fixture = Fixture{};
  o.fixture->offset = std::nan("");
  test::expect_error<InvalidArgument>([&] { align(body, body, o); }, "fixture.offset");
  o.fixture = Fixture{};
  o.kind = PoseKind::similarity;
  test::expect_error<InvalidArgument>([&] { align(body, body, o); }, "rigid");
  o.kind = PoseKind::rigid;
  o.table->normal = Eigen::Vector3d::Zero();
  test::expect_error<InvalidArgument>([&] { align(body, body, o); },
                                      "table normal has zero length");
  o.table->normal = Eigen::VectorXd::Unit(2, 1);  // a 2D plane
  test::expect_error<InvalidArgument>([&] { align(body, body, o); }, "table");
  o.table->normal = Eigen::Vector3d::UnitZ();
  o.fixture->clamp = Eigen::Vector3d::UnitX();  // without clamp_seen
  test::expect_error<InvalidArgument>([&] { align(body, body, o); }, "fixture.clamp and");
  o.fixture->clamp = Eigen::Vector3d::UnitZ();  // along the normal
  o.fixture->clamp_seen = Eigen::Vector3d::UnitX();
  test::expect_error<InvalidArgument>([&] { align(body, body, o); }, "fixture.clamp is along");
  o.fixture->clamp_seen = Eigen::Vector3d(std::nan(""), 0.0, 0.0);
  test::expect_error<InvalidArgument>([&] { align(body, body, o); }, "fixture.clamp_seen");
}

}  // namespace
}  // namespace softhd::scan
