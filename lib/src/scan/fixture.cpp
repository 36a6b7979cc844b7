// The fixture's constraint on a scan's pose (docs/formulation.md §8.12).

#include "softhd/scan/fixture.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "softhd/error.hpp"

namespace softhd::scan {

namespace {

/// Two unit vectors e1, e2 with (e1, e2, n) right-handed and orthonormal.
void plane_basis(const Eigen::Vector3d& n, Eigen::Vector3d* e1, Eigen::Vector3d* e2) {
  Eigen::Index k = 0;
  n.cwiseAbs().minCoeff(&k);  // the axis least aligned with n
  *e1 = n.cross(Eigen::Vector3d::Unit(k)).normalized();
  *e2 = n.cross(*e1);
}

}  // namespace

void Fixture::validate() const {
  if (!normal.allFinite()) throw InvalidArgument("fixture.normal is not finite");
  if (!(normal.norm() > 0.0)) throw InvalidArgument("fixture.normal has zero length");
  if (!std::isfinite(offset)) throw InvalidArgument("fixture.offset is not finite");
  if (!clamp.allFinite()) throw InvalidArgument("fixture.clamp is not finite");
  if (!clamp_seen.allFinite()) throw InvalidArgument("fixture.clamp_seen is not finite");
  if ((clamp.squaredNorm() > 0.0) != (clamp_seen.squaredNorm() > 0.0))
    throw InvalidArgument(
        "fixture.clamp and fixture.clamp_seen go together (the clamp's direction in the body's "
        "frame and where it is seen in the scan's)");
  const Eigen::Vector3d n = normal.normalized();
  if (has_clamp() && (clamp - n.dot(clamp) * n).norm() <= 1e-6 * clamp.norm())
    throw InvalidArgument("fixture.clamp is along the table's normal: it tells no side");
}

Eigen::Matrix3d rotation_between(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  // exp([θ k]×) with k = a × b/|a × b|, θ = atan2(|a × b|, a·b); for a × b ≈ 0 and a·b < 0,
  // a half turn about any axis perpendicular to a.
  const Eigen::Vector3d v = a.cross(b);
  const double sine = v.norm(), cosine = a.dot(b);
  if (sine > 1e-12 || cosine > 0.0)
    return rotation_exp(sine > 0.0 ? Eigen::Vector3d(v * (std::atan2(sine, cosine) / sine))
                                   : Eigen::Vector3d::Zero());
  Eigen::Vector3d e1, e2;
  plane_basis(a, &e1, &e2);
  return rotation_exp(M_PI * e1);
}

FixtureConstraint::FixtureConstraint(const Fixture& fixture, const Plane& table,
                                     const Eigen::MatrixXd& scan) {
  fixture.validate();
  if (table.normal.size() != 3)
    throw InvalidArgument("table: the scan's table plane must be 3D, got " +
                          std::to_string(table.normal.size()) + " normal components");
  if (!table.normal.allFinite() || !std::isfinite(table.offset))
    throw InvalidArgument("table: the scan's table plane is not finite");
  const double tn = table.normal.norm();
  if (!(tn > 0.0)) throw InvalidArgument("table: the scan's table normal has zero length");
  const double bn = fixture.normal.norm();
  nb_ = fixture.normal / bn;
  db_ = fixture.offset / bn;
  ns_ = Eigen::Vector3d(table.normal) / tn;
  ds_ = table.offset / tn;
  clamp_ = fixture.clamp;
  seen_ = fixture.clamp_seen;
  // The body is on the table's upper side: the median height of the scan's points is > 0.
  if (scan.rows() > 0) {
    std::vector<double> h(static_cast<size_t>(scan.rows()));
    for (Eigen::Index j = 0; j < scan.rows(); ++j)
      h[static_cast<size_t>(j)] = scan.row(j).dot(ns_) - ds_;
    std::nth_element(h.begin(), h.begin() + static_cast<long>(h.size() / 2), h.end());
    if (h[h.size() / 2] < 0.0) {
      ns_ = -ns_;
      ds_ = -ds_;
    }
  }
}

bool FixtureConstraint::allows(const Pose& Q) const {
  if (!(clamp_.squaredNorm() > 0.0)) return true;
  // a = (I − n_s n_sᵀ) R_Q clamp, b = (I − n_s n_sᵀ) clamp_seen: allowed if a·b ≥ 0.
  const Eigen::Vector3d a = Q.R * clamp_, b = seen_;
  return a.dot(b) - a.dot(ns_) * b.dot(ns_) >= 0.0;
}

Pose FixtureConstraint::project(const Pose& Q, const Eigen::Vector3d& centre) const {
  Pose out = Q;
  const Eigen::Matrix3d E = rotation_between(Q.R * nb_, ns_);
  out.R = E * Q.R;
  out.t = centre + E * (Q.t - centre);
  out.t += (ds_ - db_ - ns_.dot(out.t)) * ns_;  // n_s·t_Q = d_s − d_b
  return out;
}

Pose FixtureConstraint::start(double angle, const Eigen::Vector3d& body_centre,
                              const Eigen::Vector3d& scan_centre) const {
  Pose Q;
  Q.R = rotation_exp(angle * ns_) * rotation_between(nb_, ns_);
  Q.t = scan_centre - Q.R * body_centre;
  Q.t += (ds_ - db_ - ns_.dot(Q.t)) * ns_;
  return Q;
}

Eigen::MatrixXd table_tangent(const Eigen::Vector3d& n) {
  Eigen::Vector3d e1, e2;
  plane_basis(n, &e1, &e2);
  Eigen::MatrixXd B = Eigen::MatrixXd::Zero(6, 3);
  B.block<3, 1>(0, 0) = n;   // ω along n
  B.block<3, 1>(3, 1) = e1;  // v along the table
  B.block<3, 1>(3, 2) = e2;
  return B;
}

Eigen::MatrixXd FixtureConstraint::tangent() const { return table_tangent(ns_); }

Pose FixtureConstraint::fit(const Eigen::MatrixXd& from, const Eigen::MatrixXd& to) const {
  // y' = A₀ y (A₀ n_s = n_b); in the table's basis (e1, e2) of the body frame, p = (e·y'),
  // q = (e·x) about their means: θ = atan2(Σ p̃ × q̃, Σ p̃·q̃) maximises Σ q̃·Rot(θ) p̃;
  // R = Rot(n_b, θ) A₀, t = (I − n_b n_bᵀ)(x̄ − R ȳ) + (d_b − d_s) n_b.
  const Eigen::Matrix3d A0 = rotation_between(ns_, nb_);
  Eigen::Vector3d e1, e2;
  plane_basis(nb_, &e1, &e2);
  const Eigen::RowVector3d ym = from.colwise().mean(), xm = to.colwise().mean();
  double dot = 0.0, cross = 0.0;
  for (Eigen::Index k = 0; k < from.rows(); ++k) {
    const Eigen::Vector3d y = A0 * (from.row(k) - ym).transpose();
    const Eigen::Vector3d x = (to.row(k) - xm).transpose();
    const double px = e1.dot(y), py = e2.dot(y), qx = e1.dot(x), qy = e2.dot(x);
    dot += px * qx + py * qy;
    cross += px * qy - py * qx;
  }
  Pose P;
  P.R = rotation_exp(std::atan2(cross, dot) * nb_) * A0;
  const Eigen::Vector3d d = xm.transpose() - P.R * ym.transpose();
  P.t = d - nb_.dot(d) * nb_ + (db_ - ds_) * nb_;
  return P;
}

}  // namespace softhd::scan
