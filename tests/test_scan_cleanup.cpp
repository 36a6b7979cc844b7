// Scan clean-up (docs/formulation.md §8.8): crop, statistical outliers and the dominant plane,
// against brute force on small clouds, and on a synthetic scene (a box body on a table with
// uniform outliers).

#include <gtest/gtest.h>
#include <omp.h>

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "expect_error.hpp"
#include "softhd/scan/cleanup.hpp"

using softhd::InvalidArgument;
using softhd::PointCloud;
using softhd::test::expect_error;
namespace scan = softhd::scan;
using Indices = std::vector<Eigen::Index>;

namespace {

double uniform(std::mt19937_64& rng, double lo, double hi) {
  return lo + (hi - lo) * std::uniform_real_distribution<double>(0.0, 1.0)(rng);
}

Eigen::MatrixXd random_points(Eigen::Index n, int d, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  Eigen::MatrixXd x(n, d);
  for (Eigen::Index i = 0; i < n; ++i)
    for (int k = 0; k < d; ++k) x(i, k) = uniform(rng, 0.0, 1.0);
  return x;
}

// Brute force: the mean distance of each point to its k nearest others, by sorting all.
Indices brute_statistical_outliers(const Eigen::MatrixXd& x, int k, double ratio) {
  const Eigen::Index n = x.rows();
  std::vector<double> m(static_cast<size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) {
    std::vector<double> d;
    for (Eigen::Index j = 0; j < n; ++j)
      if (j != i) d.push_back((x.row(i) - x.row(j)).norm());
    std::sort(d.begin(), d.end());
    double s = 0;
    for (int q = 0; q < k; ++q) s += d[static_cast<size_t>(q)];
    m[static_cast<size_t>(i)] = s / k;
  }
  double mu = 0, var = 0;
  for (double v : m) mu += v / double(n);
  for (double v : m) var += (v - mu) * (v - mu) / double(n - 1);
  Indices kept;
  for (Eigen::Index i = 0; i < n; ++i)
    if (m[static_cast<size_t>(i)] <= mu + ratio * std::sqrt(var)) kept.push_back(i);
  return kept;
}

}  // namespace

TEST(ScanCrop, MatchesTheInflatedBoxPointByPoint) {
  const Eigen::MatrixXd x = random_points(500, 3, 3) * 3.0 - Eigen::MatrixXd::Ones(500, 3);
  const PointCloud cloud(x);
  const Eigen::Vector3d lo(0.0, 0.2, -0.1), hi(1.0, 0.6, 0.3);
  const double margin = 0.1, m = margin * (hi - lo).norm();
  Indices expected;
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    bool in = true;
    for (int k = 0; k < 3; ++k) in = in && x(i, k) >= lo[k] - m && x(i, k) <= hi[k] + m;
    if (in) expected.push_back(i);
  }
  EXPECT_EQ(scan::crop_to_box(cloud, lo, hi, margin), expected);
  EXPECT_GT(expected.size(), 5u);
  EXPECT_LT(expected.size(), 100u);
}

TEST(ScanCrop, RefusesBadBoxes) {
  const PointCloud cloud(random_points(10, 3, 1));
  expect_error<InvalidArgument>(
      [&] { scan::crop_to_box(cloud, Eigen::Vector2d(0, 0), Eigen::Vector2d(1, 1), 0.0); },
      "dimension 3");
  expect_error<InvalidArgument>(
      [&] { scan::crop_to_box(cloud, Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0, 1, 1), 0.0); },
      "lower <= upper");
  expect_error<InvalidArgument>(
      [&] { scan::crop_to_box(cloud, Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 1, 1), -1); },
      "margin");
}

TEST(ScanOutliers, MatchBruteForce) {
  for (int d : {2, 3}) {
    Eigen::MatrixXd x = random_points(300, d, 7 + d);
    x.row(10).setConstant(4.0);  // two far points
    x.row(20).setConstant(-3.0);
    x.row(30) = x.row(31);  // a duplicate
    const PointCloud cloud(x);
    for (int k : {1, 5, 20}) {
      for (double ratio : {0.5, 2.0}) {
        const Indices kept = scan::remove_statistical_outliers(cloud, k, ratio);
        EXPECT_EQ(kept, brute_statistical_outliers(x, k, ratio)) << d << "D k=" << k;
        EXPECT_EQ(std::count(kept.begin(), kept.end(), 10), 0);
      }
    }
  }
}

TEST(ScanOutliers, RefuseBadParameters) {
  const PointCloud cloud(random_points(10, 3, 1));
  expect_error<InvalidArgument>([&] { scan::remove_statistical_outliers(cloud, 0, 1.0); },
                                "k must");
  expect_error<InvalidArgument>([&] { scan::remove_statistical_outliers(cloud, 10, 1.0); },
                                "k must");
  expect_error<InvalidArgument>([&] { scan::remove_statistical_outliers(cloud, 3, NAN); }, "ratio");
}

TEST(ScanPlane, FindsTheLeastSquaresPlaneOfItsInliers) {
  // 600 points near the plane n·x = 0.4 (noise ±0.003), 300 uniform points off it (n·x > 0.9).
  std::mt19937_64 rng(11);
  const Eigen::Vector3d n = Eigen::Vector3d(0.3, -0.2, 1.0).normalized();
  const Eigen::Vector3d e1 = n.unitOrthogonal(), e2 = n.cross(e1);
  Eigen::MatrixXd x(900, 3);
  for (Eigen::Index i = 0; i < 600; ++i)
    x.row(i) = (0.4 + uniform(rng, -0.003, 0.003)) * n + uniform(rng, -1, 1) * e1 +
               uniform(rng, -1, 1) * e2;
  for (Eigen::Index i = 600; i < 900; ++i)
    x.row(i) = Eigen::Vector3d(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, 1.5, 2.5));
  const PointCloud cloud(x);
  scan::PlaneRemoval options;
  options.distance = 0.01;
  const scan::Plane plane = scan::find_dominant_plane(cloud, options);
  // Independent least squares: the smallest right singular vector of the centred inliers.
  Indices inliers;
  for (Eigen::Index i = 0; i < 900; ++i)
    if (std::abs(plane.normal.dot(x.row(i).transpose()) - plane.offset) <= options.distance)
      inliers.push_back(i);
  Eigen::MatrixXd in(static_cast<Eigen::Index>(inliers.size()), 3);
  for (size_t r = 0; r < inliers.size(); ++r) in.row(Eigen::Index(r)) = x.row(inliers[r]);
  const Eigen::RowVector3d c = in.colwise().mean();
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(in.rowwise() - c, Eigen::ComputeThinV);
  Eigen::Vector3d ls = svd.matrixV().col(2);
  if (ls.dot(plane.normal) < 0) ls = -ls;
  EXPECT_EQ(plane.inliers, 600);
  EXPECT_EQ(inliers.size(), 600u);
  EXPECT_LT((ls - plane.normal).norm(), 1e-9);
  EXPECT_NEAR(plane.offset, ls.dot(c.transpose()), 1e-9);
  EXPECT_LT(std::acos(std::min(1.0, plane.normal.dot(n))), 0.01);
  // remove_dominant_plane keeps exactly the others, in order.
  Indices off;
  for (Eigen::Index i = 600; i < 900; ++i) off.push_back(i);
  EXPECT_EQ(scan::remove_dominant_plane(cloud, options), off);
  // Deterministic whatever the thread count.
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const scan::Plane serial = scan::find_dominant_plane(cloud, options);
  omp_set_num_threads(threads);
  EXPECT_EQ(serial.normal, plane.normal);
  EXPECT_EQ(serial.offset, plane.offset);
  // A plane holding too few points removes nothing.
  options.min_fraction = 0.7;
  EXPECT_EQ(scan::remove_dominant_plane(cloud, options).size(), 900u);
}

TEST(ScanPlane, FindsALineIn2D) {
  std::mt19937_64 rng(5);
  Eigen::MatrixXd x(300, 2);
  for (Eigen::Index i = 0; i < 200; ++i) x.row(i) = Eigen::Vector2d(uniform(rng, -1, 1), 0.25);
  for (Eigen::Index i = 200; i < 300; ++i)
    x.row(i) = Eigen::Vector2d(uniform(rng, -1, 1), uniform(rng, 0.5, 1.0));
  scan::PlaneRemoval options;
  options.distance = 1e-6;
  const scan::Plane plane = scan::find_dominant_plane(PointCloud(x), options);
  EXPECT_EQ(plane.inliers, 200);
  EXPECT_NEAR(plane.normal[1], 1.0, 1e-12);
  EXPECT_NEAR(plane.offset, 0.25, 1e-12);
}

TEST(ScanPlane, RefusesBadOptions) {
  const PointCloud cloud(random_points(10, 3, 1));
  scan::PlaneRemoval options;
  expect_error<InvalidArgument>([&] { scan::remove_dominant_plane(cloud, options); },
                                "PlaneRemoval.distance");
  options.distance = 0.1;
  options.iterations = 0;
  expect_error<InvalidArgument>([&] { options.validate(); }, "PlaneRemoval.iterations");
  options.iterations = 10;
  options.min_fraction = 1.5;
  expect_error<InvalidArgument>([&] { options.validate(); }, "PlaneRemoval.min_fraction");
  expect_error<InvalidArgument>([&] { scan::select(cloud, {}); }, "no points");
  expect_error<InvalidArgument>([&] { scan::select(cloud, {10}); }, "out of range");
}

namespace {

// The synthetic scene: a box body [0,1]×[0,0.5]×[0,0.3] standing on the table z = 0, its top
// and sides sampled uniformly (2500 points per unit area, noise ±0.002), the table
// [−1,2]×[−1,1.5] outside the body's footprint at the same density, and 3 % of the total
// as uniform outliers in [−1,2]×[−1,1.5]×[0,1]. Labels: 0 body, 1 table, 2 outlier.
struct Scene {
  Eigen::MatrixXd points;
  std::vector<int> label;
};

Scene make_scene() {
  std::mt19937_64 rng(2026);
  std::vector<Eigen::Vector3d> p;
  std::vector<int> label;
  auto noise = [&] { return uniform(rng, -0.002, 0.002); };
  const double density = 2500;
  auto face = [&](int axis, double at, Eigen::Vector2d lo, Eigen::Vector2d hi) {
    const int n = int(density * (hi - lo).prod());
    for (int i = 0; i < n; ++i) {
      const double u = uniform(rng, lo[0], hi[0]), v = uniform(rng, lo[1], hi[1]);
      Eigen::Vector3d q;
      q[axis] = at + noise();
      q[(axis + 1) % 3] = u;
      q[(axis + 2) % 3] = v;
      p.push_back(q), label.push_back(0);
    }
  };
  face(2, 0.3, {0, 0}, {1, 0.5});    // top: x, y
  face(0, 0.0, {0, 0}, {0.5, 0.3});  // x = 0: y, z
  face(0, 1.0, {0, 0}, {0.5, 0.3});  // x = 1
  face(1, 0.0, {0, 0}, {0.3, 1.0});  // y = 0: z, x
  face(1, 0.5, {0, 0}, {0.3, 1.0});  // y = 0.5
  const int table = int(density * 3.0 * 2.5);
  for (int i = 0; i < table; ++i) {
    const double x = uniform(rng, -1, 2), y = uniform(rng, -1, 1.5);
    if (x >= 0 && x <= 1 && y >= 0 && y <= 0.5) continue;  // under the body
    p.emplace_back(x, y, noise()), label.push_back(1);
  }
  const int outliers = int(0.03 * double(p.size()) / 0.97);
  for (int i = 0; i < outliers; ++i)
    p.emplace_back(uniform(rng, -1, 2), uniform(rng, -1, 1.5), uniform(rng, 0, 1)),
        label.push_back(2);
  Scene s;
  s.points.resize(static_cast<Eigen::Index>(p.size()), 3);
  for (size_t i = 0; i < p.size(); ++i) s.points.row(Eigen::Index(i)) = p[i].transpose();
  s.label = label;
  return s;
}

}  // namespace

// The goal: the plane and ≥ 95 % of the outliers removed, ≥ 99 % of the body kept
// (body points farther than the plane threshold from the table: nearer ones are the table's).
TEST(ScanCleanup, SyntheticSceneKeepsTheBody) {
  const Scene s = make_scene();
  const PointCloud cloud(s.points);
  // The order of a scene's target block: crop → plane → outliers.
  Indices kept =
      scan::crop_to_box(cloud, Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0.5, 0.3), 0.3);
  PointCloud step = scan::select(cloud, kept);
  scan::PlaneRemoval plane;
  plane.distance = 0.01;
  auto compose = [&](const Indices& inner) {
    Indices out;
    for (Eigen::Index i : inner) out.push_back(kept[static_cast<size_t>(i)]);
    kept = out;
    step = scan::select(cloud, kept);
  };
  compose(scan::remove_dominant_plane(step, plane));
  compose(scan::remove_statistical_outliers(step, 20, 2.0));
  std::vector<bool> alive(s.label.size(), false);
  for (Eigen::Index i : kept) alive[static_cast<size_t>(i)] = true;
  int body = 0, body_kept = 0, table = 0, table_kept = 0, out = 0, out_kept = 0;
  for (size_t i = 0; i < s.label.size(); ++i) {
    const bool a = alive[i];
    if (s.label[i] == 0 && s.points(Eigen::Index(i), 2) > plane.distance) body++, body_kept += a;
    if (s.label[i] == 1) table++, table_kept += a;
    if (s.label[i] == 2) out++, out_kept += a;
  }
  RecordProperty("body_kept", body_kept), RecordProperty("body", body);
  RecordProperty("outliers_kept", out_kept), RecordProperty("outliers", out);
  RecordProperty("table_kept", table_kept), RecordProperty("table", table);
  std::printf("body kept %d of %d, table kept %d of %d, outliers kept %d of %d\n", body_kept, body,
              table_kept, table, out_kept, out);
  EXPECT_GE(body_kept, 0.99 * body);
  EXPECT_LE(table_kept, 0.001 * table);
  EXPECT_LE(out_kept, 0.05 * out);
}
