// The directed mean over a scan's surface, given as points with surface weights, against a body's
// continuum inner integral (docs/formulation.md §2.8, "A scan's surface against the body's
// cells"):
//
//     A^4 = (1/W) Σ_j w_j d̃_X(y_j)^4,   d̃_X(y) = (J_X(y)/|Ω_X|)^(−1/4) − ε,   W = Σ_j w_j.

#include "surface_mean.hpp"

#include <cmath>
#include <string>

#include "softhd/error.hpp"

namespace softhd::detail {

namespace {

/// ∂d̃/∂J = −(d̃ + ε)^5 / (4 |Ω_X|) and ∂d̃/∂|Ω_X| = (d̃ + ε) / (4 |Ω_X|), from
/// d̃ + ε = (J/|Ω_X|)^(−1/4).
struct DTildeBars {
  double d_j, d_volume;
};
DTildeBars d_tilde_bars(double d, double epsilon, double volume) {
  const double s = d + epsilon;
  return {-std::pow(s, 5) / (4.0 * volume), s / (4.0 * volume)};
}

/// The points' checks of directed_point_mean; returns W = Σ_j w_j.
double checked_total(const Eigen::MatrixXd& points, const Eigen::VectorXd& weights) {
  if (points.cols() != 3 || weights.size() != points.rows() || points.rows() == 0)
    throw InvalidArgument("directed_point_mean: the points must be M by 3 with M weights, M > 0");
  const double total = weights.sum();
  if (!(total > 0.0))
    throw InvalidArgument("directed_point_mean: the weights sum to " + std::to_string(total) +
                          ", not a positive number");
  return total;
}

/// A^4 from J at the points, with *bar_j = ∂A^4/∂J_j and *bar_volume = ∂A^4/∂|Ω_X| when not null.
OuterMean mean_of_j(const Eigen::VectorXd& j, const Eigen::VectorXd& weights, double total,
                    double source_volume, double epsilon, Eigen::VectorXd* bar_j,
                    double* bar_volume) {
  OuterMean m;
  m.volume = total;
  if (bar_j) bar_j->resize(j.size());
  if (bar_volume) *bar_volume = 0.0;
  for (Eigen::Index k = 0; k < j.size(); ++k) {
    const double d = std::pow(j[k] / source_volume, -0.25) - epsilon;  // d̃_X(y_k)
    const double w = weights[k] / total;
    m.mean += w * d * d * d * d;
    const DTildeBars b = d_tilde_bars(d, epsilon, source_volume);
    if (bar_j) (*bar_j)[k] = 4.0 * w * d * d * d * b.d_j;
    if (bar_volume) *bar_volume += 4.0 * w * d * d * d * b.d_volume;
  }
  return m;
}

}  // namespace

OuterMean directed_point_mean(const Eigen::MatrixXd& points, const Eigen::VectorXd& weights,
                              const BodyIntegral& source_j, double source_volume, double epsilon,
                              OuterMeanGradient* grad) {
  const double total = checked_total(points, weights);
  Eigen::VectorXd j;
  source_j.evaluate(points, &j);
  Eigen::VectorXd bar_j;  // ∂A^4/∂J_j
  double bar_volume = 0.0;
  const OuterMean m = mean_of_j(j, weights, total, source_volume, epsilon, grad ? &bar_j : nullptr,
                                grad ? &bar_volume : nullptr);
  if (grad) {
    grad->outer.resize(0, 3);  // the scan is fixed
    grad->source = source_j.surface_vjp(points, bar_j);
    grad->source_volume = bar_volume;
  }
  return m;
}

OuterMean directed_point_mean_moving(const Eigen::MatrixXd& points, const Eigen::VectorXd& weights,
                                     const BodyIntegral& source_j, double source_volume,
                                     double epsilon, Eigen::MatrixXd* point_gradient) {
  const double total = checked_total(points, weights);
  Eigen::VectorXd j, bar_j;
  Eigen::MatrixXd dj;  // ∂J/∂y_j
  source_j.evaluate(points, &j, point_gradient ? &dj : nullptr);
  const OuterMean m = mean_of_j(j, weights, total, source_volume, epsilon,
                                point_gradient ? &bar_j : nullptr, nullptr);
  if (point_gradient) *point_gradient = dj.array().colwise() * bar_j.array();
  return m;
}

}  // namespace softhd::detail
