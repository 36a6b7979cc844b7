#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "expect_error.hpp"
#include "softhd/error.hpp"
#include "softhd/samplers.hpp"

using softhd::InvalidArgument;
using softhd::PointCloud;
using softhd::test::expect_error;

namespace {

constexpr double kPi = 3.14159265358979323846;

Eigen::VectorXd vec(std::initializer_list<double> v) {
  Eigen::VectorXd out(static_cast<Eigen::Index>(v.size()));
  Eigen::Index i = 0;
  for (double x : v) out[i++] = x;
  return out;
}

Eigen::VectorXi ivec(std::initializer_list<int> v) {
  Eigen::VectorXi out(static_cast<Eigen::Index>(v.size()));
  Eigen::Index i = 0;
  for (int x : v) out[i++] = x;
  return out;
}

bool bit_equal(const PointCloud& a, const PointCloud& b) {
  return a.dim() == b.dim() && a.size() == b.size() &&
         std::memcmp(a.points().data(), b.points().data(),
                     sizeof(double) * static_cast<std::size_t>(a.points().size())) == 0 &&
         std::memcmp(a.volumes().data(), b.volumes().data(),
                     sizeof(double) * static_cast<std::size_t>(a.size())) == 0;
}

// Mean of coordinate k (a plain loop: GCC 12 warns spuriously inside Eigen's
// AVX-512 reductions).
double column_mean(const PointCloud& c, int k) {
  double sum = 0.0;
  for (Eigen::Index i = 0; i < c.size(); ++i) sum += c.points()(i, k);
  return sum / static_cast<double>(c.size());
}

// Integral of x^p over [a, b].
double integral_power(double a, double b, int p) {
  return (std::pow(b, p + 1) - std::pow(a, p + 1)) / (p + 1);
}

// sum_i V_i prod_k x_ik^powers[k]
double quadrature(const PointCloud& c, const std::vector<int>& powers) {
  double sum = 0.0;
  for (Eigen::Index i = 0; i < c.size(); ++i) {
    double f = 1.0;
    for (int k = 0; k < c.dim(); ++k) f *= std::pow(c.points()(i, k), powers[k]);
    sum += c.volumes()[i] * f;
  }
  return sum;
}

double exact(const Eigen::VectorXd& lo, const Eigen::VectorXd& hi, const std::vector<int>& powers) {
  double r = 1.0;
  for (Eigen::Index k = 0; k < lo.size(); ++k) r *= integral_power(lo[k], hi[k], powers[k]);
  return r;
}

}  // namespace

// Relative error bound of a floating-point sum of n positive terms, each rounded
// once from its exact value: (n + 1) u, u = 2^-53 (recursive summation).
double summation_bound(Eigen::Index n) {
  return static_cast<double>(n + 1) * std::numeric_limits<double>::epsilon() / 2;
}

// ----------------------------------------------------------------------------
// sample_box_grid

TEST(BoxGrid, CellCentresAndVolumes) {
  const Eigen::VectorXd lo = vec({-1.0, 0.5, 2.0}), hi = vec({2.0, 1.0, 2.7});
  const Eigen::VectorXi n = ivec({3, 4, 5});
  const PointCloud c = softhd::sample_box_grid(lo, hi, n);
  ASSERT_EQ(c.dim(), 3);
  ASSERT_EQ(c.size(), 60);
  const double box = 3.0 * 0.5 * 0.7;
  EXPECT_NEAR(c.total_volume(), box, 1e-14 * box);
  std::set<std::vector<long>> cells;
  for (Eigen::Index i = 0; i < c.size(); ++i) {
    EXPECT_NEAR(c.volumes()[i], box / 60, 1e-15);
    std::vector<long> cell;
    for (int k = 0; k < 3; ++k) {
      const double h = (hi[k] - lo[k]) / n[k];
      const double t = (c.points()(i, k) - lo[k]) / h - 0.5;  // cell index if centred
      EXPECT_NEAR(t, std::round(t), 1e-12);
      EXPECT_GE(std::lround(t), 0);
      EXPECT_LT(std::lround(t), n[k]);
      cell.push_back(std::lround(t));
    }
    cells.insert(cell);
  }
  EXPECT_EQ(cells.size(), 60u);  // every cell exactly once
  // x varies fastest.
  EXPECT_NEAR(c.points()(1, 0) - c.points()(0, 0), 1.0, 1e-15);
  EXPECT_EQ(c.points()(1, 1), c.points()(0, 1));
}

TEST(BoxGrid, MidpointRuleIsExactForMultilinear) {
  const Eigen::VectorXd lo = vec({0.25, -3.0}), hi = vec({1.75, 1.0});
  const PointCloud c = softhd::sample_box_grid(lo, hi, ivec({7, 2}));
  ASSERT_EQ(c.dim(), 2);
  ASSERT_EQ(c.size(), 14);
  EXPECT_NEAR(c.total_volume(), 6.0, 1e-14);
  EXPECT_NEAR(quadrature(c, {1, 1}), exact(lo, hi, {1, 1}), 1e-13);
  EXPECT_NEAR(quadrature(c, {1, 0}), exact(lo, hi, {1, 0}), 1e-13);
  // ... but not for x^2 (midpoint error -h^2/12 per unit length): a sanity check.
  EXPECT_GT(std::abs(quadrature(c, {2, 0}) - exact(lo, hi, {2, 0})), 1e-3);
}

TEST(BoxGrid, SingleCell) {
  const PointCloud c = softhd::sample_box_grid(vec({0, 0}), vec({2, 4}), ivec({1, 1}));
  ASSERT_EQ(c.size(), 1);
  EXPECT_EQ(c.points()(0, 0), 1.0);
  EXPECT_EQ(c.points()(0, 1), 2.0);
  EXPECT_EQ(c.volumes()[0], 8.0);
}

// ----------------------------------------------------------------------------
// sample_q2_nodes

TEST(Q2Nodes, OneElementWeights) {
  // 2D, one element: Simpson weights (1,4,1) x (1,4,1) * L1 L2 / 36.
  const PointCloud c = softhd::sample_q2_nodes(vec({0, 0}), vec({3, 6}), ivec({1, 1}));
  ASSERT_EQ(c.size(), 9);
  const double w[3] = {1, 4, 1};
  const double x[3] = {0, 1.5, 3}, y[3] = {0, 3, 6};
  for (int j = 0; j < 3; ++j) {
    for (int i = 0; i < 3; ++i) {
      const Eigen::Index p = i + 3 * j;
      EXPECT_EQ(c.points()(p, 0), x[i]);
      EXPECT_EQ(c.points()(p, 1), y[j]);
      EXPECT_DOUBLE_EQ(c.volumes()[p], w[i] * w[j] * 18.0 / 36.0);
    }
  }
}

TEST(Q2Nodes, SharedNodeWeights1DPattern) {
  // Two elements in x, one in y: x weights h/6 * (1, 4, 2, 4, 1) with h = 1.
  const PointCloud c = softhd::sample_q2_nodes(vec({0, 0}), vec({2, 1}), ivec({2, 1}));
  ASSERT_EQ(c.size(), 15);
  const double wx[5] = {1, 4, 2, 4, 1};
  for (int i = 0; i < 5; ++i) {
    EXPECT_EQ(c.points()(i, 0), 0.5 * i);
    EXPECT_DOUBLE_EQ(c.volumes()[i], wx[i] / 6.0 * 1.0 / 6.0);
  }
}

TEST(Q2Nodes, CountsCornersAndTotal) {
  const Eigen::VectorXd lo = vec({-1.0, 0.1, 2.0}), hi = vec({0.3, 0.2, 5.0});
  const PointCloud c = softhd::sample_q2_nodes(lo, hi, ivec({2, 3, 4}));
  ASSERT_EQ(c.dim(), 3);
  ASSERT_EQ(c.size(), 5 * 7 * 9);
  const double box = 1.3 * 0.1 * 3.0;
  EXPECT_NEAR(c.total_volume(), box, 1e-14 * box);
  // The first and last nodes are the box corners, exactly.
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(c.points()(0, k), lo[k]);
    EXPECT_EQ(c.points()(c.size() - 1, k), hi[k]);
  }
  for (Eigen::Index i = 0; i < c.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      EXPECT_GE(c.points()(i, k), lo[k]);
      EXPECT_LE(c.points()(i, k), hi[k]);
    }
  }
}

TEST(Q2Nodes, SimpsonIntegratesTensorCubicsExactly) {
  {
    const Eigen::VectorXd lo = vec({-0.5, 1.0}), hi = vec({2.0, 1.75});
    const PointCloud c = softhd::sample_q2_nodes(lo, hi, ivec({3, 2}));
    for (const std::vector<int>& p :
         std::vector<std::vector<int>>{{3, 2}, {3, 3}, {2, 1}, {0, 3}, {1, 0}}) {
      const double e = exact(lo, hi, p);
      EXPECT_NEAR(quadrature(c, p), e, 1e-13 * std::max(1.0, std::abs(e))) << p[0] << " " << p[1];
    }
    // x^4 is not integrated exactly (Simpson's error term): a sanity check.
    EXPECT_GT(std::abs(quadrature(c, {4, 0}) - exact(lo, hi, {4, 0})), 1e-4);
  }
  {
    const Eigen::VectorXd lo = vec({0.0, -1.0, 0.5}), hi = vec({1.0, 2.0, 1.5});
    const PointCloud c = softhd::sample_q2_nodes(lo, hi, ivec({1, 2, 3}));
    const std::vector<int> p = {3, 2, 3};
    const double e = exact(lo, hi, p);
    EXPECT_NEAR(quadrature(c, p), e, 1e-13 * std::abs(e));
  }
}

// ----------------------------------------------------------------------------
// sample_uniform_random

TEST(UniformRandom, InsideBoxEqualVolumesDeterministic) {
  const Eigen::VectorXd lo = vec({-2.0, 0.1, 10.0}), hi = vec({-1.0, 0.3, 10.5});
  const Eigen::Index n = 20000;
  const PointCloud c = softhd::sample_uniform_random(lo, hi, n, 42);
  ASSERT_EQ(c.dim(), 3);
  ASSERT_EQ(c.size(), n);
  const double box = 1.0 * 0.2 * 0.5;
  EXPECT_NEAR(c.total_volume(), box, summation_bound(n) * box);
  EXPECT_TRUE((c.volumes().array() == c.volumes()[0]).all());
  for (Eigen::Index i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) {
      ASSERT_GE(c.points()(i, k), lo[k]);
      ASSERT_LT(c.points()(i, k), hi[k]);
    }
  }
  // Mean and variance of each coordinate: (lo+hi)/2 and w^2/12, within ~5 sigma.
  for (int k = 0; k < 3; ++k) {
    const double w = hi[k] - lo[k];
    const double mean = column_mean(c, k);
    EXPECT_NEAR(mean, 0.5 * (lo[k] + hi[k]), 5 * w / std::sqrt(12.0 * n));
    double var = 0.0;
    for (Eigen::Index i = 0; i < n; ++i) var += std::pow(c.points()(i, k) - mean, 2) / n;
    EXPECT_NEAR(var, w * w / 12, 5 * w * w / std::sqrt(180.0 * n));
  }
  EXPECT_TRUE(bit_equal(softhd::sample_uniform_random(lo, hi, n, 42), c));
  EXPECT_FALSE(bit_equal(softhd::sample_uniform_random(lo, hi, n, 43), c));
}

TEST(UniformRandom, FollowsTheDocumentedRecipe) {
  // The documented construction, written out independently: one mt19937_64 draw
  // per coordinate, top 53 bits scaled by 2^-53.
  const Eigen::VectorXd lo = vec({1.0, -4.0}), hi = vec({3.0, 4.0});
  const PointCloud c = softhd::sample_uniform_random(lo, hi, 5, 2024);
  std::mt19937_64 rng(2024);
  for (Eigen::Index i = 0; i < 5; ++i) {
    for (int k = 0; k < 2; ++k) {
      const double u = std::ldexp(static_cast<double>(rng() >> 11), -53);
      EXPECT_EQ(c.points()(i, k), lo[k] + (hi[k] - lo[k]) * u);
    }
  }
  EXPECT_DOUBLE_EQ(c.volumes()[0], 16.0 / 5);
}

// ----------------------------------------------------------------------------
// sample_sphere_shell

TEST(SphereShell, Sphere3D) {
  const Eigen::VectorXd center = vec({1.0, -2.0, 0.5});
  const double r = 2.5;
  const Eigen::Index n = 40000;
  const PointCloud c = softhd::sample_sphere_shell(center, r, n, 7);
  ASSERT_EQ(c.dim(), 3);
  ASSERT_EQ(c.size(), n);
  EXPECT_NEAR(c.total_volume(), 4 * kPi * r * r, summation_bound(n) * 4 * kPi * r * r);
  EXPECT_TRUE((c.volumes().array() == c.volumes()[0]).all());
  Eigen::Index cap = 0, octant = 0;
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Vector3d d = c.points().row(i).transpose() - center;
    ASSERT_NEAR(d.norm(), r, 1e-14 * 8 * r);
    cap += d.z() > 0.5 * r;                         // cap area fraction 1/4
    octant += d.x() > 0 && d.y() > 0 && d.z() > 0;  // 1/8
  }
  const double sigma = std::sqrt(0.25 * 0.75 / n);
  EXPECT_NEAR(double(cap) / n, 0.25, 5 * sigma);
  EXPECT_NEAR(double(octant) / n, 0.125, 5 * std::sqrt(0.125 * 0.875 / n));
  // The centroid of uniform points on a sphere is the centre.
  const Eigen::Vector3d mean(column_mean(c, 0), column_mean(c, 1), column_mean(c, 2));
  EXPECT_LT((mean - center).norm(), 5 * r / std::sqrt(double(n)));

  EXPECT_TRUE(bit_equal(softhd::sample_sphere_shell(center, r, n, 7), c));
  EXPECT_FALSE(bit_equal(softhd::sample_sphere_shell(center, r, n, 8), c));
}

TEST(SphereShell, Circle2D) {
  const Eigen::VectorXd center = vec({-3.0, 4.0});
  const double r = 0.75;
  const Eigen::Index n = 20000;
  const PointCloud c = softhd::sample_sphere_shell(center, r, n, 11);
  ASSERT_EQ(c.dim(), 2);
  EXPECT_NEAR(c.total_volume(), 2 * kPi * r, summation_bound(n) * 2 * kPi * r);
  Eigen::Index quadrant = 0;
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Vector2d d = c.points().row(i).transpose() - center;
    ASSERT_NEAR(d.norm(), r, 1e-14 * 8 * r);
    quadrant += d.x() > 0 && d.y() > 0;
  }
  EXPECT_NEAR(double(quadrant) / n, 0.25, 5 * std::sqrt(0.25 * 0.75 / n));
  EXPECT_TRUE(bit_equal(softhd::sample_sphere_shell(center, r, n, 11), c));
}

// ----------------------------------------------------------------------------
// Argument checks

TEST(Samplers, RejectBadArguments) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const Eigen::VectorXd lo2 = vec({0, 0}), hi2 = vec({1, 1});
  const Eigen::VectorXi n2 = ivec({2, 2});
  using softhd::sample_box_grid;
  using softhd::sample_q2_nodes;
  using softhd::sample_sphere_shell;
  using softhd::sample_uniform_random;

  expect_error<InvalidArgument>([&] { sample_box_grid(vec({0}), vec({1}), ivec({1})); },
                                "sample_box_grid: lo must have size 2 or 3, got 1");
  expect_error<InvalidArgument>(
      [&] {
        sample_box_grid(vec({0, 0, 0, 0}), vec({1, 1, 1, 1}), ivec({1, 1, 1, 1}));
      },
      "lo must have size 2 or 3, got 4");
  expect_error<InvalidArgument>(
      [&] {
        sample_box_grid(lo2, vec({1, 1, 1}), n2);
      },
      "hi has size 3 but lo has size 2");
  expect_error<InvalidArgument>(
      [&] {
        sample_box_grid(lo2, vec({1, 0}), n2);
      },
      "need lo < hi, but lo[1] = 0.000000 >= hi[1] = 0.000000");
  expect_error<InvalidArgument>(
      [&] {
        sample_box_grid(vec({2, 0}), hi2, n2);
      },
      "lo[0] = 2.000000 >= hi[0]");
  expect_error<InvalidArgument>(
      [&] {
        sample_box_grid(vec({nan, 0}), hi2, n2);
      },
      "lo[0] is not finite");
  expect_error<InvalidArgument>(
      [&] {
        sample_box_grid(lo2, vec({1, INFINITY}), n2);
      },
      "hi[1] is not finite");
  expect_error<InvalidArgument>(
      [&] {
        sample_box_grid(vec({-1e300, 0}), vec({1e300, 1e300}), n2);
      },
      "the box volume overflows");
  expect_error<InvalidArgument>([&] { sample_box_grid(lo2, hi2, ivec({2})); },
                                "counts has size 1 but lo has size 2");
  expect_error<InvalidArgument>(
      [&] {
        sample_box_grid(lo2, hi2, ivec({2, 0}));
      },
      "counts[1] must be >= 1, got 0");
  expect_error<InvalidArgument>(
      [&] {
        sample_box_grid(lo2, hi2, ivec({-3, 1}));
      },
      "counts[0] must be >= 1, got -3");
  expect_error<InvalidArgument>(
      [&] {
        sample_box_grid(vec({0, 0, 0}), vec({1, 1, 1}), ivec({1 << 20, 1 << 20, 4}));
      },
      "counts: too many points");
  expect_error<InvalidArgument>(
      [&] {
        sample_box_grid(lo2, vec({1e-200, 1e-200}), n2);
      },
      "underflows or overflows");

  expect_error<InvalidArgument>(
      [&] {
        sample_q2_nodes(lo2, hi2, ivec({1, 0}));
      },
      "sample_q2_nodes: elements[1] must be >= 1, got 0");
  expect_error<InvalidArgument>(
      [&] {
        sample_q2_nodes(lo2, hi2, ivec({1, 1, 1}));
      },
      "elements has size 3 but lo has size 2");
  expect_error<InvalidArgument>(
      [&] {
        sample_q2_nodes(vec({1, 0}), hi2, n2);
      },
      "sample_q2_nodes: need lo < hi");

  expect_error<InvalidArgument>([&] { sample_uniform_random(lo2, hi2, 0, 1); },
                                "sample_uniform_random: n must be >= 1, got 0");
  expect_error<InvalidArgument>([&] { sample_uniform_random(lo2, hi2, -5, 1); },
                                "n must be >= 1, got -5");
  expect_error<InvalidArgument>(
      [&] {
        sample_uniform_random(lo2, vec({1, 1, 1}), 3, 1);
      },
      "hi has size 3 but lo has size 2");

  expect_error<InvalidArgument>([&] { sample_sphere_shell(vec({0}), 1.0, 3, 1); },
                                "sample_sphere_shell: center must have size 2 or 3, got 1");
  expect_error<InvalidArgument>(
      [&] {
        sample_sphere_shell(vec({0, nan}), 1.0, 3, 1);
      },
      "center is not finite");
  expect_error<InvalidArgument>([&] { sample_sphere_shell(lo2, 0.0, 3, 1); },
                                "radius must be finite and > 0");
  expect_error<InvalidArgument>([&] { sample_sphere_shell(lo2, -1.0, 3, 1); },
                                "radius must be finite and > 0");
  expect_error<InvalidArgument>([&] { sample_sphere_shell(lo2, nan, 3, 1); },
                                "radius must be finite and > 0");
  expect_error<InvalidArgument>(
      [&] {
        sample_sphere_shell(vec({0, 0, 0}), 1e200, 3, 1);
      },
      "the surface measure overflows");
  expect_error<InvalidArgument>([&] { sample_sphere_shell(lo2, 1.0, 0, 1); },
                                "n must be >= 1, got 0");
}
