#pragma once
// The all-pairs kernel sums of docs/formulation.md §2.5 (internal). Runs N·M times per pass: this
// is the hot loop of the exact method.
//
// For an outer point o with scale c_o = r_min(o) + ε and inner points x_n:
//     t_n = 1/(r_n + ε),  r_n = |o − x_n|            (φ(r_n))
//     p_n = (c_o t_n)^α ∈ (0, 1]                       (scaled φ^α, never overflows)
//     S   = Σ_n w_n p_n                                 (kOuterSum)
//     G   = Σ_n w_n p_n t_n (o − x_n)/r_n               (kOuterGrad)
// and, scaled by the inner points' own scales c_n = r_min(x_n) + ε:
//     p'_n = (c_n t_n)^α
//     H   = Σ_n h_n p'_n,   G2 = Σ_n h_n p'_n t_n (o − x_n)/r_n   (kInner)
// A coincident pair (r_n = 0) contributes zero to G and G2 (symmetric subgradient).
// With kMagnitude, also the sums of the norms of the vector terms (method tree's
// error budget for G and G2 is relative to them):
//     Gm = Σ_{r_n>0} w_n p_n t_n,   G2m = Σ_{r_n>0} h_n p'_n t_n

#include <Eigen/Core>

namespace softhd::detail {

/// p = q^α for q ∈ (0, 1]: repeated squaring when α is an integer (exact to a few
/// ulps per squaring, vectorised over a block), exp(α log q) otherwise. For α ∈ {2, 4, 8,
/// 16, 64} pair_sums unrolls the same squarings inside its one loop over the sources
/// (the same numbers, without the block buffers: 2–3× faster, docs/bench_hausdorff.md).
class KernelPower {
 public:
  explicit KernelPower(double alpha);
  void apply(const double* q, double* p, int len) const;
  /// q^α for one q ≥ 0 (the same arithmetic as apply).
  double scalar(double q) const;
  double alpha() const { return alpha_; }
  /// α when it is an integer ≤ 2^30, else 0.
  unsigned long long fixed() const { return integer_; }

 private:
  double alpha_;
  unsigned long long integer_ = 0;  // α when α is an integer ≤ 2^30, else 0
};

/// Inner points in structure-of-arrays form, with per-point weights.
struct PairSources {
  int dim = 3;
  Eigen::Index size = 0;
  const double* coord[3] = {nullptr, nullptr, nullptr};  ///< coordinate arrays
  const double* weight = nullptr;                        ///< w_n (kOuterSum, kOuterGrad)
  const double* coef = nullptr;                          ///< h_n (kInner)
  const double* scale = nullptr;                         ///< c_n (kInner)
};

enum PairFlags : unsigned { kOuterSum = 1u, kOuterGrad = 2u, kInner = 4u, kMagnitude = 8u };

struct PairSums {
  double S = 0.0;
  double G[3] = {0.0, 0.0, 0.0};
  double H = 0.0;
  double G2[3] = {0.0, 0.0, 0.0};
  double Gm = 0.0;   ///< Σ of |term| of G (kMagnitude with kOuterGrad)
  double G2m = 0.0;  ///< Σ of |term| of G2 (kMagnitude with kInner)
};

/// The sums above for one outer point `o` (dim coordinates) and the requested flags.
PairSums pair_sums(const double* o, double c_o, const PairSources& src, const KernelPower& power,
                   double eps, unsigned flags);

}  // namespace softhd::detail
