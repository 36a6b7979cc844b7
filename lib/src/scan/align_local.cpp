// The objective of align() on one level and its local minimiser over a twist
// (docs/formulation.md §8.5).

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "align_internal.hpp"
#include "softhd/error.hpp"

namespace softhd::scan::detail {

PoseObjective::PoseObjective(const Eigen::MatrixXd& body, const Eigen::VectorXd& body_volumes,
                             const PointCloud& scan, const HausdorffOptions& distance,
                             DistanceForm form)
    : body_(body, body_volumes), target_(scan, distance), form_(std::move(form)) {}

double PoseObjective::value(const Pose& Q, Eigen::VectorXd* gradient,
                            Eigen::Vector3d* centre) const {
  return pose_distance(target_, body_, form_, Q, gradient, centre);
}

Pose twist_step(const Pose& Q, const Eigen::VectorXd& delta, const Eigen::Vector3d& centre) {
  return PoseMap(Q, centre, delta.size() == 7 ? PoseKind::similarity : PoseKind::rigid).at(delta);
}

namespace {

/// The twist δ of the scaled variables u = (L ω, v, L σ).
Eigen::VectorXd unscale(const Eigen::VectorXd& u, double L) {
  Eigen::VectorXd d = u;
  d.head<3>() /= L;
  if (d.size() == 7) d[6] /= L;
  return d;
}

/// ∂ρ̃/∂u from ∂ρ̃/∂δ (u = D⁻¹ δ, so ∂/∂u = D ∂/∂δ with D = diag(1/L, 1, 1/L)).
Eigen::VectorXd scale_gradient(const Eigen::VectorXd& g, double L) { return unscale(g, L); }

Pose clamp_scale(Pose Q, const LocalSettings& st) {
  if (st.similarity) Q.s = std::exp(std::clamp(std::log(Q.s), st.log_scale_min, st.log_scale_max));
  return Q;
}

/// The pose after the step u of the scaled variables from Q, σ stopped at the scale's bounds
/// (u changed to the step taken).
Pose step_pose(const Pose& Q, Eigen::VectorXd* u, const Eigen::Vector3d& c,
               const LocalSettings& st) {
  if (st.similarity) {
    const double ls = std::log(Q.s);
    (*u)[6] =
        std::clamp((*u)[6], (st.log_scale_min - ls) * st.size, (st.log_scale_max - ls) * st.size);
  }
  return clamp_scale(twist_step(Q, unscale(*u, st.size), c), st);
}

/// The scaled step u = (L ω, v, L σ) of the twist about c that takes Q to `to` (PoseMap::twist_of).
Eigen::VectorXd twist_to(const Pose& Q, const Pose& to, const Eigen::Vector3d& c,
                         const LocalSettings& st) {
  const PoseMap step(Q, c, st.similarity ? PoseKind::similarity : PoseKind::rigid);
  Eigen::VectorXd u = step.twist_of(to);
  u.head<3>() *= st.size;
  if (u.size() == 7) u[6] *= st.size;
  return u;
}

}  // namespace

LocalResult minimise_pose(const PoseObjective& objective, const Pose& start,
                          const LocalSettings& st) {
  return scan::minimise_pose([&objective](const Pose& Q, Eigen::VectorXd* g,
                                          Eigen::Vector3d* c) { return objective.value(Q, g, c); },
                             start, st);
}

}  // namespace softhd::scan::detail

namespace softhd::scan {

using detail::clamp_scale;
using detail::scale_gradient;
using detail::step_pose;
using detail::twist_to;

double pose_distance(const HausdorffTarget& scan, const PointCloud& body, const DistanceForm& form,
                     const Pose& Q, Eigen::VectorXd* gradient, Eigen::Vector3d* centre) {
  const PointCloud moved(apply_points(Q, body.points()), body.volumes());
  HausdorffRequest request;
  request.form = form;
  request.gradient_points = gradient != nullptr;
  const HausdorffResult r = scan.evaluate(moved, request);
  if (gradient == nullptr) return r.rho;
  // The twist about the centroid c of the moved points, at δ = 0 (PoseMap::twist_gradient).
  const Eigen::Vector3d c = moved.points().colwise().mean().transpose();
  const PoseMap step(Q, c, gradient->size() == 7 ? PoseKind::similarity : PoseKind::rigid);
  *gradient = step.twist_gradient(moved.points(), r.gradient_points, Eigen::VectorXd());
  *centre = c;
  return r.rho;
}

LocalPoseResult minimise_pose(const PoseFunction& objective, const Pose& start,
                              const LocalPoseSettings& st) {
  const int n = st.similarity ? 7 : 6;
  const double L = st.size;
  LocalPoseResult out;
  out.pose = clamp_scale(start, st);
  Eigen::VectorXd g(n), g_new(n);
  Eigen::Vector3d c, c_new;
  // Steps in the span of st.subspace (B, orthonormal): g ← B Bᵀ g, H = B Bᵀ at a (re)start;
  // the BFGS update of H with s and y in that span keeps H = B Bᵀ H B Bᵀ.
  const bool reduced = st.subspace.size() > 0;
  if (reduced && (st.subspace.rows() != n || st.subspace.cols() > n))
    throw InternalError("minimise_pose: subspace must have " + std::to_string(n) + " rows");
  const Eigen::MatrixXd I = reduced ? Eigen::MatrixXd(st.subspace * st.subspace.transpose())
                                    : Eigen::MatrixXd(Eigen::MatrixXd::Identity(n, n));
  const auto in_span = [&](const Eigen::VectorXd& v) -> Eigen::VectorXd {
    return reduced ? Eigen::VectorXd(I * v) : v;
  };
  double f = objective(out.pose, &g, &c);
  g = in_span(scale_gradient(g, L));
  // Inverse-Hessian estimate in u; the first step moves points by about first_step × L at most.
  const double first = st.first_step * L;
  Eigen::MatrixXd H = I * (first / std::max(g.norm(), 1e-300));
  bool fresh = true;
  for (out.iterations = 0; out.iterations < st.max_iterations; ++out.iterations) {
    Eigen::VectorXd p = -H * g;
    if (st.similarity) {  // a scale at its bound stays there while the gradient pushes out
      const double ls = std::log(out.pose.s);
      if ((ls <= st.log_scale_min && p[6] < 0) || (ls >= st.log_scale_max && p[6] > 0)) p[6] = 0;
    }
    const double longest = p.lpNorm<Eigen::Infinity>();  // no point moves further than L/2
    if (longest > 0.5 * L) p *= 0.5 * L / longest;
    double slope = g.dot(p);
    if (!(slope < 0.0)) {  // not a descent direction: restart from the gradient
      if (fresh) {         // the gradient itself is zero (or not finite)
        out.converged = g.allFinite();
        break;
      }
      H = I * (first / std::max(g.norm(), 1e-300));
      fresh = true;
      --out.iterations;
      continue;
    }
    // Armijo backtracking: f(α) ≤ f + 1e-4 α gᵀp.
    double alpha = 1.0, f_new = f;
    Pose trial;
    Eigen::VectorXd s;
    bool accepted = false;
    for (int k = 0; k < st.max_backtracks && !accepted; ++k, alpha *= 0.5) {
      s = alpha * p;
      trial = step_pose(out.pose, &s, c, st);
      if (st.feasible) {  // the step taken: the twist from the current pose to the feasible one
        trial = st.feasible(trial);
        s = twist_to(out.pose, trial, c, st);
      }
      ++out.evaluations;
      g_new.resize(n);
      f_new = objective(trial, &g_new, &c_new);
      const double slope_s = g.dot(s);  // < 0 unless the projection turned the step
      accepted = std::isfinite(f_new) && slope_s < 0.0 && f_new <= f + 1e-4 * slope_s;
      if (accepted) break;
    }
    if (!accepted) {  // no decrease left at double precision
      out.converged = true;
      break;
    }
    g_new = in_span(scale_gradient(g_new, L));
    const Eigen::VectorXd y = g_new - g;
    const double sy = s.dot(y);
    if (sy > 1e-12 * s.norm() * y.norm()) {  // BFGS update of the inverse Hessian
      if (fresh) H = I * (sy / y.squaredNorm());
      const double r = 1.0 / sy;
      const Eigen::MatrixXd V = Eigen::MatrixXd::Identity(n, n) - r * y * s.transpose();
      H = V.transpose() * H * V + r * s * s.transpose();
      fresh = false;
    }
    out.pose = trial;
    f = f_new;
    g = g_new;
    c = c_new;
    if (s.lpNorm<Eigen::Infinity>() <= st.step_tolerance * L) {
      out.converged = true;
      ++out.iterations;
      break;
    }
  }
  out.rho = f;
  return out;
}

}  // namespace softhd::scan
