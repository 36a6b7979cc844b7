#pragma once
/// \file pose.hpp
/// The pose of a scan: the rigid motion (or similarity) y ↦ s R y + t that takes the scan's
/// points from the camera's frame into the body's (docs/formulation.md §8). Shared by `align`,
/// the visibility of the body from the camera and the joint pose-and-control optimisation.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>

#include "softhd/point_cloud.hpp"

namespace softhd::scan {

/// y' = s R y + t (3D). The identity by default.
struct Pose {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();  ///< rotation (orthonormal, det +1)
  Eigen::Vector3d t = Eigen::Vector3d::Zero();      ///< translation
  double s = 1.0;                                   ///< scale (1 for a rigid motion)

  /// The relative tolerance of a rigid motion's scale, |s − 1| ≤ this (from_matrix's of the
  /// rotation block).
  static constexpr double kScaleTolerance = 1e-9;
  /// A rigid motion: s = 1 to kScaleTolerance.
  bool rigid() const { return std::abs(s - 1.0) <= kScaleTolerance; }

  /// The 4×4 homogeneous matrix [[s R, t], [0, 1]].
  Eigen::Matrix4d matrix() const;
  /// The pose of a 4×4 matrix [[s R, t], [0 0 0 1]]; throws InvalidArgument if the last row is not
  /// (0, 0, 0, 1), an entry is not finite, or the 3×3 block is not a positive multiple of a
  /// rotation to 1e-9 (relative).
  static Pose from_matrix(const Eigen::Matrix4d& m);
  /// The twist (ω, v, σ) with R = exp([ω]×), s = e^σ, t = v: 7 numbers, |ω| ≤ π.
  Eigen::Matrix<double, 7, 1> twist() const;
  /// The pose of a twist (ω, v, σ), the inverse of twist().
  static Pose from_twist(const Eigen::Matrix<double, 7, 1>& twist);
  /// The camera's position in the body's frame: the image of the scan frame's origin, t.
  Eigen::Vector3d camera_position() const { return t; }
  /// The inverse motion (body frame → camera frame).
  Pose inverse() const;
  /// The moved cloud: points s R y + t, volumes times s² for a surface cloud (`surface`) or s³.
  PointCloud apply(const PointCloud& scan, bool surface) const;
};

/// Rotation angle of Ra Rbᵀ in radians (the error measure of the tests and benchmarks).
double rotation_angle_between(const Eigen::Matrix3d& Ra, const Eigen::Matrix3d& Rb);

/// The pose a ∘ b: y ↦ a(b(y)).
Pose compose(const Pose& a, const Pose& b);
/// The rows of `points` (N by 3) moved: s R y + t.
Eigen::MatrixXd apply_points(const Pose& pose, const Eigen::MatrixXd& points);

/// [ω]×, the skew matrix with [ω]× v = ω × v.
Eigen::Matrix3d hat(const Eigen::Vector3d& w);
/// (K₃₂ − K₂₃, K₁₃ − K₃₁, K₂₁ − K₁₂): 2ω for K = [ω]×.
Eigen::Vector3d vee(const Eigen::Matrix3d& K);
/// exp([ω]×) by Rodrigues' formula (its Taylor series below |ω| = 1e-4).
Eigen::Matrix3d rotation_exp(const Eigen::Vector3d& w);
/// The left Jacobian of exp on rotations, exp([ω + δ]×) = exp([J_l δ]×) exp([ω]×) + O(δ²):
/// J_l = I + (1 − cos θ)/θ² [ω]× + (θ − sin θ)/θ³ [ω]×² (θ = |ω|; series below 1e-4).
Eigen::Matrix3d rotation_left_jacobian(const Eigen::Vector3d& w);
/// The ω with |ω| ≤ π and exp([ω]×) = R (R a rotation), accurate near 0 and near π.
Eigen::Vector3d rotation_log(const Eigen::Matrix3d& R);

}  // namespace softhd::scan
