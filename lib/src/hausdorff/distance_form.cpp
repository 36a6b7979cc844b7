// The distance forms of docs/formulation.md §8 (one-sided, visible, soft cap): their names,
// validation, and the cap-from-a-quantile rule. The evaluation is in hausdorff.cpp.

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "scaled_means.hpp"
#include "side_means.hpp"
#include "softhd/enum_names.hpp"
#include "softhd/error.hpp"
#include "softhd/hausdorff.hpp"

namespace softhd {

constexpr auto kSidesNames =
    enum_sequence<Sides::visible>({"symmetric", "scan_to_body", "visible"});

std::string to_string(Sides sides) { return enum_name(kSidesNames, sides); }

Sides sides_from_string(const std::string& name) {
  return enum_from_name(kSidesNames, name, "distance");
}

namespace {
// "<what>, got <value>" with the value in full precision (std::to_string prints 1e-9 as 0).
std::string got(const std::string& what, double value) {
  std::ostringstream msg;
  msg.precision(17);
  msg << what << ", got " << value;
  return msg.str();
}
}  // namespace

void DistanceForm::validate(Eigen::Index moving_points) const {
  if (!(cap.c == 0.0 || (std::isfinite(cap.c) && cap.c > 0.0)))
    throw InvalidArgument(got("distance cap.c must be 0 (no cap) or finite and > 0", cap.c));
  // ψ_c(d)/m = (1 + s^q)^(−1/q) ∈ [2^(−1/q), 1] (§8.3): for q ≥ 1e-3 it stays a normal double
  // (≥ 2^−1000) and the scaled evaluation's relative error, about ε_mach/q, below 1e-12.
  if (!(std::isfinite(cap.q) && cap.q >= SoftCap::kMinQ))
    throw InvalidArgument(
        got("distance cap.q must be finite and >= 0.001 (the soft cap's sharpness cap_q)", cap.q));
  if (sides != Sides::visible) {
    if (camera_mask.size() != 0)
      throw InvalidArgument("distance visible: a camera_mask is given but the distance is " +
                            to_string(sides));
    return;
  }
  if (camera_mask.size() != moving_points) {
    throw InvalidArgument("distance visible: the camera_mask has " +
                          std::to_string(camera_mask.size()) + " entries for " +
                          std::to_string(moving_points) + " moving points");
  }
  if (!camera_mask.any())
    throw InvalidArgument("distance visible: the camera_mask marks no moving point");
}

void check_cap_length(const SoftCap& cap, const PointCloud& X, const PointCloud& Y) {
  if (cap.c == 0.0 || X.size() == 0 || Y.size() == 0) return;
  const Eigen::RowVectorXd lo = X.points().colwise().minCoeff().cwiseMin(
                               Y.points().colwise().minCoeff()),
                           hi = X.points().colwise().maxCoeff().cwiseMax(
                               Y.points().colwise().maxCoeff());
  const double L = (hi - lo).norm();
  // ψ_c'(d) ≈ (c/d)^(q+1) for d ≫ c stays ≥ 2^−1022 for every d ≤ L iff c ≥ L 2^(−1022/(q+1)).
  const double smallest = L * std::exp2(-1022.0 / (cap.q + 1.0));
  if (cap.c < smallest) {
    std::ostringstream msg;
    msg.precision(6);
    msg << "distance cap (cap.c) " << cap.c << " is below " << smallest
        << ", the smallest cap for clouds of extent " << L << " with cap_q " << cap.q
        << ": the capped fields' slopes underflow and rho is the constant cap; give 0 (no cap) "
           "or a cap >= "
        << smallest;
    throw InvalidArgument(msg.str());
  }
}

double cap_from_quantile(const Eigen::VectorXd& field, double quantile, double factor) {
  if (!(quantile >= 0.0 && quantile <= 1.0))
    throw InvalidArgument(got("cap quantile must be in [0, 1]", quantile));
  if (!(std::isfinite(factor) && factor > 0.0))
    throw InvalidArgument(got("cap factor must be finite and > 0", factor));
  if (field.size() == 0) throw InvalidArgument("cap quantile: the field has no values");
  if (!field.allFinite()) throw InvalidArgument("cap quantile: the field has a value not finite");
  // Q(p) = x_(k) + (h − k)(x_(k+1) − x_(k)), h = (n − 1) p, k = ⌊h⌋ (order statistics x_(·)).
  std::vector<double> x(field.data(), field.data() + field.size());
  std::sort(x.begin(), x.end());
  const double h = static_cast<double>(x.size() - 1) * quantile;
  const size_t k = static_cast<size_t>(std::floor(h));
  const double upper = k + 1 < x.size() ? x[k + 1] : x[k];
  const double c = factor * (x[k] + (h - static_cast<double>(k)) * (upper - x[k]));
  if (!(std::isfinite(c) && c > 0.0))
    throw InvalidArgument(got("cap quantile: the cap it gives must be finite and > 0", c));
  return c;
}

}  // namespace softhd

namespace softhd::detail {

SideMean side_mean(const Eigen::VectorXd& dt, const Eigen::VectorXd& u, const SoftCap& cap,
                   double beta, bool slopes, const Mask* in_mean) {
  SideMean m;
  m.capped.resize(dt.size());
  for (Eigen::Index n = 0; n < dt.size(); ++n)
    m.capped[n] = in_mean == nullptr || (*in_mean)[n] ? soft_cap(dt[n], cap.c, cap.q) : 0.0;
  m.value = power_mean(m.capped, u, beta);
  if (slopes) {
    m.slope.resize(dt.size());
    for (Eigen::Index n = 0; n < dt.size(); ++n)
      m.slope[n] = power_mean_derivative(m.capped[n], u[n], m.value, beta) *
                   soft_cap_derivative(dt[n], cap.c, cap.q);
  }
  return m;
}

Eigen::VectorXd b_weights(const PointCloud& X, const DistanceForm& form, double& volume) {
  if (form.sides != Sides::visible) {
    volume = X.total_volume();
    return X.volumes() / volume;
  }
  const Eigen::VectorXd V = form.camera_mask.select(X.volumes(), 0.0);
  volume = V.sum();
  return V / volume;
}

std::pair<double, double> rho_slopes(double A, double B, double rho, double gamma, Sides sides) {
  if (sides == Sides::scan_to_body) return {1.0, 0.0};
  return {power_mean_derivative(A, 0.5, rho, gamma), power_mean_derivative(B, 0.5, rho, gamma)};
}

}  // namespace softhd::detail
