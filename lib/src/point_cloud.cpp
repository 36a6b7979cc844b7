#include "softhd/point_cloud.hpp"

#include <cmath>
#include <string>

#include "softhd/error.hpp"

namespace softhd {

PointCloud::PointCloud(Eigen::MatrixXd points, Eigen::VectorXd volumes)
    : points_(std::move(points)), volumes_(std::move(volumes)) {
  if (points_.cols() != 2 && points_.cols() != 3) {
    throw InvalidArgument("point cloud: dimension must be 2 or 3, got " +
                          std::to_string(points_.cols()));
  }
  if (points_.rows() < 1) throw InvalidArgument("point cloud: it has no points (N must be >= 1)");
  if (volumes_.size() != points_.rows()) {
    throw InvalidArgument("point cloud: " + std::to_string(points_.rows()) + " points but " +
                          std::to_string(volumes_.size()) + " volumes");
  }
  for (Eigen::Index i = 0; i < points_.rows(); ++i) {
    for (Eigen::Index k = 0; k < points_.cols(); ++k) {
      if (!std::isfinite(points_(i, k))) {
        throw InvalidArgument("point cloud: point " + std::to_string(i) +
                              " has a non-finite coordinate");
      }
    }
    if (!std::isfinite(volumes_[i]) || !(volumes_[i] > 0.0)) {
      throw InvalidArgument("point cloud: point " + std::to_string(i) + " has volume " +
                            std::to_string(volumes_[i]) + " (volumes must be finite and > 0)");
    }
  }
  total_volume_ = volumes_.sum();
  if (!std::isfinite(total_volume_)) {
    throw InvalidArgument("point cloud: the total volume overflows");
  }
}

PointCloud::PointCloud(Eigen::MatrixXd points)
    : PointCloud(points, Eigen::VectorXd::Ones(points.rows())) {}

}  // namespace softhd
