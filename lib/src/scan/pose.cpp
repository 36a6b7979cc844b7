// The pose of a scan: y' = s R y + t, its 4×4 matrix and its twist (docs/formulation.md §8.4).

#include "softhd/scan/pose.hpp"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <sstream>

#include "softhd/error.hpp"

namespace softhd::scan {

namespace {

/// The rotation nearest to M (Frobenius): U Vᵀ of M = U Σ Vᵀ, with det +1.
Eigen::Matrix3d nearest_rotation(const Eigen::Matrix3d& M) {
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(M, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
  D(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1.0 : 1.0;
  return svd.matrixU() * D * svd.matrixV().transpose();
}

std::string entry_name(int r, int c) {
  return "pose matrix entry (" + std::to_string(r + 1) + ", " + std::to_string(c + 1) + ")";
}

}  // namespace

Eigen::Matrix3d hat(const Eigen::Vector3d& w) {
  Eigen::Matrix3d K;
  K << 0, -w.z(), w.y(), w.z(), 0, -w.x(), -w.y(), w.x(), 0;
  return K;
}

Eigen::Vector3d vee(const Eigen::Matrix3d& K) {
  return {K(2, 1) - K(1, 2), K(0, 2) - K(2, 0), K(1, 0) - K(0, 1)};  // 2·vee of the skew part
}

namespace {

/// The coefficients of exp and its left Jacobian at θ = |ω|: a = sin θ/θ, b = (1 − cos θ)/θ²,
/// c = (θ − sin θ)/θ³; below θ = 1e-4 their Taylor series (error < θ⁶/5040).
struct RodriguesCoefficients {
  double a, b, c;
};

RodriguesCoefficients rodrigues_coefficients(double t2) {
  const double t = std::sqrt(t2);
  if (t < 1e-4)
    return {1.0 - t2 / 6.0 + t2 * t2 / 120.0, 0.5 - t2 / 24.0 + t2 * t2 / 720.0,
            1.0 / 6.0 - t2 / 120.0 + t2 * t2 / 5040.0};
  return {std::sin(t) / t, (1.0 - std::cos(t)) / t2, (t - std::sin(t)) / (t2 * t)};
}

}  // namespace

Eigen::Matrix3d rotation_exp(const Eigen::Vector3d& w) {
  // Rodrigues: exp([ω]×) = I + a [ω]× + b [ω]×².
  const RodriguesCoefficients k = rodrigues_coefficients(w.squaredNorm());
  const Eigen::Matrix3d K = hat(w);
  return Eigen::Matrix3d::Identity() + k.a * K + k.b * K * K;
}

Eigen::Matrix3d rotation_left_jacobian(const Eigen::Vector3d& w) {
  // J_l = I + b [ω]× + c [ω]×².
  const RodriguesCoefficients k = rodrigues_coefficients(w.squaredNorm());
  const Eigen::Matrix3d K = hat(w);
  return Eigen::Matrix3d::Identity() + k.b * K + k.c * K * K;
}

Eigen::Vector3d rotation_log(const Eigen::Matrix3d& R) {
  // θ = atan2(|vee(R − Rᵀ)|/2, (tr R − 1)/2). For θ < π/2, ω = (θ/sin θ)·vee(R − Rᵀ)/2 (series
  // 1 + θ²/6 + 7θ⁴/360 below 1e-4); else the axis n from R + Rᵀ = 2 cos θ I + 2(1 − cos θ) n nᵀ
  // (its largest column), its sign from vee(R − Rᵀ) = 2 sin θ n.
  const Eigen::Vector3d v = 0.5 * vee(R);
  const double sin_t = v.norm();
  const double cos_t = std::clamp(0.5 * (R.trace() - 1.0), -1.0, 1.0);
  const double t = std::atan2(sin_t, cos_t);
  if (t < 1e-4) return (1.0 + t * t / 6.0 + 7.0 * t * t * t * t / 360.0) * v;
  if (t < 0.5 * M_PI) return (t / sin_t) * v;
  const Eigen::Matrix3d S =
      (0.5 * (R + R.transpose()) - cos_t * Eigen::Matrix3d::Identity()) / (1.0 - cos_t);
  int k = 0;
  S.diagonal().maxCoeff(&k);
  Eigen::Vector3d n = S.col(k) / std::sqrt(S(k, k));
  if (n.dot(v) < 0.0) n = -n;
  return t * n.normalized();
}

double rotation_angle_between(const Eigen::Matrix3d& Ra, const Eigen::Matrix3d& Rb) {
  return rotation_log(Ra * Rb.transpose()).norm();
}

Eigen::Matrix4d Pose::matrix() const {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.topLeftCorner<3, 3>() = s * R;
  m.topRightCorner<3, 1>() = t;
  return m;
}

Pose Pose::from_matrix(const Eigen::Matrix4d& m) {
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c)
      if (!std::isfinite(m(r, c))) throw InvalidArgument(entry_name(r, c) + " is not finite");
  for (int c = 0; c < 4; ++c) {
    const double want = c == 3 ? 1.0 : 0.0;
    if (std::abs(m(3, c) - want) > 1e-12) {
      std::ostringstream os;
      os.precision(17);
      os << entry_name(3, c) << " is " << m(3, c) << ", expected " << want
         << " (the last row must be 0 0 0 1)";
      throw InvalidArgument(os.str());
    }
  }
  const Eigen::Matrix3d M = m.topLeftCorner<3, 3>();
  const double det = M.determinant();
  if (!(det > 0.0)) {
    throw InvalidArgument("pose matrix: the 3x3 block has determinant " + std::to_string(det) +
                          " (a rotation times a positive scale has det > 0)");
  }
  const double s = std::cbrt(det);
  const double off =
      ((M / s).transpose() * (M / s) - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (off > 1e-9) {
    std::ostringstream os;
    os << "pose matrix: the 3x3 block is not a scaled rotation (|QᵀQ − I| = " << off
       << " > 1e-9 with Q = block/det^(1/3))";
    throw InvalidArgument(os.str());
  }
  Pose p;
  p.s = s;
  p.R = nearest_rotation(M / s);
  p.t = m.topRightCorner<3, 1>();
  return p;
}

Eigen::Matrix<double, 7, 1> Pose::twist() const {
  Eigen::Matrix<double, 7, 1> x;
  const Eigen::Vector3d w = rotation_log(R);
  for (int k = 0; k < 3; ++k) {
    x[k] = w[k];
    x[3 + k] = t[k];
  }
  x[6] = std::log(s);
  return x;
}

Pose Pose::from_twist(const Eigen::Matrix<double, 7, 1>& twist) {
  for (int k = 0; k < 7; ++k)
    if (!std::isfinite(twist[k]))
      throw InvalidArgument("twist entry " + std::to_string(k + 1) + " is not finite");
  Pose p;
  p.R = rotation_exp(twist.head<3>());
  p.t = twist.segment<3>(3);
  p.s = std::exp(twist[6]);
  return p;
}

Pose Pose::inverse() const {
  // y = R⁻¹ (y' − t) / s = (1/s) Rᵀ y' − (1/s) Rᵀ t
  Pose p;
  p.R = R.transpose();
  p.s = 1.0 / s;
  p.t = -(p.s * (p.R * t));
  return p;
}

Pose compose(const Pose& a, const Pose& b) {
  // a(b(y)) = s_a R_a (s_b R_b y + t_b) + t_a
  Pose p;
  p.R = a.R * b.R;
  p.s = a.s * b.s;
  p.t = a.s * (a.R * b.t) + a.t;
  return p;
}

Eigen::MatrixXd apply_points(const Pose& pose, const Eigen::MatrixXd& points) {
  // rows y ↦ s R y + t
  Eigen::MatrixXd out = (points * (pose.s * pose.R).transpose()).rowwise() + pose.t.transpose();
  return out;
}

PointCloud Pose::apply(const PointCloud& scan, bool surface) const {
  if (scan.dim() != 3) {
    throw InvalidArgument("pose: the cloud is " + std::to_string(scan.dim()) +
                          "D, a pose moves 3D clouds");
  }
  const double factor = surface ? s * s : s * s * s;
  return PointCloud(apply_points(*this, scan.points()), scan.volumes() * factor);
}

}  // namespace softhd::scan
