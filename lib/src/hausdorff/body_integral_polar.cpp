// BodyIntegral's polar rule for the triangles near y (body_integral.hpp): each edge's wedge in
// the sinh variable, the first moment by the edge line integrals, the solid angle.

#include <array>
#include <cmath>

#include "body_integral_internal.hpp"

namespace softhd::detail::body {

namespace {

// The most angle points (validate: angle_points ≤ 64).
constexpr int kMaxAnglePoints = 64;

// 1/j! for j = 0 … 18.
constexpr std::array<double, 19> inverse_factorials() {
  std::array<double, 19> a{};
  double f = 1.0;
  for (int j = 0; j < 19; ++j) {
    if (j > 0) f *= j;
    a[j] = 1.0 / f;
  }
  return a;
}
constexpr std::array<double, 19> kInverseFactorial = inverse_factorials();

// cosh u at the nodes u = m + δ of one panel of width du about its middle m (em = e^m): cosh m
// C(δ) + sinh m S(δ), C and S the Taylor series of cosh δ and sinh δ to δ¹⁸ and δ¹⁷ (|δ| ≤ du/2 ≤
// 1: the next terms below 1e-17; sinh m from e^m is exact to ~1e-16 cosh m, as the sum needs),
// a loop the compiler vectorises; std::cosh per node for panels wider than 2 (panel_width > 2).
void panel_cosh(const Rules& rule, double em, double du, double* ch) {
  const int n = static_cast<int>(rule.x.size());
  const double cm = 0.5 * (em + 1.0 / em), sm = 0.5 * (em - 1.0 / em);
  if (du > 2.0) {
    const double m = std::log(em);
    for (int i = 0; i < n; ++i) ch[i] = std::cosh(m + du * (rule.x[i] - 0.5));
    return;
  }
#pragma omp simd
  for (int i = 0; i < n; ++i) {
    const double d = du * (rule.x[i] - 0.5), d2 = d * d;
    double c = kInverseFactorial[18], s = kInverseFactorial[17];
    for (int j = 8; j >= 0; --j) c = c * d2 + kInverseFactorial[2 * j];
    for (int j = 7; j >= 0; --j) s = s * d2 + kInverseFactorial[2 * j + 1];
    ch[i] = cm * c + sm * (s * d);
  }
}

// e^{asinh x} = x + √(x² + 1) (for x < 0 its reciprocal's form, without cancellation; 2x and
// 1/(2|x|) beyond |x| = 1e8).
double exp_asinh(double x) {
  const double a = std::abs(x), v = a > 1e8 ? 2.0 * a : a + std::sqrt(a * a + 1.0);
  return x < 0.0 ? 1.0 / v : v;
}

// The Gauss–Legendre panels of [u1, u2], u = asinh x, x from x1 to x2, of width ≤ rule.width,
// with cosh u at their nodes: calls f(ch, du) per panel (angle_points values). From E = e^u at
// the ends: u2 − u1 = log(E2/E1), a panel's middle e^m = √(E1 E2) for one panel, E1 e^{(p+½)du}
// else (one logarithm per edge instead of two asinh and an exp per panel).
template <class F>
void cosh_panels(const Rules& rule, double x1, double x2, F&& f) {
  const double e1 = exp_asinh(x1), e2 = exp_asinh(x2), ratio = e2 / e1;
  const double span = std::isfinite(ratio) ? std::log(ratio) : std::log(e2) - std::log(e1);
  const int panels = std::max(1, static_cast<int>(std::ceil(span / rule.width)));
  const double du = span / panels;
  double ch[kMaxAnglePoints];
  for (int p = 0; p < panels; ++p) {
    panel_cosh(rule, panels == 1 ? std::sqrt(e1) * std::sqrt(e2) : e1 * std::exp((p + 0.5) * du),
               du, ch);
    f(ch, du);
  }
}

// The wedge of one edge seen from the foot p of y (in-plane distance |p_e| > 0 to the edge's
// line, t1 < t2 its ends along it), polar about p, T(u) = √(p_e² cosh²u + h²), θ = gd(u):
//   W_A = ∫ [Φ_A(T) − Φ_A(|h|)] dθ = ∫ ∫₀^R G(r)/r³ s ds dθ
//   W_B = ∫ [K₁(T) − K₁(|h|)] dθ   = ∫ ∫₀^R k(r) s ds dθ
// (dθ = du / cosh u). α = 4: Φ_A and K₁'s closed forms inline, the nodes' loop vectorised.
void edge_wedge(const Radial& k, const Rules& rule, double pe, double h, double t1, double t2,
                bool want_a, bool want_b, double* wa, double* wb) {
  const double ah = std::abs(h), p2 = pe * pe, h2 = h * h;
  const double fa = want_a ? k.phi_a(ah) : 0.0, fb = want_b ? k.k1(ah) : 0.0;
  const int n = static_cast<int>(rule.x.size());
  const double* w = rule.w.data();
  const double eps = k.eps, ie = 1.0 / eps;
  double sa = 0.0, sb = 0.0;
  cosh_panels(rule, t1 / pe, t2 / pe, [&](const double* ch, double du) {
    if (!k.four) {
      for (int i = 0; i < n; ++i) {
        const double T = std::sqrt(p2 * ch[i] * ch[i] + h2), f = du * w[i] / ch[i];
        if (want_a) sa += f * (k.phi_a(T) - fa);
        if (want_b) sb += f * (k.k1(T) - fb);
      }
      return;
    }
    if (want_a) {  // Φ_A = −(T + ε/2)/(3ε (T + ε)²): [Φ_A(T) − fa]/cosh u by one division
#pragma omp simd reduction(+ : sa)
      for (int i = 0; i < n; ++i) {
        const double T = std::sqrt(p2 * ch[i] * ch[i] + h2), v = T + eps, v2 = v * v;
        sa += du * w[i] * (-(T + 0.5 * eps) - 3.0 * eps * fa * v2) / (3.0 * eps * v2 * ch[i]);
      }
    }
    if (want_b) {  // K₁ = z²(3 + z)/(6ε²(1 + z)³), z = T/ε: likewise
#pragma omp simd reduction(+ : sb)
      for (int i = 0; i < n; ++i) {
        const double z = std::sqrt(p2 * ch[i] * ch[i] + h2) * ie, v = 1.0 + z, v3 = v * v * v;
        sb += du * w[i] * (z * z * (3.0 + z) * ie * ie - 6.0 * v3 * fb) / (6.0 * v3 * ch[i]);
      }
    }
  });
  *wa = sa;
  *wb = sb;
}

// E = ∫_{t1}^{t2} K₁(√(t² + q²)) dt along an edge's line (t from the foot of y on it, q the
// distance of y to the line): t = q sinh u, so K₁(q cosh u) q cosh u du; for q = 0, on each
// side of t = 0, t = ε sinh u.
double edge_line(const Radial& k, const Rules& rule, double q, double t1, double t2) {
  double s = 0.0;
  if (q > 0.0) {
    const int n = static_cast<int>(rule.x.size());
    const double* w = rule.w.data();
    const double ie = 1.0 / k.eps;
    cosh_panels(rule, t1 / q, t2 / q, [&](const double* ch, double du) {
      if (!k.four) {
        for (int i = 0; i < n; ++i) s += du * w[i] * k.k1(q * ch[i]) * q * ch[i];
        return;
      }
#pragma omp simd reduction(+ : s)
      for (int i = 0; i < n; ++i) {  // K₁ = z²(3 + z)/(6ε²(1 + z)³), z = r/ε
        const double r = q * ch[i], z = r * ie, v = 1.0 + z;
        s += du * w[i] * r * z * z * (3.0 + z) * ie * ie / (6.0 * v * v * v);
      }
    });
    return s;
  }
  auto side = [&](double a, double b) {  // ∫_a^b K₁(t) dt, 0 ≤ a < b
    panel_rule(
        rule.x, rule.w, rule.width, std::asinh(a / k.eps), std::asinh(b / k.eps),
        [&](double u, double wt) { s += wt * k.k1(k.eps * std::sinh(u)) * k.eps * std::cosh(u); });
  };
  if (t2 <= 0.0)
    side(-t2, -t1);
  else if (t1 >= 0.0)
    side(t1, t2);
  else {
    side(0.0, -t1);
    side(0.0, t2);
  }
  return s;
}

}  // namespace

EdgeFrame edge_frame(const Triangle& t, const double* y) {
  EdgeFrame f;
  double d[3][3];
  for (int a = 0; a < 3; ++a)
    for (int i = 0; i < 3; ++i) d[a][i] = t.v[a][i] - y[i];
  f.h = dot(t.n, d[0]);
  for (int e = 0; e < 3; ++e) {
    f.pe[e] = dot(t.nu[e], d[e]);  // ν ⊥ n: the foot's distance equals y's
    f.t1[e] = dot(t.tau[e], d[e]);
  }
  return f;
}

// Near triangle, polar rule: A = ∫_t G(r)/r³ dA = Σ_e sign(p_e) W_A,e, likewise B = ∫_t k dA;
// the edges in the bit mask skip left out (their wedges cancel against a coplanar neighbour's).
void near_pair(const Triangle& t, const Radial& k, const Rules& rule, const EdgeFrame& f,
               bool want_a, bool want_b, double* a, double* b, int skip) {
  double sa = 0.0, sb = 0.0;
  for (int e = 0; e < 3; ++e) {
    if (f.pe[e] == 0.0 || (skip >> e & 1)) continue;  // a degenerate or cancelled wedge
    double wa, wb;
    edge_wedge(k, rule, std::abs(f.pe[e]), f.h, f.t1[e], f.t1[e] + t.len[e], want_a, want_b, &wa,
               &wb);
    const double sg = f.pe[e] > 0.0 ? 1.0 : -1.0;
    sa += sg * wa;
    sb += sg * wb;
  }
  *a = sa;
  *b = sb;
}

// The signed solid angle of a triangle seen from y, ω_t = h_t ∫_t r^−3 dA (Van Oosterom and
// Strackee): with a, b, c = v_i − y, tan(ω/2) = a·(b × c) / (|a||b||c| + (a·b)|c| + (a·c)|b| +
// (b·c)|a|); positive when y is on the inner side.
double solid_angle(const Triangle& t, const double* y) {
  double a[3], b[3], c[3], bc[3];
  for (int i = 0; i < 3; ++i) {
    a[i] = t.v[0][i] - y[i];
    b[i] = t.v[1][i] - y[i];
    c[i] = t.v[2][i] - y[i];
  }
  cross(b, c, bc);
  const double la = std::sqrt(dot(a, a)), lb = std::sqrt(dot(b, b)), lc = std::sqrt(dot(c, c));
  const double den = la * lb * lc + dot(a, b) * lc + dot(a, c) * lb + dot(b, c) * la;
  return 2.0 * std::atan2(dot(a, bc), den);
}

// Whether y lies on the near triangle t (|h| and the foot's distance outside its edges below
// 1e-12 of its size).
bool on_triangle(const Triangle& t, const EdgeFrame& f) {
  const double tol = 1e-12 * (t.len[0] + t.len[1] + t.len[2]);
  return std::abs(f.h) <= tol && f.pe[0] >= -tol && f.pe[1] >= -tol && f.pe[2] >= -tol;
}

// ∫_t k λ_a dA for the three corners a of a near triangle: λ_a(p) B + ∇λ_a · M with the
// first moment M = ∫_t k (x − p) dA = ∮ K₁(r) ν dl (∇_∥K₁(r) = k(r)(x − p)).
void near_moments(const Triangle& t, const Radial& k, const Rules& rule, const EdgeFrame& f,
                  const double* y, double c[3]) {
  double a_unused, b;
  near_pair(t, k, rule, f, false, true, &a_unused, &b);
  double m[3] = {0.0, 0.0, 0.0};
  for (int e = 0; e < 3; ++e) {
    const double q = std::sqrt(f.pe[e] * f.pe[e] + f.h * f.h);
    const double line = edge_line(k, rule, q, f.t1[e], f.t1[e] + t.len[e]);
    for (int i = 0; i < 3; ++i) m[i] += line * t.nu[e][i];
  }
  for (int a = 0; a < 3; ++a) {
    const double* v = t.v[(a + 1) % 3];  // λ_a(v_{a+1}) = 0, ∇λ_a ⊥ n: λ_a(p) = ∇λ_a·(y − v)
    const double d[3] = {y[0] - v[0], y[1] - v[1], y[2] - v[2]};
    c[a] = dot(t.glam[a], d) * b + dot(t.glam[a], m);
  }
}

}  // namespace softhd::detail::body
