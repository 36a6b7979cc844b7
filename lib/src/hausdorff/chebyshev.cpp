#include "chebyshev.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <utility>

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

void make_translation(const ChebyshevRule& rule, const Box& outer, const Box& inner, int d,
                      Translation& t) {
  const int n = rule.n;
  for (int k = 0; k < d; ++k)
    for (int i = 0; i < n; ++i)
      rule.basis((inner.c[k] + inner.a[k] * rule.xi[i] - outer.c[k]) / outer.a[k], &t.E[k][i * n]);
}

void tensor_apply(const Translation& t, bool transpose, int n, int d, const double* in, double f,
                  double* out) {
  constexpr int kMax = kMaxChebyshev * kMaxChebyshev * kMaxChebyshev;
  double buf[2][kMax];
  int total = 1;
  for (int k = 0; k < d; ++k) total *= n;
  const double* src = in;
  int stride = 1;
  for (int k = d - 1, which = 0; k >= 0; --k, which ^= 1, stride *= n) {
    double M[kMaxChebyshev * kMaxChebyshev];  // M[i n + j] = M_k(i, j)
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) M[i * n + j] = transpose ? t.E[k][j * n + i] : t.E[k][i * n + j];
    double* dst = buf[which];
    const int block = n * stride;
    for (int base = 0; base < total; base += block)
      for (int i = 0; i < n; ++i)
        for (int inner = 0; inner < stride; ++inner) {
          double sum = 0.0;
          for (int j = 0; j < n; ++j) sum += M[i * n + j] * src[base + j * stride + inner];
          dst[base + i * stride + inner] = sum;
        }
    src = dst;
  }
  for (int q = 0; q < total; ++q) out[q] += f * src[q];
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

/// log of the 1D bound e_j (value and gradient kernels) for one interpolated axis,
/// minimised over a grid of ellipses.
LogBounds axis_log_bound(const Box& T, const Box& S, int d, bool which_t, int axis, int n,
                         double alpha, double eps) {
  const double inf = std::numeric_limits<double>::infinity();
  LogBounds best{inf, inf};
  const double a = (which_t ? T : S).a[axis];
  const double D0 = std::sqrt(box_gap2(T, S, d, which_t, axis, a));
  if (!(D0 > 0.0)) return best;
  const double u = D0 / a;
  const double rho_max = u + std::sqrt(u * u + 1.0);  // B(ρ_max) = D0
  static constexpr double kGrid[] = {0.03, 0.08, 0.15, 0.25, 0.35, 0.45,
                                     0.55, 0.65, 0.75, 0.85, 0.93};
  for (double f : kGrid) {
    const double rho = 1.0 + (rho_max - 1.0) * f;
    const double A = 0.5 * a * (rho + 1.0 / rho), B = 0.5 * a * (rho - 1.0 / rho);
    const double Dm2 = box_gap2(T, S, d, which_t, axis, A);
    if (!(Dm2 > B * B)) continue;
    const double delta = std::sqrt(Dm2 - B * B);
    const double common = std::log(4.0) - (n - 1) * std::log(rho) - std::log(rho - 1.0);
    const double value = common - alpha * std::log(delta + eps);
    const double grad =
        value - std::log(delta + eps) + 0.5 * std::log((Dm2 + B * B) / (Dm2 - B * B));
    best.value = std::min(best.value, value);
    best.grad = std::min(best.grad, grad);
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

LogBounds interpolation_log_bound(const Box& T, bool interp_t, const Box& S, bool interp_s, int d,
                                  int n, double alpha, double eps) {
  double lv[6], lg[6];
  int m = 0;
  for (int side = 0; side < 2; ++side) {
    const bool which_t = side == 0;
    if (which_t ? !interp_t : !interp_s) continue;
    for (int k = 0; k < d; ++k) {
      const LogBounds e = axis_log_bound(T, S, d, which_t, k, n, alpha, eps);
      lv[m] = e.value;
      lg[m] = e.grad;
      ++m;
    }
  }
  const double inf = std::numeric_limits<double>::infinity();
  if (m == 0) return {-inf, -inf};
  const double log_lambda = std::log(lebesgue_bound(n));
  return {combine(lv, m, log_lambda), combine(lg, m, log_lambda)};
}

}  // namespace softhd::detail
