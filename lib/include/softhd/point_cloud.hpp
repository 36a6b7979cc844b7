#pragma once
/// \file point_cloud.hpp
/// A weighted point cloud (docs/formulation.md §1.1): N points in R^d (d = 2 or 3) with volumes
/// V_i > 0 (areas in 2D).

#include <Eigen/Core>

namespace softhd {

/// N points x_i in R^d with positive volumes V_i.
///
/// Positions are stored N by d, column-major: each coordinate is one contiguous
/// array (structure of arrays), which is what the pair loops stream through.
/// The invariants (d in {2, 3}, N >= 1, finite coordinates, finite positive
/// volumes) are checked on construction and throw softhd::InvalidArgument.
class PointCloud {
 public:
  /// `points`: N by d; `volumes`: N. Throws InvalidArgument naming the first
  /// offending point when an invariant fails.
  PointCloud(Eigen::MatrixXd points, Eigen::VectorXd volumes);
  /// All volumes equal to 1.
  explicit PointCloud(Eigen::MatrixXd points);

  /// The dimension d (2 or 3).
  int dim() const { return static_cast<int>(points_.cols()); }
  /// The number of points N.
  Eigen::Index size() const { return points_.rows(); }
  /// N by d positions.
  const Eigen::MatrixXd& points() const { return points_; }
  /// N volumes.
  const Eigen::VectorXd& volumes() const { return volumes_; }
  /// |X| = sum of the volumes.
  double total_volume() const { return total_volume_; }

 private:
  Eigen::MatrixXd points_;
  Eigen::VectorXd volumes_;
  double total_volume_ = 0.0;
};

}  // namespace softhd
