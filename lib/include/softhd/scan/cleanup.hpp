#pragma once
/// \file cleanup.hpp
/// The clean-up a user expects before a scan is tracked (docs/formulation.md §8.8): crop to an
/// inflated box, statistical outlier removal, removal of a dominant plane (the table). Each
/// returns the kept points' indices in increasing order, so weights and colours can follow.
/// Clouds of 2 or 3 dimensions (in 2D the "plane" is a line).

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "softhd/point_cloud.hpp"

namespace softhd::scan {

/// Indices of the points inside the box [lower − m, upper + m], m = margin · |upper − lower|
/// (the box's diagonal). Throws InvalidArgument if lower/upper do not have the cloud's
/// dimension, are not finite, lower > upper somewhere, or margin is negative or not finite.
std::vector<Eigen::Index> crop_to_box(const PointCloud& cloud, const Eigen::VectorXd& lower,
                                      const Eigen::VectorXd& upper, double margin);

/// Statistical outlier removal (as PCL's and Open3D's): with m_i the mean distance of point i
/// to its k nearest other points, μ and s the mean and the sample standard deviation (N − 1)
/// of m over the cloud, keeps the points with m_i ≤ μ + ratio · s. Requires 1 ≤ k < N and a
/// finite ratio (InvalidArgument naming `k` or `ratio`).
std::vector<Eigen::Index> remove_statistical_outliers(const PointCloud& cloud, int k, double ratio);

/// RANSAC for the dominant plane n·x = offset (|n| = 1): `iterations` samples of d points
/// drawn from std::mt19937_64(seed) (deterministic, whatever the thread count), the sample
/// with the most points within `distance` wins, then the plane is refit by least squares
/// (the normal of smallest variance of its inliers about their centroid) twice, recounting
/// the inliers each time. If that plane holds fewer than `min_fraction` of the points nothing
/// is removed.
struct PlaneRemoval {
  double distance = 0.0;      ///< inlier threshold (a length); > 0 and finite
  int iterations = 1000;      ///< RANSAC samples, ≥ 1
  double min_fraction = 0.1;  ///< smallest plane worth removing, in [0, 1]
  std::uint64_t seed = 1;     ///< of the sampler
  /// Throws InvalidArgument naming the offending field.
  void validate() const;
};

/// The plane found (see PlaneRemoval): unit normal (sign: its largest component positive),
/// offset, and the number of points within `distance` of it.
struct Plane {
  Eigen::VectorXd normal;    ///< unit normal n
  double offset = 0.0;       ///< d of n·x = d
  Eigen::Index inliers = 0;  ///< points within PlaneRemoval::distance of it
};
/// The dominant plane of `cloud` by RANSAC and a least-squares refit on its inliers.
Plane find_dominant_plane(const PointCloud& cloud, const PlaneRemoval& options);

/// The indices of the points off the dominant plane (|n·x − offset| > distance), or of all
/// points if the plane holds fewer than min_fraction of them.
std::vector<Eigen::Index> remove_dominant_plane(const PointCloud& cloud,
                                                const PlaneRemoval& options);

/// The clean-up of a scan in the order a scene's target block applies it: crop to the body's
/// box inflated by `crop` (a fraction of its diagonal), then the dominant plane within `plane`
/// (a length), then statistical outliers; each step optional.
struct ScanCleanup {
  std::optional<double> crop;   ///< margin (≥ 0) for crop_to_box; none: no crop
  std::optional<double> plane;  ///< PlaneRemoval::distance (> 0); none: no plane removal
  /// Statistical outlier removal's settings (remove_statistical_outliers).
  struct Outliers {
    int k = 20;          ///< neighbours (≥ 1)
    double ratio = 2.0;  ///< of the standard deviation (finite)
  };
  std::optional<Outliers> outliers;  ///< none: no statistical outlier removal
  /// Throws InvalidArgument naming the offending field (crop, plane, outliers.k, .ratio).
  void validate() const;
};

/// What one step removed.
struct CleanupStep {
  std::string name;          ///< "crop", "plane" or "outliers"
  Eigen::Index removed = 0;  ///< points it removed
};

/// The scan after `cleanup`, the box [lower, upper] being the body's. Appends one entry per
/// step made to `steps` if given. Throws InvalidArgument "no points left after the clean-up
/// (<step> removed the last N)" if a step leaves none, and whatever the steps throw (e.g.
/// outliers.k not below the points left).
PointCloud clean_scan(const PointCloud& scan, const Eigen::VectorXd& lower,
                      const Eigen::VectorXd& upper, const ScanCleanup& cleanup,
                      std::vector<CleanupStep>* steps = nullptr);

/// "crop removed 12, plane removed 3400, outliers removed 51 of 9000 points".
std::string describe(const std::vector<CleanupStep>& steps, Eigen::Index points);

/// The sub-cloud of the given indices (points and volumes). Throws InvalidArgument if
/// `indices` is empty or one is out of range.
PointCloud select(const PointCloud& cloud, const std::vector<Eigen::Index>& indices);

}  // namespace softhd::scan
