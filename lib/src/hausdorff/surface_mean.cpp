// The directed mean over a scan's surface, given as points with surface weights, against a body's
// continuum inner integral (docs/formulation.md §2.8, "A scan's surface against the body's
// cells"):
//
//     A^4 = (1/W) Σ_j w_j d̃_X(y_j)^4,   d̃_X(y) = (J_X(y)/|Ω_X|)^(−1/4) − ε,   W = Σ_j w_j.

#include <cmath>
#include <string>

#include "body_integral.hpp"
#include "cell_distance.hpp"
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

}  // namespace

OuterMean directed_point_mean(const Eigen::MatrixXd& points, const Eigen::VectorXd& weights,
                              const BodyIntegral& source_j, double source_volume, double epsilon,
                              OuterMeanGradient* grad) {
  if (points.cols() != 3 || weights.size() != points.rows() || points.rows() == 0)
    throw InvalidArgument("directed_point_mean: the points must be M by 3 with M weights, M > 0");
  const double total = weights.sum();
  if (!(total > 0.0))
    throw InvalidArgument("directed_point_mean: the weights sum to " + std::to_string(total) +
                          ", not a positive number");
  Eigen::VectorXd j;
  source_j.evaluate(points, &j);
  OuterMean m;
  m.volume = total;
  Eigen::VectorXd bar_j(points.rows());  // ∂A^4/∂J_j
  double bar_volume = 0.0;               // ∂A^4/∂|Ω_X|
  for (Eigen::Index k = 0; k < points.rows(); ++k) {
    const double d = std::pow(j[k] / source_volume, -0.25) - epsilon;  // d̃_X(y_k)
    const double w = weights[k] / total;
    m.mean += w * d * d * d * d;
    const DTildeBars b = d_tilde_bars(d, epsilon, source_volume);
    bar_j[k] = 4.0 * w * d * d * d * b.d_j;
    bar_volume += 4.0 * w * d * d * d * b.d_volume;
  }
  if (grad) {
    grad->outer.resize(0, 3);  // the scan is fixed
    grad->source = source_j.surface_vjp(points, bar_j);
    grad->source_volume = bar_volume;
  }
  return m;
}

}  // namespace softhd::detail
