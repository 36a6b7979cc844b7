#pragma once
/// \file cleanup.hpp
/// The clean-up a user expects before a scan is tracked (docs/formulation.md §8): crop to an
/// inflated box, statistical outlier removal, removal of a dominant plane (the table). Each
/// returns the kept points' indices, so weights and colours can follow.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "softhd/point_cloud.hpp"

namespace softhd::scan {

/// Indices of the points inside the box [lower − m, upper + m], m = margin · the box's diagonal.
std::vector<Eigen::Index> crop_to_box(const PointCloud& cloud, const Eigen::VectorXd& lower,
                                      const Eigen::VectorXd& upper, double margin);

/// Statistical outlier removal (as PCL's and Open3D's): keeps the points whose mean distance
/// to their k nearest neighbours is at most mean + ratio · std of that quantity over the cloud.
std::vector<Eigen::Index> remove_statistical_outliers(const PointCloud& cloud, int k, double ratio);

/// The dominant plane n·x = d found by RANSAC (a fixed seed: deterministic) with
/// inlier threshold `distance`; returns the indices of the points off it (|n·x − d| > distance).
/// If the plane holds fewer than `min_fraction` of the points nothing is removed.
struct PlaneRemoval {
  double distance = 0.0;      ///< inlier threshold (a length); > 0
  int iterations = 1000;      ///< RANSAC samples
  double min_fraction = 0.1;  ///< smallest plane worth removing
  std::uint64_t seed = 1;
};
std::vector<Eigen::Index> remove_dominant_plane(const PointCloud& cloud,
                                                const PlaneRemoval& options);

/// The sub-cloud of the given indices (points and volumes).
PointCloud select(const PointCloud& cloud, const std::vector<Eigen::Index>& indices);

}  // namespace softhd::scan
