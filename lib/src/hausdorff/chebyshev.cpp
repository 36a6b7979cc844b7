#include "chebyshev.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <utility>

#ifdef SOFTHD_HAVE_LIBMVEC
#include <immintrin.h>
// glibc's vector maths (libmvec), 4 doubles per call in the x86-64 vector function ABI.
extern "C" __m256d _ZGVdN4v_log(__m256d);
extern "C" __m256d _ZGVdN4v_log1p(__m256d);
#endif

namespace softhd::detail {

ChebyshevRule::ChebyshevRule(int points) : n(points) {
  assert(n >= 2 && n <= kMaxChebyshev);
  for (int i = 0; i < n; ++i) {
    xi[i] = std::cos(M_PI * i / (n - 1));
    bw[i] = (i % 2 == 0 ? 1.0 : -1.0) * (i == 0 || i == n - 1 ? 0.5 : 1.0);
  }
}

void ChebyshevRule::basis(double u, double* L) const {
  double sum = 0.0;
  for (int i = 0; i < n; ++i) {
    const double diff = u - xi[i];
    if (diff == 0.0) {
      for (int j = 0; j < n; ++j) L[j] = j == i ? 1.0 : 0.0;
      return;
    }
    L[i] = bw[i] / diff;
    sum += L[i];
  }
  const double inv = 1.0 / sum;
  for (int i = 0; i < n; ++i) L[i] *= inv;
}

double lebesgue_bound(int n) { return 2.0 / M_PI * std::log(static_cast<double>(n)) + 1.0; }

Box interpolation_box(const double* lo, const double* hi, int d) {
  Box b;
  double amax = 0.0;
  for (int k = 0; k < d; ++k) {
    b.c[k] = 0.5 * (lo[k] + hi[k]);
    b.a[k] = 0.5 * (hi[k] - lo[k]);
    amax = std::max(amax, b.a[k]);
  }
  for (int k = 0; k < d; ++k) {
    const double floor = amax > 0.0 ? 1e-3 * amax : 1e-12 * (1.0 + std::fabs(b.c[k]));
    b.a[k] = std::max(b.a[k], floor);
  }
  return b;
}

int Box::points_along(int k, int m) const {
  if (slope[k] >= 1.0) return m;
  const int q = static_cast<int>(std::ceil(1.0 + (m - 1) * slope[k] - 1e-9));
  return std::clamp(q, 2, m);
}

int Box::grid_size(int d, int m) const {
  int P = 1;
  for (int k = 0; k < d; ++k) P *= points_along(k, m);
  return P;
}

void set_grid_slopes(Box& b, int d, double rho_ref) {
  double amax = 0.0;
  for (int k = 0; k < d; ++k) amax = std::max(amax, b.a[k]);
  for (int k = 0; k < d; ++k) {
    b.slope[k] = 1.0;
    if (!(rho_ref > 1.0) || !(b.a[k] < amax)) continue;
    const double L = std::log(rho_ref);
    b.slope[k] = L / (L + std::log(amax / b.a[k]));  // L/(L − ln(a_k/a_max))
  }
}

bool grid_nests(const Box& inner, const Box& outer, int d, int m) {
  for (int k = 0; k < d; ++k)
    if (inner.points_along(k, m) < outer.points_along(k, m)) return false;
  return true;
}

void make_translation(const ChebyshevRule* rules, const Box& outer, const Box& inner, int m, int d,
                      Translation& t) {
  for (int k = 0; k < d; ++k) {
    const int rows = inner.points_along(k, m), cols = outer.points_along(k, m);
    assert(rows >= cols);
    t.rows[k] = rows;
    t.cols[k] = cols;
    const ChebyshevRule& in = rules[rows];
    for (int i = 0; i < rows; ++i)
      rules[cols].basis((inner.c[k] + inner.a[k] * in.xi[i] - outer.c[k]) / outer.a[k],
                        &t.E[k][i * cols]);
  }
}

namespace {

/// out += f (A_0 ⊗ … ⊗ A_(d−1)) in, A_k of rows[k] × cols[k], element (i, j) at
/// A_k[i · rs[k] + j · cs[k]] (cs = 1, rs = cols: row-major; swapped: the transpose).
void tensor_axes(const double* const* A, const int* rs, const int* cs, const int* rows,
                 const int* cols, int d, const double* in, double f, double* out) {
  constexpr int kMax = kMaxChebyshev * kMaxChebyshev * kMaxChebyshev;
  double buf[2][kMax];
  int dims[3] = {cols[0], d > 1 ? cols[1] : 1, d > 2 ? cols[2] : 1};
  const double* src = in;
  for (int k = d - 1, which = 0; k >= 0; --k, which ^= 1) {
    int outer = 1, inner = 1;
    for (int a = 0; a < k; ++a) outer *= dims[a];
    for (int a = k + 1; a < d; ++a) inner *= dims[a];
    double* dst = buf[which];
    const double* M = A[k];
    for (int o = 0; o < outer; ++o)
      for (int i = 0; i < rows[k]; ++i)
        for (int r = 0; r < inner; ++r) {
          double sum = 0.0;
          for (int j = 0; j < cols[k]; ++j)
            sum += M[i * rs[k] + j * cs[k]] * src[(o * cols[k] + j) * inner + r];
          dst[(o * rows[k] + i) * inner + r] = sum;
        }
    dims[k] = rows[k];
    src = dst;
  }
  int total = 1;
  for (int k = 0; k < d; ++k) total *= rows[k];
  for (int q = 0; q < total; ++q) out[q] += f * src[q];
}

}  // namespace

void tensor_apply(const Translation& t, bool transpose, int d, const double* in, double f,
                  double* out) {
  const double* A[3] = {t.E[0], t.E[1], t.E[2]};
  int rs[3], cs[3], rows[3], cols[3];
  for (int k = 0; k < d; ++k) {
    rows[k] = transpose ? t.cols[k] : t.rows[k];
    cols[k] = transpose ? t.rows[k] : t.cols[k];
    rs[k] = transpose ? 1 : t.cols[k];
    cs[k] = transpose ? t.cols[k] : 1;
  }
  tensor_axes(A, rs, cs, rows, cols, d, in, f, out);
}

std::int64_t tensor_products(const int* rows, const int* cols, int d) {
  std::int64_t dims[3] = {cols[0], d > 1 ? cols[1] : 1, d > 2 ? cols[2] : 1}, total = 0;
  for (int k = d - 1; k >= 0; --k) {
    std::int64_t rest = 1;
    for (int a = 0; a < d; ++a)
      if (a != k) rest *= dims[a];
    total += rest * rows[k] * cols[k];
    dims[k] = rows[k];
  }
  return total;
}

std::int64_t translation_products(const Translation& t, bool transpose, int d) {
  return transpose ? tensor_products(t.cols, t.rows, d) : tensor_products(t.rows, t.cols, d);
}

void tensor_rect(const double* const* A, const int* rows, const int* cols, int d, const double* in,
                 double* out) {
  const int cs[3] = {1, 1, 1};
  tensor_axes(A, cols, cs, rows, cols, d, in, 1.0, out);
}

void tensor_rect(const double* A, int rows, int cols, int d, const double* in, double* out) {
  const double* As[3] = {A, A, A};
  const int r[3] = {rows, rows, rows}, c[3] = {cols, cols, cols};
  tensor_rect(As, r, c, d, in, out);
}

namespace {

/// Squared distance between box T and box S, with half-width `widen` replacing the
/// half-width of axis `axis` of T (which_t) or of S.
double box_gap2(const Box& T, const Box& S, int d, bool which_t, int axis, double widen) {
  double g2 = 0.0;
  for (int k = 0; k < d; ++k) {
    double at = T.a[k], as = S.a[k];
    if (k == axis) (which_t ? at : as) = widen;
    const double gap = std::max(0.0, std::fabs(T.c[k] - S.c[k]) - at - as);
    g2 += gap * gap;
  }
  return g2;
}

/// min over the Bernstein ellipse with real half-axis A and imaginary half-axis B (centred
/// at 0) of (Re d)² − (Im d)² for d = z − y, y real in [lo, hi]:
///     min_{x∈[−1,1]} dist(A x, [lo, hi])² − B² (1 − x²).
/// (For a given real part the boundary has the largest |Im z|, so the minimum over the
/// filled ellipse lies on the boundary, z = A x ± i B √(1 − x²).) Each piece of [−1, 1] is
/// a convex quadratic in x, minimised in closed form. Branch-free (an empty piece gives
/// +∞), so that the loop over the ellipses vectorises.
inline double ellipse_min(double A, double B, double lo, double hi) {
  const double inf = std::numeric_limits<double>::infinity();
  const double B2 = B * B, AB2 = A * A + B2, rl = lo / A, rh = hi / A;
  // A x ≤ lo, x ∈ [−1, min(1, lo/A)], non-empty iff lo > −A: dist = lo − A x.
  const double xl = std::min(std::max(lo * A / AB2, -1.0), std::min(1.0, rl));
  const double vl = lo > -A ? (lo - A * xl) * (lo - A * xl) - B2 * (1.0 - xl * xl) : inf;
  // A x ≥ hi, x ∈ [max(−1, hi/A), 1], non-empty iff hi < A: dist = A x − hi.
  const double xh = std::min(std::max(hi * A / AB2, std::max(-1.0, rh)), 1.0);
  const double vh = hi < A ? (hi - A * xh) * (hi - A * xh) - B2 * (1.0 - xh * xh) : inf;
  // A x inside [lo, hi]: dist = 0, the smallest |x| gives the most negative value.
  const double x0 = std::max(-1.0, rl), x1 = std::min(1.0, rh);
  const double xi = std::min(std::max(0.0, x0), x1);
  const double vi = x0 <= x1 ? -B2 * (1.0 - xi * xi) : inf;
  return std::min(vl, std::min(vh, vi));
}

constexpr double kLog4 = 1.3862943611198906;  // log 4
static_assert(AxisTerms::kGrid % 4 == 0, "the grid's logs are taken four at a time");

/// y = log x (Plus1: log(1 + x)) over the ellipse grid: libmvec's AVX2 log and log1p (within
/// 4 ulp) where the build has them, else std::log, std::log1p. Any rounding of a log
/// shifts a bound by a few ulp of its logarithm.
template <bool Plus1>
void logs(const double (&x)[AxisTerms::kGrid], double (&y)[AxisTerms::kGrid]) {
#ifdef SOFTHD_HAVE_LIBMVEC
  for (int i = 0; i < AxisTerms::kGrid; i += 4) {
    const __m256d v = _mm256_loadu_pd(x + i);
    _mm256_storeu_pd(y + i, Plus1 ? _ZGVdN4v_log1p(v) : _ZGVdN4v_log(v));
  }
#else
  for (int i = 0; i < AxisTerms::kGrid; ++i) y[i] = Plus1 ? std::log1p(x[i]) : std::log(x[i]);
#endif
}

AxisTerms axis_terms(const Box& T, const Box& S, int d, bool which_t, int axis, double alpha,
                     double eps) {
  AxisTerms out;
  const Box& mine = which_t ? T : S;
  const Box& other = which_t ? S : T;
  const double a = mine.a[axis];
  const double D0 = std::sqrt(box_gap2(T, S, d, which_t, axis, a));
  if (!(D0 > 0.0)) return out;
  double across = 0.0;  // squared gap of the (real) boxes across the other axes
  for (int k = 0; k < d; ++k) {
    const double gap = std::max(0.0, std::fabs(T.c[k] - S.c[k]) - T.a[k] - S.a[k]);
    if (k != axis) across += gap * gap;
  }
  const double lo = other.c[axis] - other.a[axis] - mine.c[axis];
  const double hi = other.c[axis] + other.a[axis] - mine.c[axis];
  // Analyticity needs A² + B² = a² (ρ² + ρ⁻²)/2 below the squared distance to the far
  // side of the other box plus `across`: ρ < ρ_top.
  const double far2 = std::max(lo * lo, hi * hi) + across;
  const double rho_top = std::sqrt(2.0 * far2) / a + 1.0;
  static constexpr int kG = AxisTerms::kGrid;
  static constexpr double kGrid[kG] = {0.02, 0.05, 0.09, 0.14, 0.2,  0.27, 0.34, 0.41,
                                       0.48, 0.55, 0.62, 0.69, 0.76, 0.83, 0.9,  0.96};
  // The ellipses first, then their logarithms four at a time (they were most of the
  // planning's transcendental work), then the bounds of the ellipses with Re s > 0.
  double rho[kG], rho_minus_1[kG], delta_eps[kG], im_ratio[kG], re2[kG];
#pragma omp simd
  for (int f = 0; f < kG; ++f) {
    rho[f] = 1.0 + (rho_top - 1.0) * kGrid[f];
    const double A = 0.5 * a * (rho[f] + 1.0 / rho[f]), B = 0.5 * a * (rho[f] - 1.0 / rho[f]);
    re2[f] = across + ellipse_min(A, B, lo, hi);   // ≤ Re s
    const double s = re2[f] > 0.0 ? re2[f] : 1.0;  // placeholders for the skipped ellipses
    rho_minus_1[f] = rho[f] - 1.0;
    delta_eps[f] = std::sqrt(s) + eps;  // δ + ε
    im_ratio[f] = 2.0 * B * B / s;
  }
  double log_rho[kG], log_rho1[kG], ld[kG], log_im[kG];
  logs<false>(rho, log_rho);
  logs<false>(rho_minus_1, log_rho1);
  logs<false>(delta_eps, ld);
  logs<true>(im_ratio, log_im);
  for (int f = 0; f < kG; ++f) {
    if (!(re2[f] > 0.0)) continue;
    const double value = kLog4 - log_rho1[f] - alpha * ld[f];
    // ‖o − x‖² = Re s + 2 (Im d)² ≤ Re s + 2 B², |r|² = |s| ≥ Re s.
    out.log_rho[out.count] = log_rho[f];
    out.base_v[out.count] = value;
    out.base_g[out.count] = value - ld[f] + 0.5 * log_im[f];
    ++out.count;
  }
  return out;
}

/// log e_j at n points per axis: the best ellipse of the grid.
LogBounds axis_log_bound(const AxisTerms& t, int n) {
  const double inf = std::numeric_limits<double>::infinity();
  LogBounds best{inf, inf};
  for (int f = 0; f < t.count; ++f) {
    const double drop = (n - 1) * t.log_rho[f];
    best.value = std::min(best.value, t.base_v[f] - drop);
    best.grad = std::min(best.grad, t.base_g[f] - drop);
  }
  return best;
}

/// log Σ_j Λ^j e_j with the e_j sorted in decreasing order (the largest gets Λ^0).
double combine(double* le, int m, double log_lambda) {
  for (int i = 1; i < m; ++i)  // insertion sort, decreasing (m ≤ 6)
    for (int j = i; j > 0 && le[j] > le[j - 1]; --j) std::swap(le[j], le[j - 1]);
  const double top = le[0];
  if (!std::isfinite(top)) return top;
  double sum = 0.0;
  for (int j = 0; j < m; ++j) sum += std::exp(le[j] - top + j * log_lambda);
  return top + std::log(sum);
}

}  // namespace

PairBounds::PairBounds(const Box& T, const Box& S, int d, double alpha, double eps)
    : T_(T), S_(S), d_(d), alpha_(alpha), eps_(eps) {}

const AxisTerms& PairBounds::terms(bool which_t, int axis) {
  const int i = (which_t ? 0 : 3) + axis;
  if (!done_[i]) {
    terms_[i] = axis_terms(T_, S_, d_, which_t, axis, alpha_, eps_);
    done_[i] = true;
    ++computed_;
  }
  return terms_[i];
}

LogBounds PairBounds::axis_bound(bool which_t, int axis, int n) {
  return axis_log_bound(terms(which_t, axis), (which_t ? T_ : S_).points_along(axis, n));
}

void PairBounds::bounds(bool interp_t, bool interp_s, int n_min, int n_max, LogBounds* out) {
  const AxisTerms* terms[6];
  const Box* box[6];
  int axis[6];
  int m = 0;
  for (int side = 0; side < 2; ++side) {
    const bool which_t = side == 0;
    if (which_t ? !interp_t : !interp_s) continue;
    for (int k = 0; k < d_; ++k, ++m) {
      terms[m] = &this->terms(which_t, k);
      box[m] = which_t ? &T_ : &S_;
      axis[m] = k;
    }
  }
  const double inf = std::numeric_limits<double>::infinity();
  for (int n = std::max(n_min, 2); n <= n_max; ++n) {
    if (m == 0) {
      out[n] = {-inf, -inf};
      continue;
    }
    double lv[6], lg[6];
    for (int j = 0; j < m; ++j) {
      const LogBounds e = axis_log_bound(*terms[j], box[j]->points_along(axis[j], n));
      lv[j] = e.value;
      lg[j] = e.grad;
    }
    const double log_lambda = std::log(lebesgue_bound(n));
    out[n] = {combine(lv, m, log_lambda), combine(lg, m, log_lambda)};
  }
}

void interpolation_log_bounds(const Box& T, bool interp_t, const Box& S, bool interp_s, int d,
                              int n_max, double alpha, double eps, LogBounds* out) {
  PairBounds(T, S, d, alpha, eps).bounds(interp_t, interp_s, 2, n_max, out);
}

LogBounds interpolation_log_bound(const Box& T, bool interp_t, const Box& S, bool interp_s, int d,
                                  int n, double alpha, double eps) {
  LogBounds all[kMaxChebyshev + 1];
  interpolation_log_bounds(T, interp_t, S, interp_s, d, n, alpha, eps, all);
  return all[n];
}

}  // namespace softhd::detail
