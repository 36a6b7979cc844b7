// The pose of a moving cloud as one map of a twist (docs/formulation.md §8.4, §8.5, §8.10).

#include "softhd/scan/pose_map.hpp"

#include <cmath>

#include "softhd/enum_names.hpp"
#include "softhd/error.hpp"

namespace softhd::scan {

constexpr auto kPoseKindNames = enum_sequence<PoseKind::similarity>({"rigid", "similarity"});

std::string to_string(PoseKind kind) { return enum_name(kPoseKindNames, kind); }
PoseKind pose_kind_from_string(const std::string& name) {
  return enum_from_name(kPoseKindNames, name, "align");
}

PoseMap::PoseMap(const Pose& start, const Eigen::Vector3d& centre, PoseKind kind)
    : start_(start), centre_(centre), kind_(kind) {}

Eigen::VectorXd PoseMap::sized(const Eigen::VectorXd& xi) const {
  const int n = variables();
  if (xi.size() == 0) return Eigen::VectorXd::Zero(n);
  if (xi.size() != n)
    throw InvalidArgument("pose twist has " + std::to_string(xi.size()) + " values, expected " +
                          std::to_string(n));
  return xi;
}

Eigen::VectorXd PoseMap::checked(const Eigen::VectorXd& xi) const {
  Eigen::VectorXd out = sized(xi);
  if (!out.allFinite()) throw InvalidArgument("pose twist is not finite");
  return out;
}

Pose PoseMap::at(const Eigen::VectorXd& xi_in) const {
  const Eigen::VectorXd xi = sized(xi_in);
  // T_ξ ∘ Q₀: R = E R₀, s = e^σ s₀, t = c + e^σ E (t₀ − c) + v, E = exp([ω]×).
  const Eigen::Matrix3d E = rotation_exp(xi.head<3>());
  const double es = xi.size() == 7 ? std::exp(xi[6]) : 1.0;
  Pose q;
  q.R = E * start_.R;
  q.s = es * start_.s;
  q.t = centre_ + es * (E * (start_.t - centre_)) + xi.segment<3>(3);
  return q;
}

Eigen::VectorXd PoseMap::twist_of(const Pose& Q) const {
  // The inverse of at: E = R R₀ᵀ, ω = log E, σ = log(s/s₀), v = t − c − e^σ E (t₀ − c).
  Eigen::VectorXd xi = Eigen::VectorXd::Zero(variables());
  const Eigen::Matrix3d E = Q.R * start_.R.transpose();
  xi.head<3>() = rotation_log(E);
  const double es = kind_ == PoseKind::similarity ? Q.s / start_.s : 1.0;
  if (kind_ == PoseKind::similarity) xi[6] = std::log(es);
  xi.segment<3>(3) = Q.t - centre_ - es * (E * (start_.t - centre_));
  return xi;
}

PointCloud PoseMap::apply(const PointCloud& cloud, const Eigen::VectorXd& xi) const {
  return PointCloud(apply_points(at(xi), cloud.points()), cloud.volumes());
}

Eigen::VectorXd PoseMap::twist_gradient(const Eigen::MatrixXd& moved, const Eigen::MatrixXd& g,
                                        const Eigen::VectorXd& xi_in) const {
  const Eigen::VectorXd xi = sized(xi_in);
  // ∂/∂v = Σ g_i, ∂/∂ω = J_l(ω)ᵀ Σ y_i × g_i, ∂/∂σ = Σ y_i·g_i, y_i = x'_i − c − v.
  const Eigen::Vector3d base = centre_ + xi.segment<3>(3);
  Eigen::Vector3d gv = Eigen::Vector3d::Zero(), gw = Eigen::Vector3d::Zero();
  double gs = 0.0;
  for (Eigen::Index i = 0; i < moved.rows(); ++i) {
    const Eigen::Vector3d y = moved.row(i).transpose() - base;
    const Eigen::Vector3d gi = g.row(i).transpose();
    gv += gi;
    gw += y.cross(gi);
    gs += y.dot(gi);
  }
  Eigen::VectorXd out(xi.size());
  out.head<3>() = rotation_left_jacobian(xi.head<3>()).transpose() * gw;
  out.segment<3>(3) = gv;
  if (xi.size() == 7) out[6] = gs;
  return out;
}

Eigen::MatrixXd PoseMap::pullback(const Eigen::MatrixXd& g, const Eigen::VectorXd& xi) const {
  const Pose q = at(xi);
  return q.s * (g * q.R);  // rows: s (Rᵀ g_i)ᵀ = s g_iᵀ R
}

}  // namespace softhd::scan
