#pragma once
// Scalar formulas of docs/formulation.md §2.3 evaluated in the scaled / log domain (internal).
// Each function is one formula; the comment gives the formula it implements.

#include <Eigen/Core>
#include <algorithm>
#include <cmath>

namespace softhd::detail {

/// d̃ = φ⁻¹(I) from the scaled kernel sum S = Σ w_n ((r_min+ε)/(r_n+ε))^α ∈ (0, 1]:
///     d̃ = r_min · S^(−1/α) + ε · expm1(−log(S)/α)
/// (equal to 1/I − ε with I = S^(1/α)/(r_min + ε), without its cancellation).
inline double regularised_distance(double r_min, double S, double alpha, double eps) {
  const double e = -std::log(S) / alpha;
  return r_min * std::exp(e) + eps * std::expm1(e);
}

/// Weighted power mean M = (Σ w_j v_j^p)^(1/p), Σ w_j = 1, v_j ≥ 0, scaled by the
/// maximum D = max v_j:  M = D (Σ w_j (v_j/D)^p)^(1/p). Returns 0 when all v_j = 0.
inline double power_mean(const Eigen::VectorXd& v, const Eigen::VectorXd& w, double p) {
  const double D = v.size() > 0 ? v.maxCoeff() : 0.0;
  if (!(D > 0.0)) return 0.0;
  double sum = 0.0;
  for (Eigen::Index j = 0; j < v.size(); ++j) sum += w[j] * std::pow(v[j] / D, p);
  return D * std::pow(sum, 1.0 / p);
}

/// ∂M/∂v_j of the power mean above: w_j (v_j/M)^(p−1). Where v_j = 0 (or M = 0) the
/// derivative is w_j for p = 1, and 0 otherwise (the value for p > 1; a subgradient
/// choice for p < 1, where it is unbounded).
inline double power_mean_derivative(double v_j, double w_j, double M, double p) {
  if (!(M > 0.0)) return 0.0;
  if (v_j > 0.0) return w_j * std::pow(v_j / M, p - 1.0);
  return p == 1.0 ? w_j : 0.0;
}

/// ρ̃ = ((A^γ + B^γ)/2)^(1/γ), scaled by max(A, B).
inline double combine_means(double A, double B, double gamma) {
  const double D = std::max(A, B);
  if (!(D > 0.0)) return 0.0;
  return D * std::pow(0.5 * (std::pow(A / D, gamma) + std::pow(B / D, gamma)), 1.0 / gamma);
}

}  // namespace softhd::detail

namespace softhd::detail {

/// The soft cap of docs/formulation.md §8.3, ψ_c(d) = (d^(−q) + c^(−q))^(−1/q), in the
/// scaled form ψ_c(d) = m (1 + s^q)^(−1/q) with m = min(d, c), s = m / max(d, c) ∈ [0, 1]
/// (no power of d or c is formed, so nothing overflows). ψ_c(0) = 0; c = 0 means no cap.
inline double soft_cap(double d, double c, double q) {
  if (c == 0.0 || !(d > 0.0)) return c == 0.0 ? d : 0.0;
  const double lo = std::min(d, c), hi = std::max(d, c);
  return lo * std::exp(-std::log1p(std::pow(lo / hi, q)) / q);
}

/// ψ_c'(d) = (ψ_c(d)/d)^(q+1) ∈ (0, 1], with ψ_c/d = (1 + (d/c)^q)^(−1/q) for d ≤ c and
/// (c/d)(1 + (c/d)^q)^(−1/q) for d > c. ψ_c'(0) = 1; c = 0 (no cap): 1.
inline double soft_cap_derivative(double d, double c, double q) {
  if (c == 0.0 || !(d > 0.0)) return 1.0;
  const double s = d <= c ? d / c : c / d;
  const double ratio = (d <= c ? 1.0 : s) * std::exp(-std::log1p(std::pow(s, q)) / q);
  return std::pow(ratio, q + 1.0);
}

}  // namespace softhd::detail
