#include <gtest/gtest.h>

#include <limits>

#include "expect_error.hpp"
#include "softhd/error.hpp"
#include "softhd/point_cloud.hpp"

using softhd::InvalidArgument;
using softhd::PointCloud;
using softhd::test::expect_error;

TEST(PointCloud, StoresPointsVolumesAndTotal) {
  Eigen::MatrixXd p(3, 2);
  p << 0, 0, 1, 0, 0, 1;
  Eigen::VectorXd v(3);
  v << 0.5, 0.25, 0.25;
  PointCloud c(p, v);
  EXPECT_EQ(c.dim(), 2);
  EXPECT_EQ(c.size(), 3);
  EXPECT_DOUBLE_EQ(c.total_volume(), 1.0);
  PointCloud unit(Eigen::MatrixXd::Zero(4, 3));
  EXPECT_DOUBLE_EQ(unit.total_volume(), 4.0);
}

TEST(PointCloud, RejectsBadInput) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  expect_error<InvalidArgument>([] { PointCloud(Eigen::MatrixXd::Zero(3, 4)); },
                                "dimension must be 2 or 3");
  expect_error<InvalidArgument>([] { PointCloud(Eigen::MatrixXd::Zero(0, 3)); }, "no points");
  expect_error<InvalidArgument>(
      [] { PointCloud(Eigen::MatrixXd::Zero(2, 3), Eigen::VectorXd::Ones(3)); },
      "2 points but 3 volumes");
  expect_error<InvalidArgument>(
      [&] {
        Eigen::MatrixXd p = Eigen::MatrixXd::Zero(3, 3);
        p(1, 2) = nan;
        PointCloud c(p);
      },
      "point 1 has a non-finite coordinate");
  expect_error<InvalidArgument>(
      [] {
        Eigen::VectorXd v = Eigen::VectorXd::Ones(3);
        v[2] = 0.0;
        PointCloud c(Eigen::MatrixXd::Zero(3, 3), v);
      },
      "point 2 has volume 0");
  expect_error<InvalidArgument>(
      [] {
        Eigen::VectorXd v = Eigen::VectorXd::Ones(3);
        v[0] = -1.0;
        PointCloud c(Eigen::MatrixXd::Zero(3, 3), v);
      },
      "point 0 has volume -1");
}
