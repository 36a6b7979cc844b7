// Surface weights of a scan (docs/formulation.md §8.9): exact cells on grids, and the issue's
// goals on a sphere sampled with a 10:1 density contrast (summed areas within 3 % of 4π, ρ̃
// within 2 % of its value against a dense uniform sample).

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>
#include <vector>

#include "expect_error.hpp"
#include "softhd/hausdorff.hpp"
#include "softhd/samplers.hpp"
#include "softhd/scan/surface_weights.hpp"

using softhd::InvalidArgument;
using softhd::PointCloud;
using softhd::scan::AreaEstimate;
using softhd::test::expect_error;
namespace scan = softhd::scan;

namespace {

constexpr double kPi = 3.14159265358979323846;

// n points on the unit sphere, density ∝ 1 + 9 (z + 1)/2 (10:1 from z = 1 to z = −1), by
// rejection from the uniform (Archimedes: z uniform, azimuth uniform).
PointCloud graded_sphere(Eigen::Index n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Eigen::MatrixXd x(n, 3);
  for (Eigen::Index i = 0; i < n;) {
    const double z = 2.0 * u(rng) - 1.0, phi = 2.0 * kPi * u(rng);
    if (10.0 * u(rng) > 1.0 + 4.5 * (z + 1.0)) continue;
    const double r = std::sqrt(1.0 - z * z);
    x.row(i++) << r * std::cos(phi), r * std::sin(phi), z;
  }
  return PointCloud(x);
}

// n points on the bent plate {(s, cos t, sin t) : s ∈ [0, 2], t ∈ [0, π/2]} (area π), an
// open surface: density ∝ 1 + 4.5 s (10:1 along s) if `graded`, else uniform; each point
// weighs π/n.
PointCloud bent_plate(Eigen::Index n, bool graded, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Eigen::MatrixXd x(n, 3);
  for (Eigen::Index i = 0; i < n;) {
    const double s = 2.0 * u(rng), t = 0.5 * kPi * u(rng);
    if (graded && 10.0 * u(rng) > 1.0 + 4.5 * s) continue;
    x.row(i++) << s, std::cos(t), std::sin(t);
  }
  return PointCloud(x, Eigen::VectorXd::Constant(n, kPi / double(n)));
}

// A planar h-grid of (2m+1)² points in a tilted plane.
Eigen::MatrixXd tilted_grid(int m, double h) {
  const Eigen::Vector3d n = Eigen::Vector3d(1, 2, 3).normalized();
  const Eigen::Vector3d e1 = n.unitOrthogonal(), e2 = n.cross(e1);
  Eigen::MatrixXd x((2 * m + 1) * (2 * m + 1), 3);
  Eigen::Index r = 0;
  for (int i = -m; i <= m; ++i)
    for (int j = -m; j <= m; ++j) x.row(r++) = (h * i * e1 + h * j * e2).transpose();
  return x;
}

}  // namespace

TEST(SurfaceWeights, VoronoiCellOfAGridPointIsTheCell) {
  // Interior grid points: the Voronoi cell is the h × h square, however ties (four co-circular
  // neighbours) fall.
  const double h = 0.1;
  const Eigen::VectorXd a =
      scan::area_weights(PointCloud(tilted_grid(6, h)), AreaEstimate::delaunay, 12);
  for (int i = -4; i <= 4; ++i)
    for (int j = -4; j <= 4; ++j) EXPECT_NEAR(a[(i + 6) * 13 + (j + 6)], h * h, 1e-14) << i << j;
}

TEST(SurfaceWeights, KnnAreaIsPiRkSquaredOverK) {
  // On the grid the 4th neighbour is at h, the 8th at h√2 (brute force by counting).
  const double h = 0.1;
  const PointCloud grid(tilted_grid(6, h));
  const Eigen::Index centre = 6 * 13 + 6;
  EXPECT_NEAR(scan::area_weights(grid, AreaEstimate::knn, 4)[centre], kPi * h * h / 4, 1e-14);
  EXPECT_NEAR(scan::area_weights(grid, AreaEstimate::knn, 8)[centre], kPi * 2 * h * h / 8, 1e-14);
}

TEST(SurfaceWeights, CurveLengthsIn2D) {
  // A circle sampled at angles t_i (10:1 density): the Voronoi length is half the chord gaps
  // projected on the tangent; the sum is 2π to second order.
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Eigen::MatrixXd x(2000, 2);
  for (Eigen::Index i = 0; i < x.rows();) {
    const double t = 2 * kPi * u(rng);
    if (10.0 * u(rng) > 1.0 + 9.0 * std::abs(std::sin(t / 2))) continue;
    x.row(i++) << std::cos(t), std::sin(t);
  }
  const PointCloud c(x);
  EXPECT_NEAR(scan::area_weights(c, AreaEstimate::delaunay, 4).sum(), 2 * kPi, 0.005 * 2 * kPi);
  EXPECT_NEAR(scan::area_weights(c, AreaEstimate::knn, 8).sum(), 2 * kPi, 0.03 * 2 * kPi);
}

// Goal 1: summed weights within 3 % of the true area under a 10:1 density contrast.
TEST(SurfaceWeights, SumToTheSphereAreaUnderTenToOneDensity) {
  const PointCloud y = graded_sphere(3000, 17);
  for (AreaEstimate e : {AreaEstimate::knn, AreaEstimate::delaunay}) {
    const double sum = scan::area_weights(y, e, 12).sum();
    std::printf("%s: summed area %.5f, 4π = %.5f, relative error %.4f\n",
                scan::to_string(e).c_str(), sum, 4 * kPi, sum / (4 * kPi) - 1);
    EXPECT_NEAR(sum, 4 * kPi, 0.03 * 4 * kPi) << scan::to_string(e);
  }
}

// Goal 2: ρ̃ against the graded sample with estimated weights within 2 % of ρ̃ against a
// dense uniform sample; with unit weights it is not (the test would catch weights ignored).
TEST(SurfaceWeights, RhoMatchesTheDenseUniformSample) {
  const PointCloud x = softhd::sample_sphere_shell(Eigen::Vector3d(0, 0, 0.3), 1.0, 2000, 5);
  const PointCloud dense = softhd::sample_sphere_shell(Eigen::Vector3d::Zero(), 1.0, 12000, 6);
  const PointCloud graded = graded_sphere(3000, 17);
  const double reference = softhd::hausdorff(x, dense).rho;
  const double unit = softhd::hausdorff(x, graded).rho;
  std::printf("rho dense %.6f, graded with unit weights %.6f (%.4f)\n", reference, unit,
              unit / reference - 1);
  EXPECT_GT(std::abs(unit / reference - 1), 0.02);
  for (AreaEstimate e : {AreaEstimate::knn, AreaEstimate::delaunay}) {
    const double rho = softhd::hausdorff(x, scan::with_area_weights(graded, e, 12)).rho;
    std::printf("%s: rho %.6f (%.4f)\n", scan::to_string(e).c_str(), rho, rho / reference - 1);
    EXPECT_NEAR(rho, reference, 0.02 * reference) << scan::to_string(e);
  }
}

// The same goals on an open surface, where the border matters: delaunay meets both (its
// border cells are twice their inward half); knn overestimates at the border (measured,
// printed, not asserted: docs/formulation.md §8.9 says to prefer delaunay for open scans).
TEST(SurfaceWeights, OpenBentPlateUnderTenToOneDensity) {
  const PointCloud graded = bent_plate(3000, true, 21);
  const PointCloud dense = bent_plate(12000, false, 22);
  PointCloud x = bent_plate(1500, false, 23);
  x = PointCloud(x.points().rowwise() + Eigen::RowVector3d(0.0, 0.25, 0.25));
  const double reference = softhd::hausdorff(x, dense).rho;
  const double unit = softhd::hausdorff(x, PointCloud(graded.points())).rho;
  std::printf("plate: rho dense %.6f, graded with unit weights %.6f (%.4f)\n", reference, unit,
              unit / reference - 1);
  for (AreaEstimate e : {AreaEstimate::knn, AreaEstimate::delaunay}) {
    const PointCloud w = scan::with_area_weights(graded, e, 12);
    const double sum = w.volumes().sum(), rho = softhd::hausdorff(x, w).rho;
    std::printf("plate %s: summed area %.5f (%.4f), rho %.6f (%.4f)\n", scan::to_string(e).c_str(),
                sum, sum / kPi - 1, rho, rho / reference - 1);
    if (e == AreaEstimate::delaunay) {
      EXPECT_NEAR(sum, kPi, 0.03 * kPi);
      EXPECT_NEAR(rho, reference, 0.02 * reference);
    }
  }
}

TEST(SurfaceWeights, RefusesBadNeighbours) {
  const PointCloud y = graded_sphere(20, 1);
  expect_error<InvalidArgument>([&] { scan::area_weights(y, AreaEstimate::knn, 0); }, "neighbours");
  expect_error<InvalidArgument>([&] { scan::area_weights(y, AreaEstimate::knn, 20); },
                                "neighbours");
  expect_error<InvalidArgument>([&] { scan::area_weights(y, AreaEstimate::delaunay, 2); },
                                "neighbours");
  const PointCloud same(Eigen::MatrixXd::Ones(5, 3));
  expect_error<InvalidArgument>([&] { scan::area_weights(same, AreaEstimate::knn, 2); }, "no area");
  EXPECT_EQ(scan::area_estimate_from_string("knn"), AreaEstimate::knn);
  expect_error<InvalidArgument>([] { scan::area_estimate_from_string("voronoi"); },
                                "expected knn or delaunay");
}
