#pragma once
// The β-means of the distance forms (docs/formulation.md §8, internal): one side's capped mean
// and its slopes, B's weights (all moving points or the visible ones), ∂ρ̃/∂A and ∂ρ̃/∂B.

#include <Eigen/Core>
#include <utility>

#include "pair_backend.hpp"
#include "softhd/hausdorff.hpp"
#include "softhd/point_cloud.hpp"

namespace softhd::detail {

/// One side's β-mean of capped field values, and its slopes (§8.3):
///     m = (Σ_n u_n ψ(d̃_n)^β)^(1/β),  ∂m/∂d̃_n = u_n (ψ_n/m)^(β−1) ψ'(d̃_n)
/// with weights u_n summing to 1 (zero for points outside the mean: B_V's hidden points).
struct SideMean {
  Eigen::VectorXd capped;  ///< ψ(d̃_n) (0 outside the mean, so its scale ignores them)
  double value = 0.0;      ///< m
  Eigen::VectorXd slope;   ///< ∂m/∂d̃_n (when asked for)
};

/// The mean above of the fields `dt` with weights `u`; `in_mean` (optional) marks the points
/// in it, the others' ψ set to 0. Slopes only if `slopes`.
SideMean side_mean(const Eigen::VectorXd& dt, const Eigen::VectorXd& u, const SoftCap& cap,
                   double beta, bool slopes, const Mask* in_mean = nullptr);

/// The weights of B's mean: V_i/|X| (symmetric), or V_i/|V| on the visible points and 0
/// elsewhere (visible, |V| = Σ_{k visible} V_k). `volume` gets |X| or |V|.
Eigen::VectorXd b_weights(const PointCloud& X, const DistanceForm& form, double& volume);

/// ∂ρ̃/∂A and ∂ρ̃/∂B: ½ (A/ρ̃)^(γ−1) and ½ (B/ρ̃)^(γ−1); scan_to_body (ρ̃ = A): 1 and 0.
std::pair<double, double> rho_slopes(double A, double B, double rho, double gamma, Sides sides);

}  // namespace softhd::detail
