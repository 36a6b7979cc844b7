#pragma once
// Tensor Chebyshev interpolation of the pair kernel over boxes, with a rigorous bound
// on the interpolation error (internal; docs/tree_tolerance.md §7 derives it).
//
// On [c − a, c + a] the n Chebyshev points of the second kind are c + a ξ_i,
// ξ_i = cos(π i/(n − 1)); the interpolant of degree n − 1 is evaluated in barycentric
// form. For f analytic inside the Bernstein ellipse E_ρ (foci c ± a, semi-axes
// A = a(ρ + 1/ρ)/2 and B = a(ρ − 1/ρ)/2) with |f| ≤ M there,
//     ‖f − I_n f‖ ≤ 4 M ρ^(1−n)/(ρ − 1),                  (Trefethen, ATAP Thm 8.2)
// also for vector-valued f (norm ‖·‖₂). The Lebesgue constant of these points is
// Λ_n ≤ (2/π) ln n + 1 (ATAP Thm 15.2), so interpolating m variables one after the other,
//     ‖f − I_1⋯I_m f‖ ≤ Σ_j Λ^(j−1) e_j,   e_j: the bound for variable j, others real.
//
// The kernel. With r = |o − x| and one coordinate of o or x complex (z = ξ + iη, |η| ≤ B),
// s = r² has Re s = D² − η² ≥ Dmin² − B² where D is the distance between the real parts
// and Dmin the distance between the two boxes with the interpolated box widened to A
// along that axis. Then Re √s ≥ δ = √(Dmin² − B²), so u(r) = (r + ε)^(−α) is analytic
// (Re s > 0) with |u| ≤ (δ + ε)^(−α), and the gradient kernel u t (o − x)/r, t = 1/(r + ε),
// has ‖·‖ ≤ (δ + ε)^(−α−1) √((Dmin² + B²)/(Dmin² − B²)).

#include <cstdint>

namespace softhd::detail {

constexpr int kMaxChebyshev = 16;  ///< most points per axis

/// The n points ξ_i on [−1, 1] and their barycentric weights.
struct ChebyshevRule {
  explicit ChebyshevRule(int n);
  int n;
  double xi[kMaxChebyshev];
  double bw[kMaxChebyshev];
  /// The n Lagrange basis values at u ∈ [−1, 1] (exactly δ_i at a node).
  void basis(double u, double* L) const;
};

/// Λ_n ≤ (2/π) ln n + 1.
double lebesgue_bound(int n);

/// An axis-aligned box: centre and half-widths, and the shape of its interpolation grids.
/// At degree m (points per axis) axis k carries points_along(k, m) =
/// max(2, ⌈1 + (m − 1) slope_k⌉) ≤ m points: all m where slope_k = 1 (the default), fewer
/// along thin axes (set_grid_slopes). Every bound and translation uses these counts.
struct Box {
  double c[3] = {0.0, 0.0, 0.0};
  double a[3] = {0.0, 0.0, 0.0};
  double slope[3] = {1.0, 1.0, 1.0};
  int points_along(int k, int m) const;
  /// Points of the grid at degree m (the product over the d axes).
  int grid_size(int d, int m) const;
};

/// The box [lo, hi] padded so that every half-width is > 0 (at least 1e-3 of the
/// largest, or a tiny absolute width for a single point): interpolation boxes.
Box interpolation_box(const double* lo, const double* hi, int d);

/// Grid shapes for thin boxes: slope_k = L/(L − ln(a_k/a_max)), L = ln ρ_ref > 0. The
/// one-axis bound falls like ρ_k^(1−m) and the largest admissible ρ_k grows like 1/a_k,
/// so with ρ_ref the widest axis's ρ, an axis a_max/a_k times thinner reaches the same
/// bound with about 1 + (m − 1) L/(L + ln(a_max/a_k)) points. A heuristic for the cost
/// only: the pair bounds use the counts actually chosen. ρ_ref ≤ 1: slopes 1 (isotropic).
void set_grid_slopes(Box& b, int d, double rho_ref);

/// Whether the grids of `inner` at degree m have at least as many points along every
/// axis as those of `outer`: then translations between them are exact (M2M, L2L).
bool grid_nests(const Box& inner, const Box& outer, int d, int m);

/// Translation between a box and a box inside it at degree m (M2M and L2L), for grids
/// that nest (grid_nests(inner, outer)): along axis k, rows[k] = the inner grid's points,
/// cols[k] = the outer grid's, E[k][i·cols + j] = ℓ_j((c'_k + a'_k ξ_i − c_k)/a_k), the
/// outer box's basis function j at the inner box's interpolation point i.
struct Translation {
  int rows[3] = {0, 0, 0}, cols[3] = {0, 0, 0};
  double E[3][kMaxChebyshev * kMaxChebyshev];
};
/// rules[q]: the rule of q points per axis (for every q the grids use).
void make_translation(const ChebyshevRule* rules, const Box& outer, const Box& inner, int m, int d,
                      Translation& t);

/// out += f · (M_0 ⊗ … ⊗ M_(d−1)) in (the last axis fastest), applied one axis at a time,
/// with M_k = E_k (L2L: the outer box's interpolant at the inner box's points; in on the
/// outer grid, out on the inner) or M_k = E_kᵀ (`transpose`, M2M: the outer box's weights
/// Σ_x w_x L_q(x) from the inner box's weights). Both are exact, up to rounding: the inner
/// grid interpolates the outer box's polynomials (degree cols_k − 1 along axis k) exactly.
void tensor_apply(const Translation& t, bool transpose, int d, const double* in, double f,
                  double* out);
/// The multiply-adds of tensor_apply (cost model).
std::int64_t translation_products(const Translation& t, bool transpose, int d);
/// The same count for the translation between grids of rows[k] and cols[k] points.
std::int64_t tensor_products(const int* rows, const int* cols, int d);

/// out += (A_0 ⊗ … ⊗ A_(d−1)) in for rows[k] × cols[k] matrices A_k (row-major), one axis
/// at a time: in has Π cols values, out Π rows (the last axis fastest). With
/// A_k[j][q] = ℓ^(m)_q(ξ^(n)_j) (rows n, cols m) it carries a degree-m grid's values to the
/// degree-n grid of the same box; with its transpose it carries degree-n proxy weights to
/// degree m. Both are exact up to rounding (tree_tolerance.md §7).
void tensor_rect(const double* const* A, const int* rows, const int* cols, int d, const double* in,
                 double* out);
/// The same with one matrix A (rows × cols) along every axis.
void tensor_rect(const double* A, int rows, int cols, int d, const double* in, double* out);

/// Natural logarithms of bounds, per unit source weight, on the interpolation error of
/// u and of the gradient kernel (above), for o in box T and x in box S, when the d
/// coordinates of o (interp_t) and/or of x (interp_s) are interpolated on the boxes'
/// grids at degree n (Box::points_along(k, n) points along axis k; each term of the sum
/// of §7 takes Λ of n, the most points of any axis, an upper bound). +∞ when the boxes
/// are too close for any ellipse.
struct LogBounds {
  double value;
  double grad;
};
LogBounds interpolation_log_bound(const Box& T, bool interp_t, const Box& S, bool interp_s, int d,
                                  int n, double alpha, double eps);
/// The same bounds for every n in [2, n_max] at once, in out[2..n_max] (the ellipses and
/// the kernel's bounds on them do not depend on n; only ρ^(1−n) and Λ_n do).
void interpolation_log_bounds(const Box& T, bool interp_t, const Box& S, bool interp_s, int d,
                              int n_max, double alpha, double eps, LogBounds* out);

/// The degree-free parts of the 1D bound e_j of one interpolated axis, on a grid of
/// ellipses: for ellipse f, log e_j = base_v[f] − (n − 1) log ρ_f (value kernel) and
/// base_g[f] − (n − 1) log ρ_f (gradient kernel).
struct AxisTerms {
  static constexpr int kGrid = 16;
  int count = 0;
  double log_rho[kGrid], base_v[kGrid], base_g[kGrid];
};

/// interpolation_log_bounds for one box pair and several operations (which sides are
/// interpolated), computing each axis's ellipse terms once.
class PairBounds {
 public:
  PairBounds(const Box& T, const Box& S, int d, double alpha, double eps);
  /// out[n] for n in [n_min, n_max].
  void bounds(bool interp_t, bool interp_s, int n_min, int n_max, LogBounds* out);
  /// The bound of one interpolated axis alone at degree n (of T if which_t, else of S; at
  /// its box's points_along(axis, n) points): at most bounds()' out[m] for every m ≤ n and
  /// every operation that interpolates this axis (their sum over the axes gives the
  /// largest term weight Λ^0 = 1, and an axis's bound decreases with its points). A cheap
  /// necessary test before bounds().
  LogBounds axis_bound(bool which_t, int axis, int n);
  /// How many axes' ellipse terms were computed (the planning's main work).
  int computed() const { return computed_; }

 private:
  Box T_, S_;
  int d_;
  double alpha_, eps_;
  AxisTerms terms_[6];  // T's axes, then S's
  bool done_[6] = {false, false, false, false, false, false};
  int computed_ = 0;
  const AxisTerms& terms(bool which_t, int axis);
};

}  // namespace softhd::detail
