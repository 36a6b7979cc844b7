#include "body_integral.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

#include "../common/decimal.hpp"
#include "../common/gauss_legendre.hpp"
#include "../common/surface_bvh.hpp"
#include "softhd/error.hpp"
#include "softhd/parallel.hpp"

namespace softhd::detail {

namespace {

using Triangle = BodyIntegral::Triangle;

// Dunavant's symmetric 16-point rule on the triangle (degree 8; D. A. Dunavant, Int. J. Numer.
// Meth. Eng. 21 (1985) 1129–1148; positive weights, points inside), barycentric coordinates and
// weights relative to the area: the centroid; orbits (a, a, 1 − 2a); one orbit of the
// permutations of (a, b, 1 − a − b). Checked exact to 2e-15 on every monomial up to degree 8.
constexpr int kFarPoints = 16;

struct FarRule {
  double lam[kFarPoints][3];
  double corner[3][kFarPoints];  // lam by corner (the vectorised loops)
  double w[kFarPoints];
  FarRule() {
    int q = 0;
    auto put = [&](double l0, double l1, double l2, double wt) {
      lam[q][0] = l0;
      lam[q][1] = l1;
      lam[q][2] = l2;
      w[q++] = wt;
    };
    put(1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0, 0.144315607677787);
    const double a[3] = {0.459292588292723, 0.170569307751760, 0.050547228317031};
    const double wa[3] = {0.095091634267285, 0.103217370534718, 0.032458497623198};
    for (int o = 0; o < 3; ++o) {
      const double b = 1.0 - 2.0 * a[o];
      put(b, a[o], a[o], wa[o]);
      put(a[o], b, a[o], wa[o]);
      put(a[o], a[o], b, wa[o]);
    }
    const double c[3] = {0.008394777409958, 0.263112829634638, 0.728492392955404};
    const int perm[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
    for (const auto& p : perm) put(c[p[0]], c[p[1]], c[p[2]], 0.027230314174435);
    for (int i = 0; i < kFarPoints; ++i)
      for (int a = 0; a < 3; ++a) corner[a][i] = lam[i][a];
  }
};

const FarRule& far_rule() {
  static const FarRule rule;
  return rule;
}

// Radon's symmetric 7-point rule (degree 5; fe/quadrature.cpp's table), for the triangles
// beyond kCoarseRatio × near_ratio radii: the centroid 9/40, the orbits (a, a, 1 − 2a) with
// a = (6 ∓ √15)/21, weights (155 ∓ √15)/1200; padded to 8 lanes (the centroid, weight 0).
constexpr int kCoarsePoints = 8;
constexpr double kCoarseRatio = 4.0;

struct CoarseRule {
  double lam[kCoarsePoints][3];
  double corner[3][kCoarsePoints];  // lam by corner
  double w[kCoarsePoints];
  CoarseRule() {
    const double s15 = std::sqrt(15.0);
    const double a[2] = {(6.0 - s15) / 21.0, (6.0 + s15) / 21.0};
    const double wa[2] = {(155.0 - s15) / 1200.0, (155.0 + s15) / 1200.0};
    for (int q : {0, 7}) {
      lam[q][0] = lam[q][1] = lam[q][2] = 1.0 / 3.0;
      w[q] = q == 0 ? 9.0 / 40.0 : 0.0;
    }
    for (int o = 0; o < 2; ++o)
      for (int v = 0; v < 3; ++v) {
        double* L = lam[1 + 3 * o + v];
        L[0] = L[1] = L[2] = a[o];
        L[v] = 1.0 - 2.0 * a[o];
        w[1 + 3 * o + v] = wa[o];
      }
    for (int i = 0; i < kCoarsePoints; ++i)
      for (int a = 0; a < 3; ++a) corner[a][i] = lam[i][a];
  }
};

const CoarseRule& coarse_rule() {
  static const CoarseRule rule;
  return rule;
}

// The points of a far rule on one triangle, by coordinate, weights times the area.
struct FarPoints {
  const double *x, *y, *z, *w;
  const double *l0, *l1, *l2;  // the barycentric coordinates λ_0, λ_1, λ_2 of the points
  int n;
};

// The 16-point rule within (kCoarseRatio · near_ratio · R_t)² = t.far2 of y, else the 7-point.
FarPoints far_points(const Triangle& t, double d2) {
  if (d2 < t.far2) {
    const FarRule& r = far_rule();
    return {t.qx, t.qy, t.qz, t.wq, r.corner[0], r.corner[1], r.corner[2], kFarPoints};
  }
  const CoarseRule& r = coarse_rule();
  return {t.cx, t.cy, t.cz, t.cw, r.corner[0], r.corner[1], r.corner[2], kCoarsePoints};
}

// d_m(z) = ε^−(m+1) ∫_ε^{ε(1+z)} w^m dw: log(1 + z) for m = −1, else ((1 + z)^{m+1} − 1)/(m+1)
// (log1p/expm1: no cancellation for small z).
double power_primitive(double m, double z) {
  if (m == -1.0) return std::log1p(z);
  return std::expm1((m + 1.0) * std::log1p(z)) / (m + 1.0);
}

// Σ_k c_k z^{k+j}/(k+j), c_k = binom(−α, k): ε^{α−j} ∫₀^{εz} u^{j−1}(u + ε)^−α du for z < 1.
double binomial_series(double alpha, int j, double z) {
  double c = 1.0, zk = std::pow(z, j), sum = 0.0;
  for (int k = 0; k < 200; ++k) {
    const double term = c * zk / (k + j);
    sum += term;
    if (std::abs(term) <= 1e-17 * std::abs(sum)) break;
    c *= -(alpha + k) / (k + 1.0);
    zk *= z;
  }
  return sum;
}

// The kernel's radial functions, z = r/ε, w = r + ε. Below z = 1/4 the primitives' closed
// forms cancel to (z³/3)/(3/z²) and the binomial series is used instead.
struct Radial {
  double eps, alpha;
  bool four;  // α = 4: the closed forms of docs/formulation.md §2.8
  static constexpr double kSeries = 0.25;
  // From α = 3.5 the far rule integrates G's tail H = (G∞ − G)/r³ only, G∞ by solid angles.
  static constexpr double kCoulomb = 3.5;

  // G∞ = ∫₀^∞ u²(u + ε)^−α du = 2 ε^{3−α}/((α − 1)(α − 2)(α − 3)) for α > 3
  double g_inf;

  Radial(double epsilon, double a)
      : eps(epsilon),
        alpha(a),
        four(a == 4.0),
        g_inf(a > 3.0 ? 2.0 * std::pow(epsilon, 3.0 - a) / ((a - 1.0) * (a - 2.0) * (a - 3.0))
                      : 0.0) {}
  // H(r) = (G∞ − G(r))/r³, G∞ − G(r) = ∫_r^∞ u²(u + ε)^−α du
  //      = ε^{3−α} [W^{3−α}/(α − 3) − 2W^{2−α}/(α − 2) + W^{1−α}/(α − 1)],  W = 1 + r/ε;
  // α = 4: (3W² − 3W + 1)/(3ε W³)
  double tail_over_r3(double r) const {
    const double W = 1.0 + r / eps, r3 = r * r * r;
    if (four) return (3.0 * W * W - 3.0 * W + 1.0) / (3.0 * eps * W * W * W * r3);
    const double s = std::pow(W, 3.0 - alpha) / (alpha - 3.0) -
                     2.0 * std::pow(W, 2.0 - alpha) / (alpha - 2.0) +
                     std::pow(W, 1.0 - alpha) / (alpha - 1.0);
    return std::pow(eps, 3.0 - alpha) * s / r3;
  }

  // k(r) = (r + ε)^−α
  double kernel(double r) const {
    const double s = 1.0 / (r + eps);
    if (four) return (s * s) * (s * s);
    return std::pow(s, alpha);
  }
  // G(r) = ∫₀^r u²(u + ε)^−α du = ε^{3−α} [d_{2−α} − 2 d_{1−α} + d_{−α}](z); α = 4: r³/(3ε w³)
  double g(double r) const {
    const double z = r / eps;
    if (four) return z * z * z / (3.0 * eps * (1.0 + z) * (1.0 + z) * (1.0 + z));
    const double s = z < kSeries
                         ? binomial_series(alpha, 3, z)
                         : power_primitive(2.0 - alpha, z) - 2.0 * power_primitive(1.0 - alpha, z) +
                               power_primitive(-alpha, z);
    return std::pow(eps, 3.0 - alpha) * s;
  }
  // G(r)/r³; α = 4: 1/(3ε (r + ε)³)
  double g_over_r3(double r) const {
    if (four) {
      const double s = 1.0 / (r + eps);
      return s * s * s / (3.0 * eps);
    }
    return r > 0.0 ? g(r) / (r * r * r) : std::pow(eps, -alpha) / 3.0;
  }
  // K₁(r) = ∫₀^r s (s + ε)^−α ds = ε^{2−α} [d_{1−α} − d_{−α}](z)
  double k1(double r) const {
    const double z = r / eps;
    if (four) {  // 1/(6ε²) − 1/(2w²) + ε/(3w³) = z²(3 + z)/(6ε²(1 + z)³)
      const double w = 1.0 + z;
      return z * z * (3.0 + z) / (6.0 * eps * eps * w * w * w);
    }
    const double s = z < kSeries ? binomial_series(alpha, 2, z)
                                 : power_primitive(1.0 - alpha, z) - power_primitive(-alpha, z);
    return std::pow(eps, 2.0 - alpha) * s;
  }
  // Φ_A(r) = K₁(r) − G(r)/r, a primitive of r · G(r)/r³ (by parts); α = 4: −Ψ(r)/(3ε) + const,
  // Ψ(t) = 1/(t + ε) − ε/(2(t + ε)²)
  double phi_a(double r) const {
    if (four) {
      const double s = 1.0 / (r + eps);
      return -(s - 0.5 * eps * s * s) / (3.0 * eps);
    }
    return k1(r) - (r > 0.0 ? g(r) / r : 0.0);
  }
};

// The Gauss–Legendre panels of [u1, u2] of width ≤ panel_width: calls f(u, weight).
template <class F>
void panel_rule(const std::vector<double>& x, const std::vector<double>& w, double width, double u1,
                double u2, F&& f) {
  const int panels = std::max(1, static_cast<int>(std::ceil((u2 - u1) / width)));
  const double du = (u2 - u1) / panels;
  for (int p = 0; p < panels; ++p) {
    const double a = u1 + p * du;
    for (std::size_t i = 0; i < x.size(); ++i) f(a + du * x[i], du * w[i]);
  }
}

struct Rules {
  const std::vector<double>& x;
  const std::vector<double>& w;
  double width;
};

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

double dot(const double* a, const double* b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

void cross(const double* a, const double* b, double* c) {
  c[0] = a[1] * b[2] - a[2] * b[1];
  c[1] = a[2] * b[0] - a[0] * b[2];
  c[2] = a[0] * b[1] - a[1] * b[0];
}

// Signed distance of y's foot to edge e's line (> 0 on the triangle's side), its ends along
// the line, and h_t = n·(v_0 − y).
struct EdgeFrame {
  double h;
  double pe[3], t1[3];
};

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
               bool want_a, bool want_b, double* a, double* b, int skip = 0) {
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

// A far triangle's share of J by its far rule, h_t Σ_q W_q G(r_q)/r_q³, in two parts
// (α ≥ 3.5): with G = G∞ − r³ H, the tail −h_t Σ_q W_q H(r_q) and the point-charge part G∞ ω_t,
// ω_t = h_t ∫_t r^−3 dA the triangle's signed solid angle, of which only the rule's estimate
// h_t Σ_q W_q r_q^−3 is returned (in *omega): evaluate replaces the far triangles' sum of them
// by its exact value. (Over a closed surface seen from outside the terms G∞ ω_t cancel to a J
// smaller by up to 1/(εJ); the rule's error on them would not.) α < 3.5: the plain sum, *omega 0.
double far_value(const FarPoints& t, const Radial& k, const double* y, double h, double* omega) {
  double s = 0.0, c = 0.0;
  if (k.four) {  // H(r) = (3W² − 3W + 1)/(3ε W³ r³), W = 1 + r/ε
    const double inv_eps = 1.0 / k.eps, y0 = y[0], y1 = y[1], y2 = y[2];
    const double *px = t.x, *py = t.y, *pz = t.z, *pw = t.w;
    const int n = t.n;
#pragma omp simd reduction(+ : s, c)
    for (int q = 0; q < n; ++q) {
      const double dx = px[q] - y0, dy = py[q] - y1, dz = pz[q] - y2;
      const double r = std::sqrt(dx * dx + dy * dy + dz * dz), W = 1.0 + r * inv_eps;
      const double W3 = W * W * W, wi = pw[q] / (r * r * r * W3);  // one division
      s += wi * (3.0 * W * W - 3.0 * W + 1.0);
      c += wi * W3;
    }
    *omega = h * c;
    return -h * s * inv_eps / 3.0;
  }
  const bool coulomb = k.alpha >= Radial::kCoulomb;
  for (int q = 0; q < t.n; ++q) {
    const double dx = t.x[q] - y[0], dy = t.y[q] - y[1], dz = t.z[q] - y[2];
    const double r = std::sqrt(dx * dx + dy * dy + dz * dz);
    s += t.w[q] * (coulomb ? k.tail_over_r3(r) : k.g_over_r3(r));
    if (coulomb) c += t.w[q] / (r * r * r);
  }
  *omega = h * c;
  return coulomb ? -h * s : h * s;
}

// The far triangles' exact Σ ω_t from the rule's estimate: off the surface the total solid angle
// Σ_all ω_t is 4π × the winding number, so Σ_far ω_t = 4π round((S_near + S_est)/4π) − S_near
// (the estimate's error, ~1e-6 of 4π, is far below 2π). On the surface the total is the
// interior angle at y (2π on a face): the estimate stays, and J ~ G∞ there is not small.
double far_solid_angle(double near_sum, double estimate, bool on_surface) {
  if (on_surface) return estimate;
  const double four_pi = 4.0 * 3.14159265358979323846;
  return four_pi * std::round((near_sum + estimate) / four_pi) - near_sum;
}

// Whether y lies on the near triangle t (|h| and the foot's distance outside its edges below
// 1e-12 of its size).
bool on_triangle(const Triangle& t, const EdgeFrame& f) {
  const double tol = 1e-12 * (t.len[0] + t.len[1] + t.len[2]);
  return std::abs(f.h) <= tol && f.pe[0] >= -tol && f.pe[1] >= -tol && f.pe[2] >= -tol;
}

// B = ∫_t k dA by the far rule.
double far_kernel(const FarPoints& t, const Radial& k, const double* y) {
  double s = 0.0;
  if (k.four) {
    const double eps = k.eps, y0 = y[0], y1 = y[1], y2 = y[2];
    const double *px = t.x, *py = t.y, *pz = t.z, *pw = t.w;
    const int n = t.n;
#pragma omp simd reduction(+ : s)
    for (int q = 0; q < n; ++q) {
      const double dx = px[q] - y0, dy = py[q] - y1, dz = pz[q] - y2;
      const double u = 1.0 / (std::sqrt(dx * dx + dy * dy + dz * dz) + eps);
      s += pw[q] * (u * u) * (u * u);
    }
    return s;
  }
  for (int q = 0; q < t.n; ++q) {
    const double dx = t.x[q] - y[0], dy = t.y[q] - y[1], dz = t.z[q] - y[2];
    s += t.w[q] * k.kernel(std::sqrt(dx * dx + dy * dy + dz * dz));
  }
  return s;
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

// ∫_t k λ_a dA by the far rule.
void far_moments(const FarPoints& t, const Radial& k, const double* y, double c[3]) {
  double c0 = 0.0, c1 = 0.0, c2 = 0.0;
  const double eps = k.eps, y0 = y[0], y1 = y[1], y2 = y[2];
  const double *px = t.x, *py = t.y, *pz = t.z, *pw = t.w, *l0 = t.l0, *l1 = t.l1, *l2 = t.l2;
  const int n = t.n;
  if (k.four) {
#pragma omp simd reduction(+ : c0, c1, c2)
    for (int q = 0; q < n; ++q) {
      const double dx = px[q] - y0, dy = py[q] - y1, dz = pz[q] - y2;
      const double u = 1.0 / (std::sqrt(dx * dx + dy * dy + dz * dz) + eps);
      const double kw = pw[q] * (u * u) * (u * u);
      c0 += kw * l0[q];
      c1 += kw * l1[q];
      c2 += kw * l2[q];
    }
  } else {
    for (int q = 0; q < n; ++q) {
      const double dx = px[q] - y0, dy = py[q] - y1, dz = pz[q] - y2;
      const double kw = pw[q] * k.kernel(std::sqrt(dx * dx + dy * dy + dz * dz));
      c0 += kw * l0[q];
      c1 += kw * l1[q];
      c2 += kw * l2[q];
    }
  }
  c[0] = c0;
  c[1] = c1;
  c[2] = c2;
}

// far_value and far_kernel together for α = 4 (B = ∫_t k dA into *b): per point one square root
// and one division, D = 1/(r W), 1/(r³W³) = D³, k = (εW)^−4 = (D r/ε)⁴.
double far_value_kernel(const FarPoints& t, double eps, const double* y, double h, double* omega,
                        double* b) {
  double s = 0.0, c = 0.0, kb = 0.0;
  const double inv_eps = 1.0 / eps, y0 = y[0], y1 = y[1], y2 = y[2];
  const double *px = t.x, *py = t.y, *pz = t.z, *pw = t.w;
  const int n = t.n;
#pragma omp simd reduction(+ : s, c, kb)
  for (int q = 0; q < n; ++q) {
    const double dx = px[q] - y0, dy = py[q] - y1, dz = pz[q] - y2;
    const double r = std::sqrt(dx * dx + dy * dy + dz * dz), W = 1.0 + r * inv_eps;
    const double D = 1.0 / (r * W), D3 = D * D * D, u = D * r * inv_eps, wi = pw[q] * D3;
    s += wi * (3.0 * W * W - 3.0 * W + 1.0);
    c += wi * W * W * W;
    kb += pw[q] * (u * u) * (u * u);
  }
  *omega = h * c;
  *b = kb;
  return -h * s * inv_eps / 3.0;
}

// |y − c_t|²: near below t.near2 (the polar rule), the 16-point rule below t.far2.
double distance2(const Triangle& t, const double* y) {
  const double dx = y[0] - t.c[0], dy = y[1] - t.c[1], dz = y[2] - t.c[2];
  return dx * dx + dy * dy + dz * dz;
}

// ∫_t k λ_a dA for the three corners of any triangle: the polar rule near y, the far rule else.
void corner_moments(const Triangle& tri, const Radial& k, const Rules& rule, const double* y,
                    double c[3]) {
  const double d2 = distance2(tri, y);
  if (d2 < tri.near2)
    near_moments(tri, k, rule, edge_frame(tri, y), y, c);
  else
    far_moments(far_points(tri, d2), k, y, c);
}

// One point's sums over the triangles: J without the far solid angles' G∞ part, the near
// triangles' exact solid angles and the far ones' estimate, ∂J/∂y, S = ∫_∂Ω k dA (with the
// gradient), and the tree's error bounds of J, of the far solid angles and of g and S.
struct PointSums {
  double J = 0.0, near_omega = 0.0, far_omega = 0.0, g[3] = {0.0, 0.0, 0.0}, S = 0.0;
  double err_j = 0.0, err_omega = 0.0, err_g = 0.0;
  bool on_surface = false;
};

// One triangle's share by its rules (polar when near, else the far rule).
void direct_triangle(const Triangle& t, const Radial& k, const Rules& rule, const double* y,
                     bool want_b, bool coulomb, PointSums* s, int skip = 0) {
  double b = 0.0;
  const double d2 = distance2(t, y);
  if (d2 < t.near2) {
    const EdgeFrame f = edge_frame(t, y);
    double a;
    near_pair(t, k, rule, f, true, want_b, &a, &b, skip);
    s->J += f.h * a;  // h_t ∫_t G(r)/r³ dA
    if (coulomb) {
      s->near_omega += solid_angle(t, y);
      s->on_surface = s->on_surface || on_triangle(t, f);
    }
  } else {
    const double h =
        t.n[0] * (t.v[0][0] - y[0]) + t.n[1] * (t.v[0][1] - y[1]) + t.n[2] * (t.v[0][2] - y[2]);
    const FarPoints p = far_points(t, d2);
    double omega;
    if (want_b && k.four) {
      s->J += far_value_kernel(p, k.eps, y, h, &omega, &b);
    } else {
      s->J += far_value(p, k, y, h, &omega);
      if (want_b) b = far_kernel(p, k, y);
    }
    s->far_omega += omega;
  }
  if (want_b) {
    for (int i = 0; i < 3; ++i) s->g[i] -= b * t.n[i];  // −n_t ∫_t k dA
    s->S += b;
  }
}

// The edges of tris[j] whose wedges cancel at y: both it and the coplanar neighbour across the
// edge near y (so both summed one by one by the polar rule: cluster_bounds), the foot and h the
// same for both, the edge traversed the other way (W_e cancels, in J's h_t W and in B's n_t W
// alike).
int cancelled_edges(const std::vector<Triangle>& tris, int j, const double* y) {
  int skip = 0;
  for (int e = 0; e < 3; ++e) {
    const int s = tris[j].twin[e];
    if (s >= 0 && distance2(tris[s], y) < tris[s].near2) skip |= 1 << e;
  }
  return skip;
}

// The triangles tris[begin, end) one by one (a leaf of the tree, or all of them).
void direct_range(const std::vector<Triangle>& tris, int begin, int end, const Radial& k,
                  const Rules& rule, const double* y, bool want_b, bool coulomb, PointSums* s) {
  for (int j = begin; j < end; ++j) {
    const Triangle& t = tris[j];
    const int skip = distance2(t, y) < t.near2 ? cancelled_edges(tris, j, y) : 0;
    direct_triangle(t, k, rule, y, want_b, coulomb, s, skip);
  }
}

// The tree's expansions need ε ≤ kTreeX (|p − y| − ρ): the remainder bounds below sum the
// kernels' series in ε/r up to there.
constexpr double kTreeX = 0.05;

// C_H: the remainder of the second-order expansion of n·d H(|d|) (α = 4) is at most
// C_H ρ³/z⁶ per unit area, z = |p − y| − ρ ≥ ε/kTreeX. With x = ε/r, H = (1/3) Σ_{m=1}^{3}
// r^−4 (1 + x)^−m = Σ_k a_k ε^k r^−(4+k), |a_k| ≤ (1/3) Σ_m C(m+k−1, k); each term
// d r^−(4+k) = −∇ r^−(2+k)/(2 + k), and the order-2 remainder of n·∇f at s is
// D⁴f(ξ)[n, s, s, s]/6, by polarisation at most max_u |D⁴f[u⁴]| |s|³/6, and for f = r^−2λ the
// Gegenbauer expansion |z + t u|^−2λ = Σ_n C_n^λ(cos) tⁿ |z|^−(2λ+n), |C_n^λ| ≤ C(n + 2λ − 1, n),
// gives |D⁴f[u⁴]| ≤ 4! C(5 + k, 4)/|z|^(6+k). So C_H = Σ_k |a_k| kTreeX^k 4 C(5+k, 4)/(2 + k).
// C_K likewise for the scalar k = (r + ε)^−4 = Σ_k C(k+3, 3)(−ε)^k r^−(4+k) at order 2:
// D³f[s³]/6 ≤ C(6 + k, 3) |s|³/|z|^(7+k), so C_K = Σ_k C(k+3, 3) C(6+k, 3) kTreeX^k. The solid
// angle's n·d/r³ = −n·∇(1/r): 4 ρ³/z⁵ (Legendre, |P_4| ≤ 1).
struct TreeConstants {
  double c_h = 0.0, c_k = 0.0;
  TreeConstants() {
    auto binom = [](int n, int k) {
      double c = 1.0;
      for (int i = 1; i <= k; ++i) c = c * (n - k + i) / i;
      return c;
    };
    double xk = 1.0;
    for (int k = 0; k < 80; ++k, xk *= kTreeX) {
      const double a = (binom(k, k) + binom(k + 1, k) + binom(k + 2, k)) / 3.0;
      c_h += a * xk * 4.0 * binom(5 + k, 4) / (2.0 + k);
      c_k += binom(k + 3, 3) * binom(6 + k, 3) * xk;
    }
  }
};

const TreeConstants& tree_constants() {
  static const TreeConstants c;
  return c;
}

// The vector kernel d g(r) contracted with a cluster's n-weighted moments to second order, d =
// p − y: g (d·M0) + g tr M1 + g1 dᵀM1 d + ½ [g1 q·d + g2 Σ d_i d_j d_k M2_ijk], with g1 = g′/r
// and g2 = g1′/r.
double contract_vector(const BodyIntegral::Cluster& c, const double* d, double g, double g1,
                       double g2) {
  double dm1d = 0.0, d3 = 0.0;
  for (int i = 0; i < 3; ++i) {
    double row = 0.0;
    for (int j = 0; j < 3; ++j) {
      row += c.m1[3 * i + j] * d[j];
      double inner = 0.0;
      for (int k = 0; k < 3; ++k) inner += c.m2[9 * i + 3 * j + k] * d[k];
      d3 += d[i] * d[j] * inner;
    }
    dm1d += d[i] * row;
  }
  return g * (dot(d, c.m0) + c.tr1) + g1 * dm1d + 0.5 * (g1 * dot(c.q, d) + g2 * d3);
}

// A cluster's share by its expansions: the tail −Σ n·d H (into J), the solid angles' estimate,
// and with want_b g −= f M0 + f1 M1 d + ½ [f1 v + f2 M2 : d d] and S += f A + f1 m1·d +
// ½ [f1 tr m2 + f2 dᵀm2 d], f = (r + ε)^−4 (α = 4: H = (1/3)[r⁻³w⁻¹ + r⁻²w⁻² + r⁻¹w⁻³],
// w = r + ε; H′/r = −[r⁻⁵w⁻¹ + r⁻⁴w⁻² + r⁻³w⁻³ + r⁻²w⁻⁴]; (H′/r)′/r = 5[r⁻⁷w⁻¹ + r⁻⁶w⁻² +
// r⁻⁵w⁻³ + r⁻⁴w⁻⁴] + 4r⁻³w⁻⁵; f1 = −4r⁻¹w⁻⁵, f2 = 4r⁻³w⁻⁵ + 20r⁻²w⁻⁶).
void cluster_share(const BodyIntegral::Cluster& c, double eps, const double* y, bool want_b,
                   PointSums* s) {
  const double d[3] = {c.p[0] - y[0], c.p[1] - y[1], c.p[2] - y[2]};
  const double r = std::sqrt(dot(d, d)), ir = 1.0 / r, iw = 1.0 / (r + eps);
  const double ir2 = ir * ir, iw2 = iw * iw, ir3 = ir2 * ir, iw3 = iw2 * iw;
  const double H = (ir3 * iw + ir2 * iw2 + ir * iw3) / 3.0;
  const double h1 = -ir2 * (ir3 * iw + ir2 * iw2 + ir * iw3 + iw2 * iw2);
  const double h2 =
      5.0 * ir3 * ir * (ir3 * iw + ir2 * iw2 + ir * iw3 + iw2 * iw2) + 4.0 * ir3 * iw2 * iw3;
  s->J -= contract_vector(c, d, H, h1, h2);
  const double ir5 = ir3 * ir2;
  s->far_omega += contract_vector(c, d, ir3, -3.0 * ir5, 15.0 * ir5 * ir2);
  if (!want_b) return;
  const double f = iw2 * iw2, f1 = -4.0 * ir * f * iw,
               f2 = 4.0 * ir3 * f * iw + 20.0 * ir2 * f * iw2;
  for (int i = 0; i < 3; ++i) {
    double m1d = 0.0, m2dd = 0.0;
    for (int j = 0; j < 3; ++j) {
      m1d += c.m1[3 * i + j] * d[j];
      for (int k = 0; k < 3; ++k) m2dd += c.m2[9 * i + 3 * j + k] * d[j] * d[k];
    }
    s->g[i] -= f * c.m0[i] + f1 * m1d + 0.5 * (f1 * c.v[i] + f2 * m2dd);
  }
  double dm2d = 0.0;
  for (int j = 0; j < 3; ++j)
    for (int k = 0; k < 3; ++k) dm2d += d[j] * c.s2[3 * j + k] * d[k];
  s->S += f * c.area + f1 * dot(c.s1, d) + 0.5 * (f1 * c.tr2 + f2 * dm2d);
}

// A cluster's moments over its triangles order[begin, end) (the 16-point rule, exact for the
// quadratic moments), p its area-weighted centroid.
BodyIntegral::Cluster make_cluster(const std::vector<Triangle>& tris, const std::vector<int>& order,
                                   const BvhNode& node) {
  BodyIntegral::Cluster c{};
  c.left = node.left;
  c.begin = node.begin;
  c.end = node.end;
  double area = 0.0, p[3] = {0.0, 0.0, 0.0};
  for (int j = node.begin; j < node.end; ++j) {
    const Triangle& t = tris[order[j]];
    double a = 0.0;
    for (int q = 0; q < kFarPoints; ++q) a += t.wq[q];
    area += a;
    for (int i = 0; i < 3; ++i) p[i] += a * t.c[i];
  }
  for (int i = 0; i < 3; ++i) c.p[i] = p[i] / area;
  c.area = area;
  for (int j = node.begin; j < node.end; ++j) {
    const Triangle& t = tris[order[j]];
    for (int a = 0; a < 3; ++a) {
      const double e[3] = {t.v[a][0] - c.p[0], t.v[a][1] - c.p[1], t.v[a][2] - c.p[2]};
      c.rho = std::max(c.rho, std::sqrt(dot(e, e)));
    }
    c.reach = std::max(c.reach, std::sqrt(t.near2));
    for (int q = 0; q < kFarPoints; ++q) {
      const double sv[3] = {t.qx[q] - c.p[0], t.qy[q] - c.p[1], t.qz[q] - c.p[2]};
      const double w = t.wq[q];
      for (int i = 0; i < 3; ++i) {
        c.m0[i] += w * t.n[i];
        c.s1[i] += w * sv[i];
        for (int jj = 0; jj < 3; ++jj) {
          c.m1[3 * i + jj] += w * t.n[i] * sv[jj];
          c.s2[3 * i + jj] += w * sv[i] * sv[jj];
          for (int k = 0; k < 3; ++k) c.m2[9 * i + 3 * jj + k] += w * t.n[i] * sv[jj] * sv[k];
        }
      }
    }
  }
  for (int i = 0; i < 3; ++i) {
    c.tr1 += c.m1[4 * i];
    c.tr2 += c.s2[4 * i];
    for (int j = 0; j < 3; ++j) {
      c.v[i] += c.m2[9 * i + 4 * j];
      c.q[i] += 2.0 * c.m2[9 * j + 3 * j + i] + c.m2[9 * i + 4 * j];
    }
  }
  return c;
}

// The per-unit-area error budgets of one traversal: J's, the far solid angles' and g's (and S's);
// theta > 0 (a probe for a first guess of J and S): J's and g's budgets replaced by ρ ≤ θ z.
struct Budget {
  double j, omega, g, theta = 0.0;
};

// The probe's opening ratio (a guess only: its results are not used unless the check passes).
constexpr double kProbeTheta = 0.25;

// A cluster's remainder bounds per unit area at z = |p − y| − ρ (valid: z > 0, ε ≤ kTreeX z):
// J's tail C_H ρ³/z⁶, the solid angle's 4 ρ³/z⁵, and with the gradient k's C_K ρ³/z⁷. Taken only
// beyond its triangles' near radii (z ≥ reach, so |y − c_t| ≥ z: none of them near y): a triangle
// near y is always summed one by one (cancelled_edges relies on it).
struct Bounds {
  bool valid;
  double j, omega, g;
};

Bounds cluster_bounds(const BodyIntegral::Cluster& c, double eps, double z, bool want_b) {
  if (!(z > 0.0 && eps <= kTreeX * z && z >= c.reach)) return {false, 0.0, 0.0, 0.0};
  const TreeConstants& tc = tree_constants();
  const double r3 = c.rho * c.rho * c.rho, z2 = z * z, z5 = z2 * z2 * z;
  return {true, tc.c_h * r3 / (z5 * z), 4.0 * r3 / z5, want_b ? tc.c_k * r3 / (z5 * z2) : 0.0};
}

// Whether a cluster at z, its bounds e there, enters by its expansions under the budget
// (decreasing in z: fits at z implies fits at every larger z).
bool cluster_fits(const BodyIntegral::Cluster& c, const Bounds& e, double z, const Budget& budget) {
  if (!e.valid || e.omega > budget.omega) return false;
  return budget.theta > 0.0 ? c.rho <= budget.theta * z : e.j <= budget.j && e.g <= budget.g;
}

// A cluster's expansions into y's sums, e its bounds at y's distance.
void take_cluster(const BodyIntegral::Cluster& c, double eps, const double* y, bool want_b,
                  const Bounds& e, PointSums* s) {
  cluster_share(c, eps, y, want_b, s);
  s->err_j += c.area * e.j;
  s->err_omega += c.area * e.omega;
  s->err_g += c.area * e.g;
}

// One point's sums by the tree below the nodes `start` (tris: the triangles in the tree's
// order): a cluster enters by its expansions when they are valid (ρ < R, ε ≤ kTreeX (R − ρ)) and
// their remainder bounds per unit area fit the budget; a leaf that does not, triangle by triangle.
void traverse(const std::vector<BodyIntegral::Cluster>& clusters, const std::vector<Triangle>& tris,
              const Radial& k, const Rules& rule, const double* y, bool want_b,
              const Budget& budget, const std::vector<int>& start, PointSums* s) {
  int stack[2 * kBvhMaxDepth + 2];
  for (int root : start) {
    int top = 0;
    stack[top++] = root;
    while (top > 0) {
      const BodyIntegral::Cluster& c = clusters[stack[--top]];
      const double d[3] = {c.p[0] - y[0], c.p[1] - y[1], c.p[2] - y[2]};
      const double z = std::sqrt(dot(d, d)) - c.rho;
      const Bounds e = cluster_bounds(c, k.eps, z, want_b);
      if (cluster_fits(c, e, z, budget)) {
        take_cluster(c, k.eps, y, want_b, e, s);
        continue;
      }
      if (c.left >= 0) {
        stack[top++] = c.left + 1;
        stack[top++] = c.left;
        continue;
      }
      direct_range(tris, c.begin, c.end, k, rule, y, want_b, true, s);
    }
  }
}

// One point's sums by the whole tree.
PointSums traverse(const std::vector<BodyIntegral::Cluster>& clusters,
                   const std::vector<Triangle>& tris, const Radial& k, const Rules& rule,
                   const double* y, bool want_b, const Budget& budget) {
  PointSums s;
  traverse(clusters, tris, k, rule, y, want_b, budget, {0}, &s);
  return s;
}

// A group of points (|y − centre| ≤ radius for each) and the decisions its points share: the
// clusters every point takes (fits at z − radius ≤ each point's z), the leaves no point takes
// (fails at z + radius), the nodes each point decides itself (the roots of its own traversal).
// With one budget for the group, each point's sums are those of its own traversal (the fits are
// monotone in z), in another order.
struct GroupLists {
  std::vector<int> taken, leaves, open;
};

template <class Fits>
void group_lists(const std::vector<BodyIntegral::Cluster>& clusters, const double* centre,
                 double radius, Fits&& fits, GroupLists* out) {
  out->taken.clear();
  out->leaves.clear();
  out->open.clear();
  int stack[2 * kBvhMaxDepth + 2];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const int id = stack[--top];
    const BodyIntegral::Cluster& c = clusters[id];
    const double d[3] = {c.p[0] - centre[0], c.p[1] - centre[1], c.p[2] - centre[2]};
    const double z = std::sqrt(dot(d, d)) - c.rho;
    if (fits(c, z - radius)) {
      out->taken.push_back(id);
    } else if (fits(c, z + radius)) {
      out->open.push_back(id);
    } else if (c.left >= 0) {
      stack[top++] = c.left + 1;
      stack[top++] = c.left;
    } else {
      out->leaves.push_back(id);
    }
  }
}

// Points are taken in blocks of kBlock rows (a block's points depend on the ones before them in
// it, not on the threads), each in groups of up to kGroup consecutive rows within a sphere of
// radius kGroupRadius × the root cluster's ρ that share one traversal.
constexpr Eigen::Index kBlock = 64;
constexpr Eigen::Index kGroup = 8;
constexpr double kGroupRadius = 1.0 / 32.0;

// The centre and radius of rows [begin, end) of points (the mean; the largest distance to it,
// widened by 1e-12 of itself against rounding).
double group_sphere(const Eigen::MatrixXd& points, Eigen::Index begin, Eigen::Index end,
                    double* centre) {
  for (int i = 0; i < 3; ++i) centre[i] = points.col(i).segment(begin, end - begin).mean();
  double r2 = 0.0;
  for (Eigen::Index j = begin; j < end; ++j) {
    const double d[3] = {points(j, 0) - centre[0], points(j, 1) - centre[1],
                         points(j, 2) - centre[2]};
    r2 = std::max(r2, dot(d, d));
  }
  return std::sqrt(r2) * (1.0 + 1e-12);
}

// The group of rows from begin: the most consecutive rows, up to kGroup and before limit, whose
// sphere's radius stays ≤ max_radius (one row at least); its end into *end, centre and radius.
double next_group(const Eigen::MatrixXd& points, Eigen::Index begin, Eigen::Index limit,
                  double max_radius, double* centre, Eigen::Index* end) {
  double radius = group_sphere(points, begin, begin + 1, centre);
  *end = begin + 1;
  for (Eigen::Index e = begin + 2; e <= std::min(limit, begin + kGroup); ++e) {
    double c[3];
    const double r = group_sphere(points, begin, e, c);
    if (r > max_radius) break;
    std::copy(c, c + 3, centre);
    radius = r;
    *end = e;
  }
  return radius;
}

// One point's sums from its group's lists.
PointSums group_point(const std::vector<BodyIntegral::Cluster>& clusters,
                      const std::vector<Triangle>& tris, const Radial& k, const Rules& rule,
                      const double* y, bool want_b, const Budget& budget, const GroupLists& g) {
  PointSums s;
  const auto direct = [&](const BodyIntegral::Cluster& c) {
    direct_range(tris, c.begin, c.end, k, rule, y, want_b, true, &s);
  };
  for (int id : g.taken) {  // by the bounds at y's own distance (≥ the group's, up to rounding)
    const BodyIntegral::Cluster& c = clusters[id];
    const double d[3] = {c.p[0] - y[0], c.p[1] - y[1], c.p[2] - y[2]};
    const Bounds e = cluster_bounds(c, k.eps, std::sqrt(dot(d, d)) - c.rho, want_b);
    if (e.valid)
      take_cluster(c, k.eps, y, want_b, e, &s);
    else  // invalid at y by rounding only: its triangles one by one
      direct(c);
  }
  for (int id : g.leaves) direct(clusters[id]);
  traverse(clusters, tris, k, rule, y, want_b, budget, g.open, &s);
  return s;
}

// The surface product's far field: a cluster's expansion of k(|x − y|) = k(|d + s|), d = p − y,
// s = x − p, to second order, k̃(s) = f + f1 d·s + ½ (f1 |s|² + f2 (d·s)²), its coefficients
// times w added to L (kLocal numbers: f, f1 d, f1, f2 d dᵀ by (00, 01, 02, 11, 12, 22)); returns
// the cluster's ∫ k̃ dA = f A + f1 d·m1 + ½ (f1 tr m2 + f2 dᵀ m2 d) (S's share).
constexpr int kLocal = 11;

double local_share(const BodyIntegral::Cluster& c, double eps, const double* y, double w,
                   double* L) {
  const double d[3] = {c.p[0] - y[0], c.p[1] - y[1], c.p[2] - y[2]};
  const double r = std::sqrt(dot(d, d)), ir = 1.0 / r, iw = 1.0 / (r + eps);
  const double f = (iw * iw) * (iw * iw), f1 = -4.0 * ir * f * iw;
  const double f2 = 4.0 * ir * ir * ir * f * iw + 20.0 * ir * ir * f * iw * iw;
  L[0] += w * f;
  for (int i = 0; i < 3; ++i) L[1 + i] += w * f1 * d[i];
  L[4] += w * f1;
  const int pair[6][2] = {{0, 0}, {0, 1}, {0, 2}, {1, 1}, {1, 2}, {2, 2}};
  for (int e = 0; e < 6; ++e) L[5 + e] += w * f2 * d[pair[e][0]] * d[pair[e][1]];
  double dm2d = 0.0;
  for (int j = 0; j < 3; ++j)
    for (int k = 0; k < 3; ++k) dm2d += d[j] * c.s2[3 * j + k] * d[k];
  return f * c.area + f1 * dot(c.s1, d) + 0.5 * (f1 * c.tr2 + f2 * dm2d);
}

// Σ_q W_q λ_a(q) k̃(s_q) for the corners a of triangle t (the 16-point rule: exact, λ_a k̃ is
// cubic), k̃ the expansion with coefficients L about p, added to c.
void push_local(const Triangle& t, const double* p, const double* L, double* c) {
  const FarRule& rule = far_rule();
  for (int q = 0; q < kFarPoints; ++q) {
    const double s[3] = {t.qx[q] - p[0], t.qy[q] - p[1], t.qz[q] - p[2]};
    const double quad = L[5] * s[0] * s[0] + 2.0 * L[6] * s[0] * s[1] + 2.0 * L[7] * s[0] * s[2] +
                        L[8] * s[1] * s[1] + 2.0 * L[9] * s[1] * s[2] + L[10] * s[2] * s[2];
    const double v = t.wq[q] * (L[0] + L[1] * s[0] + L[2] * s[1] + L[3] * s[2] +
                                0.5 * (L[4] * dot(s, s) + quad));
    for (int a = 0; a < 3; ++a) c[a] += v * rule.lam[q][a];
  }
}

// One point's share of the surface product by the tree, kept until its bound is checked: the
// triangles taken one by one (w ∫_t k λ_a), the clusters by their expansions (w L), S̃ and the
// bound of its error (that of every corner's sum too).
struct VjpPoint {
  std::vector<std::pair<int, std::array<double, 3>>> tris;
  std::vector<std::pair<int, std::array<double, kLocal>>> clusters;
  double S = 0.0, err = 0.0;
};

// What the surface product's traversals read: the clusters, the tree's triangle order and the
// triangles in it, the rules.
struct VjpView {
  const std::vector<BodyIntegral::Cluster>& clusters;
  const std::vector<int>& order;
  const std::vector<Triangle>& tris;
  const Radial& k;
  const Rules& rule;
};

// Cluster id's expansion into y's share (weight w), g its bound per unit area at y.
void take_vjp_cluster(const VjpView& v, int id, const double* y, double w, double g,
                      VjpPoint* out) {
  const BodyIntegral::Cluster& c = v.clusters[id];
  std::array<double, kLocal> L{};
  out->S += local_share(c, v.k.eps, y, w, L.data());
  out->err += c.area * g;
  out->clusters.emplace_back(id, L);
}

// The triangles of cluster c one by one into y's share.
void direct_vjp(const VjpView& v, const BodyIntegral::Cluster& c, const double* y, double w,
                VjpPoint* out) {
  for (int j = c.begin; j < c.end; ++j) {
    double ct[3];
    corner_moments(v.tris[j], v.k, v.rule, y, ct);
    out->S += ct[0] + ct[1] + ct[2];
    out->tris.push_back({v.order[j], {w * ct[0], w * ct[1], w * ct[2]}});
  }
}

// Whether a cluster at z enters the product by its expansion: valid, and its bound g per unit
// area within the budget (or, theta > 0, ρ ≤ θ z).
bool vjp_fits(const BodyIntegral::Cluster& c, const Bounds& e, double z, double budget,
              double theta) {
  return e.valid && (theta > 0.0 ? c.rho <= theta * z : e.g <= budget);
}

// y's share of the surface product below the nodes `start`, added to out.
void traverse_vjp(const VjpView& v, const double* y, double w, double budget, double theta,
                  const std::vector<int>& start, VjpPoint* out) {
  int stack[2 * kBvhMaxDepth + 2];
  for (int root : start) {
    int top = 0;
    stack[top++] = root;
    while (top > 0) {
      const int id = stack[--top];
      const BodyIntegral::Cluster& c = v.clusters[id];
      const double d[3] = {c.p[0] - y[0], c.p[1] - y[1], c.p[2] - y[2]};
      const double z = std::sqrt(dot(d, d)) - c.rho;
      const Bounds e = cluster_bounds(c, v.k.eps, z, true);
      if (vjp_fits(c, e, z, budget, theta)) {
        take_vjp_cluster(v, id, y, w, e.g, out);
      } else if (c.left >= 0) {
        stack[top++] = c.left + 1;
        stack[top++] = c.left;
      } else {
        direct_vjp(v, c, y, w, out);
      }
    }
  }
}

// y's share by the whole tree (out cleared first).
void traverse_vjp(const VjpView& v, const double* y, double w, double budget, double theta,
                  VjpPoint* out) {
  out->tris.clear();
  out->clusters.clear();
  out->S = out->err = 0.0;
  traverse_vjp(v, y, w, budget, theta, {0}, out);
}

// y's share from its group's lists (out cleared first); a taken cluster by its bound at y's own
// distance (its triangles one by one where rounding makes it invalid there).
void group_vjp(const VjpView& v, const double* y, double w, double budget, const GroupLists& g,
               VjpPoint* out) {
  out->tris.clear();
  out->clusters.clear();
  out->S = out->err = 0.0;
  for (int id : g.taken) {
    const BodyIntegral::Cluster& c = v.clusters[id];
    const double d[3] = {c.p[0] - y[0], c.p[1] - y[1], c.p[2] - y[2]};
    const Bounds e = cluster_bounds(c, v.k.eps, std::sqrt(dot(d, d)) - c.rho, true);
    if (e.valid)
      take_vjp_cluster(v, id, y, w, e.g, out);
    else
      direct_vjp(v, c, y, w, out);
  }
  for (int id : g.leaves) direct_vjp(v, v.clusters[id], y, w, out);
  traverse_vjp(v, y, w, budget, 0.0, g.open, out);
}

// What one evaluation by the tree reads: the clusters, the triangles in the tree's order, the
// rules, whether ∂J/∂y is wanted, τ and |∂Ω|.
struct TreeView {
  const std::vector<BodyIntegral::Cluster>& clusters;
  const std::vector<Triangle>& tris;
  const Radial& k;
  const Rules& rule;
  bool want_b;
  double tau, area;
};

// The guesses of J and S a budget is made from, and whether y was on the surface.
struct Guess {
  double j = 0.0, s = 0.0;
  bool surface = false;
};

// J = Σ + G∞ × the far solid angles (exact off the surface) and the bound of its error.
double total_j(const Radial& k, const PointSums& s) {
  return s.J + k.g_inf * far_solid_angle(s.near_omega, s.far_omega, s.on_surface);
}
double error_j(const Radial& k, const PointSums& s) {
  return s.err_j + (s.on_surface ? k.g_inf * s.err_omega : 0.0);
}

// A probe's lower bounds of J and S at y (clusters with ρ ≤ z/4 taken).
Guess probe(const TreeView& t, const double* y) {
  const PointSums s = traverse(t.clusters, t.tris, t.k, t.rule, y, t.want_b,
                               Budget{0.0, 3.0 / t.area, 0.0, kProbeTheta});
  return {total_j(t.k, s) - error_j(t.k, s), s.S - s.err_g, s.on_surface};
}

// The budget of the guesses (per unit area τ J/(2 |∂Ω|), τ S/(2 |∂Ω|); on the surface, where the
// far solid angles' estimate enters J, a quarter of J's for it and a quarter for the rest), or
// none (exact: every triangle).
Budget make_budget(const TreeView& t, const Guess& g, bool exact) {
  if (exact) return Budget{0.0, 0.0, 0.0};
  const double share = g.surface ? 0.25 : 0.5;
  const double omega = g.surface ? std::min(3.0, share * t.tau * g.j / t.k.g_inf) : 3.0;
  return Budget{share * t.tau * g.j / t.area, omega / t.area, 0.5 * t.tau * g.s / t.area};
}

// One point's sums from its group's lists.
PointSums group_point(const TreeView& t, const double* y, const Budget& budget,
                      const GroupLists& lists) {
  return group_point(t.clusters, t.tris, t.k, t.rule, y, t.want_b, budget, lists);
}

// A point's sums s checked: accepted (its J into *J) when E_J ≤ τ (J̃ − E_J) and, with the
// gradient, E_g ≤ τ (S̃ − E_g), or when exact; else redone with the budget its own lower bounds
// give, then over all pairs.
PointSums settle(const TreeView& t, const double* y, PointSums s, bool exact, double* J) {
  for (int attempt = 1;; ++attempt) {
    *J = total_j(t.k, s);
    const double err = error_j(t.k, s);
    if (exact || (err <= t.tau * (*J - err) && (!t.want_b || s.err_g <= t.tau * (s.S - s.err_g))))
      return s;
    const Guess own{*J - err, s.S - s.err_g, s.on_surface};
    exact = attempt == 2 || own.j <= 0.0 || (t.want_b && own.s <= 0.0);
    s = traverse(t.clusters, t.tris, t.k, t.rule, y, t.want_b, make_budget(t, own, exact));
  }
}

// A point's share pt checked: accepted when E ≤ τ (S̃ − E) (S̃ = pt->S, without the weight), or
// when exact; else redone with the budget its own lower bound gives, then over all pairs.
void settle_vjp(const VjpView& v, const double* y, double w, double tau, double area, bool exact,
                VjpPoint* pt) {
  for (int attempt = 1;; ++attempt) {
    if (exact || pt->err <= tau * (pt->S - pt->err)) return;
    const double own = pt->S - pt->err;
    exact = attempt == 2 || own <= 0.0;
    traverse_vjp(v, y, w, exact ? 0.0 : 0.5 * tau * own / area, 0.0, pt);
  }
}

// The corner sums Σ_k w_k ∫_t k λ_a dA of every triangle (3 per triangle, in the surface's
// order): the threads' direct sums (acc) and their clusters' expansion coefficients (loc, kLocal
// per cluster) pushed to the clusters' triangles, summed in thread order.
std::vector<double> corner_sums(const VjpView& v, const std::vector<std::vector<double>>& acc,
                                const std::vector<std::vector<double>>& loc) {
  const std::size_t count = v.tris.size(), nodes = v.clusters.size();
  std::vector<double> sum(3 * count, 0.0), local(kLocal);
  for (const std::vector<double>& a : acc)
    for (std::size_t i = 0; i < a.size(); ++i) sum[i] += a[i];
  for (std::size_t id = 0; id < nodes; ++id) {
    std::fill(local.begin(), local.end(), 0.0);
    bool any = false;
    for (const std::vector<double>& l : loc)
      for (int i = 0; i < kLocal && !l.empty(); ++i) {
        local[i] += l[kLocal * id + i];
        any = any || l[kLocal * id + i] != 0.0;
      }
    if (!any) continue;
    const BodyIntegral::Cluster& cl = v.clusters[id];
    for (int j = cl.begin; j < cl.end; ++j)
      push_local(v.tris[j], cl.p, local.data(), &sum[3 * v.order[j]]);
  }
  return sum;
}

void validate(const BodyIntegralOptions& o) {
  if (!(o.epsilon > 0.0) || !std::isfinite(o.epsilon))
    throw InvalidArgument("body integral: epsilon must be finite and > 0, got " +
                          decimal(o.epsilon));
  if (!(o.alpha > 0.0) || !std::isfinite(o.alpha))
    throw InvalidArgument("body integral: alpha must be finite and > 0, got " + decimal(o.alpha));
  if (!(o.near_ratio >= 1.0) || !std::isfinite(o.near_ratio))
    throw InvalidArgument("body integral: near_ratio must be finite and >= 1, got " +
                          decimal(o.near_ratio));
  if (o.angle_points < 2 || o.angle_points > 64)
    throw InvalidArgument("body integral: angle_points must be in [2, 64], got " +
                          std::to_string(o.angle_points));
  if (!(o.panel_width > 0.0) || !std::isfinite(o.panel_width))
    throw InvalidArgument("body integral: panel_width must be finite and > 0, got " +
                          decimal(o.panel_width));
  if (!(o.tolerance >= 0.0 && o.tolerance < 1.0))
    throw InvalidArgument("body integral: tolerance must be in [0, 1), got " +
                          decimal(o.tolerance));
  if (o.tolerance > 0.0 && o.alpha != 4.0)
    throw InvalidArgument(
        "body integral: tolerance > 0 needs alpha = 4 (the tree's expansions), "
        "got alpha " +
        decimal(o.alpha));
  check_threads(o.threads);
}

// The geometry of one triangle (area2 = 2 × its area > 0).
Triangle make_triangle(const double v[3][3], double near_ratio, double* area2) {
  Triangle t;
  std::copy(&v[0][0], &v[0][0] + 9, &t.v[0][0]);
  double e1[3], e2[3], n[3];
  for (int i = 0; i < 3; ++i) {
    e1[i] = v[1][i] - v[0][i];
    e2[i] = v[2][i] - v[0][i];
    t.c[i] = (v[0][i] + v[1][i] + v[2][i]) / 3.0;
  }
  cross(e1, e2, n);
  *area2 = std::sqrt(dot(n, n));
  if (!(*area2 > 0.0)) return t;
  double radius2 = 0.0;
  for (int i = 0; i < 3; ++i) t.n[i] = n[i] / *area2;
  for (int e = 0; e < 3; ++e) {
    const double* a = v[e];
    const double* b = v[(e + 1) % 3];
    const double d[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    t.len[e] = std::sqrt(dot(d, d));
    for (int i = 0; i < 3; ++i) t.tau[e][i] = d[i] / t.len[e];
    cross(t.tau[e], t.n, t.nu[e]);
    const double g[3] = {a[0] - t.c[0], a[1] - t.c[1], a[2] - t.c[2]};
    radius2 = std::max(radius2, dot(g, g));
  }
  t.near2 = near_ratio * near_ratio * radius2;
  t.far2 = kCoarseRatio * kCoarseRatio * t.near2;
  for (int a = 0; a < 3; ++a) {  // ∇λ_a = n × (v_{a+2} − v_{a+1}) / (2 area)
    const double* p = v[(a + 1) % 3];
    const double* q = v[(a + 2) % 3];
    const double d[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]};
    cross(t.n, d, t.glam[a]);
    for (int i = 0; i < 3; ++i) t.glam[a][i] /= *area2;
  }
  // A rule's points x = Σ_a λ_a v_a by coordinate, and its weights times the area.
  const auto place = [&](const auto& rule, int n, double* x, double* y, double* z, double* w) {
    double* coord[3] = {x, y, z};
    for (int q = 0; q < n; ++q) {
      const double* lam = rule.lam[q];
      for (int i = 0; i < 3; ++i)
        coord[i][q] = lam[0] * v[0][i] + lam[1] * v[1][i] + lam[2] * v[2][i];
      w[q] = 0.5 * *area2 * rule.w[q];
    }
  };
  place(far_rule(), kFarPoints, t.qx, t.qy, t.qz, t.wq);
  place(coarse_rule(), kCoarsePoints, t.cx, t.cy, t.cz, t.cw);
  return t;
}

// Throws InvalidArgument unless the triangles (3 corners each) close up with one orientation:
// every directed edge (a, b) as often as (b, a) (the divergence theorem, and the far solid
// angles' winding number, need a closed, consistently oriented surface).
void check_closed(const std::vector<int>& corners) {
  std::vector<std::pair<int, int>> edges;
  edges.reserve(corners.size());
  for (std::size_t t = 0; t < corners.size(); t += 3)
    for (int e = 0; e < 3; ++e) edges.emplace_back(corners[t + e], corners[t + (e + 1) % 3]);
  std::sort(edges.begin(), edges.end());
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i;
    while (j < edges.size() && edges[j] == edges[i]) ++j;
    const auto back = std::equal_range(edges.begin(), edges.end(),
                                       std::make_pair(edges[i].second, edges[i].first));
    if (static_cast<std::size_t>(back.second - back.first) != j - i)
      throw InvalidArgument("body integral: the surface is not closed and consistently oriented: " +
                            std::to_string(j - i) + " edge(s) from point " +
                            std::to_string(edges[i].first) + " to " +
                            std::to_string(edges[i].second) + ", " +
                            std::to_string(back.second - back.first) + " back");
    i = j;
  }
}

// Each triangle's coplanar neighbours (Triangle::twin): across edge (a, b) the one triangle with
// the edge (b, a), when their unit normals agree to 1e-13 and its centroid lies in the plane to
// 1e-13 of the edges' length; else −1.
void find_twins(const std::vector<int>& corners, std::vector<Triangle>* tris) {
  std::vector<std::array<int, 4>> edges;  // (a, b, triangle, edge)
  for (std::size_t t = 0; t < tris->size(); ++t)
    for (int e = 0; e < 3; ++e)
      edges.push_back({corners[3 * t + e], corners[3 * t + (e + 1) % 3], static_cast<int>(t), e});
  std::sort(edges.begin(), edges.end());
  for (const auto& ed : edges) {
    Triangle& t = (*tris)[ed[2]];
    t.twin[ed[3]] = -1;
    const std::array<int, 4> lo{ed[1], ed[0], -1, -1}, hi{ed[1], ed[0] + 1, -1, -1};
    const auto first = std::lower_bound(edges.begin(), edges.end(), lo);
    const auto last = std::lower_bound(edges.begin(), edges.end(), hi);
    if (last - first != 1) continue;
    const Triangle& s = (*tris)[(*first)[2]];
    const double size = t.len[0] + t.len[1] + t.len[2];
    const double off[3] = {s.c[0] - t.c[0], s.c[1] - t.c[1], s.c[2] - t.c[2]};
    bool flat = std::abs(dot(t.n, off)) <= 1e-13 * size;
    for (int i = 0; i < 3; ++i) flat = flat && std::abs(s.n[i] - t.n[i]) <= 1e-13;
    if (flat) t.twin[ed[3]] = (*first)[2];
  }
}

}  // namespace

double radial_g(double r, double epsilon, double alpha) {
  Radial k(epsilon, alpha);
  k.four = false;  // the general closed form and series
  return k.g(r);
}

BodyIntegral::BodyIntegral(const TriangleSurface& surface, const BodyIntegralOptions& options)
    : options_(options) {
  validate(options);
  if (surface.points.cols() != 3)
    throw InvalidArgument("body integral: the surface's points must be N by 3");
  point_count_ = surface.points.rows();
  const Eigen::Index count = surface.triangles.rows();
  triangles_.resize(count);
  corners_.resize(3 * count);
  for (Eigen::Index t = 0; t < count; ++t) {
    double v[3][3];
    for (int a = 0; a < 3; ++a) {
      const int idx = surface.triangles(t, a);
      if (idx < 0 || idx >= point_count_)
        throw InvalidArgument("body integral: triangle " + std::to_string(t) +
                              " has a point index out of range: " + std::to_string(idx));
      corners_[3 * t + a] = idx;
      for (int i = 0; i < 3; ++i) v[a][i] = surface.points(idx, i);
    }
    double area2 = 0.0;
    triangles_[t] = make_triangle(v, options.near_ratio, &area2);
    if (!(area2 > 0.0))
      throw InvalidArgument("body integral: triangle " + std::to_string(t) + " has zero area");
  }
  check_closed(corners_);
  find_twins(corners_, &triangles_);
  gauss_legendre_unit(options.angle_points, &rule_x_, &rule_w_);
  if (options.tolerance > 0.0) {
    const Bvh bvh = build_bvh(surface);
    order_ = bvh.order;
    clusters_.reserve(bvh.nodes.size());
    for (const BvhNode& node : bvh.nodes)
      clusters_.push_back(make_cluster(triangles_, order_, node));
    total_area_ = clusters_[0].area;
    group_radius_ = kGroupRadius * clusters_[0].rho;
    std::vector<int> position(order_.size());
    for (std::size_t j = 0; j < order_.size(); ++j) position[order_[j]] = static_cast<int>(j);
    for (int t : order_) {
      ordered_.push_back(triangles_[t]);
      for (int& twin : ordered_.back().twin)
        if (twin >= 0) twin = position[twin];
    }
  }
}

void BodyIntegral::evaluate(const Eigen::MatrixXd& points, Eigen::VectorXd* value,
                            Eigen::MatrixXd* grad) const {
  if (points.cols() != 3) throw InvalidArgument("body integral: the points must be M by 3");
  const Eigen::Index m = points.rows();
  value->resize(m);
  if (grad) grad->resize(m, 3);
  if (options_.tolerance > 0.0) return evaluate_tree(points, value, grad);
  const Radial k(options_.epsilon, options_.alpha);
  const Rules rule{rule_x_, rule_w_, options_.panel_width};
  const bool want_b = grad != nullptr;
  const int threads = resolve_threads(options_.threads);
  const bool coulomb = k.alpha >= Radial::kCoulomb;
  // Runs points × triangles times: the near/far switch, then 16 or 8 kernel evaluations (far)
  // or 3 edges × panels × angle_points (near).
#pragma omp parallel for schedule(static) num_threads(threads)
  for (Eigen::Index j = 0; j < m; ++j) {
    const double y[3] = {points(j, 0), points(j, 1), points(j, 2)};
    PointSums s;  // Σ ω_t: near (exact), far (the rule's)
    direct_range(triangles_, 0, static_cast<int>(triangles_.size()), k, rule, y, want_b, coulomb,
                 &s);
    double J = s.J;
    if (coulomb) J += k.g_inf * far_solid_angle(s.near_omega, s.far_omega, s.on_surface);
    (*value)[j] = J;
    if (grad)
      for (int i = 0; i < 3; ++i) (*grad)(j, i) = s.g[i];
  }
}

void BodyIntegral::evaluate_tree(const Eigen::MatrixXd& points, Eigen::VectorXd* value,
                                 Eigen::MatrixXd* grad) const {
  const Eigen::Index m = points.rows();  // value and grad sized by evaluate()
  const Radial k(options_.epsilon, options_.alpha);
  const Rules rule{rule_x_, rule_w_, options_.panel_width};
  const TreeView t{clusters_, ordered_, k, rule, grad != nullptr, options_.tolerance, total_area_};
  const Eigen::Index blocks = (m + kBlock - 1) / kBlock;
  // Per block of points in order, per group of kGroup rows in it: one budget for the group from
  // the previous group's smallest J and S (for a block's first, from a probe at its first point:
  // clusters with ρ ≤ z/4 taken, J̃ − E and S̃ − E), per unit area τ J/(2 |∂Ω|), likewise for g;
  // the far solid angles' total bound below 3 (< 2π with the far rules' own error: the winding
  // number rounds right; on the surface, where their estimate enters J, below τ J/(4 G∞) and
  // J's own τ J/(4 |∂Ω|)). One traversal decides what the group's points share (group_lists),
  // each point the rest. A point is accepted when the bounds give E_J ≤ τ (J̃ − E_J) ≤ τ J and
  // E_g ≤ τ (S̃ − E_g) ≤ τ S; else redone with its own budget, then with none (every triangle).
#pragma omp parallel for schedule(static) num_threads(resolve_threads(options_.threads))
  for (Eigen::Index b = 0; b < blocks; ++b) {
    Guess guess;
    GroupLists lists;
    const Eigen::Index block_end = std::min(m, (b + 1) * kBlock);
    for (Eigen::Index g = b * kBlock, end; g < block_end; g = end) {
      double centre[3];
      const double radius = next_group(points, g, block_end, group_radius_, centre, &end);
      if (guess.j <= 0.0) {  // a block's first group: a probe's lower bounds as the guesses
        const double y[3] = {points(g, 0), points(g, 1), points(g, 2)};
        guess = probe(t, y);
      }
      const bool exact = guess.j <= 0.0 || (t.want_b && guess.s <= 0.0);
      const Budget budget = make_budget(t, guess, exact);
      group_lists(
          t.clusters, centre, radius,
          [&](const Cluster& c, double z) {
            return cluster_fits(c, cluster_bounds(c, k.eps, z, t.want_b), z, budget);
          },
          &lists);
      Guess next{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
                 false};
      for (Eigen::Index j = g; j < end; ++j) {
        const double y[3] = {points(j, 0), points(j, 1), points(j, 2)};
        double J;
        const PointSums s = settle(t, y, group_point(t, y, budget, lists), exact, &J);
        next = {std::min(next.j, J), std::min(next.s, s.S), next.surface || s.on_surface};
        (*value)[j] = J;
        if (grad)
          for (int i = 0; i < 3; ++i) (*grad)(j, i) = s.g[i];
      }
      guess = next;
    }
  }
}

Eigen::MatrixXd BodyIntegral::surface_vjp(const Eigen::MatrixXd& points,
                                          const Eigen::VectorXd& weights) const {
  if (points.cols() != 3) throw InvalidArgument("body integral: the points must be M by 3");
  if (weights.size() != points.rows())
    throw InvalidArgument("body integral: weights must have one entry per point");
  if (options_.tolerance > 0.0) return surface_vjp_tree(points, weights);
  const Radial k(options_.epsilon, options_.alpha);
  const Rules rule{rule_x_, rule_w_, options_.panel_width};
  const int threads = resolve_threads(options_.threads);
  const std::size_t count = triangles_.size();
  // Per thread, per triangle and corner: Σ_k w_k ∫_t k λ_a dA; summed in thread order.
  std::vector<std::vector<double>> acc(threads);
  const Eigen::Index m = points.rows();
#pragma omp parallel num_threads(threads)
  {
    std::vector<double>& c = acc[thread_id()];
    c.assign(3 * count, 0.0);
#pragma omp for schedule(static)
    for (Eigen::Index j = 0; j < m; ++j) {
      const double wj = weights[j];
      if (wj == 0.0) continue;
      const double y[3] = {points(j, 0), points(j, 1), points(j, 2)};
      for (std::size_t t = 0; t < count; ++t) {
        const Triangle& tri = triangles_[t];
        double ct[3];
        corner_moments(tri, k, rule, y, ct);
        for (int a = 0; a < 3; ++a) c[3 * t + a] += wj * ct[a];
      }
    }
  }
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(point_count_, 3);
  for (std::size_t t = 0; t < count; ++t)
    for (int a = 0; a < 3; ++a) {
      double s = 0.0;
      for (const std::vector<double>& c : acc)
        if (!c.empty()) s += c[3 * t + a];
      for (int i = 0; i < 3; ++i) out(corners_[3 * t + a], i) += s * triangles_[t].n[i];
    }
  return out;
}

Eigen::MatrixXd BodyIntegral::surface_vjp_tree(const Eigen::MatrixXd& points,
                                               const Eigen::VectorXd& weights) const {
  const Radial k(options_.epsilon, options_.alpha);
  const Rules rule{rule_x_, rule_w_, options_.panel_width};
  const VjpView view{clusters_, order_, ordered_, k, rule};
  const int threads = resolve_threads(options_.threads);
  const std::size_t count = triangles_.size(), nodes = clusters_.size();
  const Eigen::Index m = points.rows(), blocks = (m + kBlock - 1) / kBlock;
  // Per thread: the triangles' corner sums and the clusters' coefficients, summed in thread
  // order. Per group of rows (as in evaluate_tree) one budget (per unit area, of every corner
  // sum's error) τ S/(2 |∂Ω|) from the previous group's smallest S (a probe's S̃ − E for a
  // block's first), one traversal for what its points share; a point is accepted when E ≤
  // τ (S̃ − E): then Σ_{t,a} |error of w ∫_t k λ_a| ≤ τ |w| S, S = ∫_∂Ω k dA; else redone with its
  // own budget, then over all pairs.
  std::vector<std::vector<double>> acc(threads), loc(threads);
#pragma omp parallel num_threads(threads)
  {
    std::vector<double>& c = acc[thread_id()];
    std::vector<double>& L = loc[thread_id()];
    c.assign(3 * count, 0.0);
    L.assign(kLocal * nodes, 0.0);
    VjpPoint pt;
    GroupLists lists;
#pragma omp for schedule(static)
    for (Eigen::Index b = 0; b < blocks; ++b) {
      double s_guess = 0.0;
      const Eigen::Index block_end = std::min(m, (b + 1) * kBlock);
      for (Eigen::Index g = b * kBlock, end; g < block_end; g = end) {
        double centre[3];
        const double radius = next_group(points, g, block_end, group_radius_, centre, &end);
        if (s_guess <= 0.0) {  // a block's first group: a probe's lower bound as the guess
          const double y[3] = {points(g, 0), points(g, 1), points(g, 2)};
          traverse_vjp(view, y, 1.0, 0.0, kProbeTheta, &pt);
          s_guess = pt.S - pt.err;
        }
        const double budget =
            s_guess > 0.0 ? 0.5 * options_.tolerance * s_guess / total_area_ : 0.0;
        group_lists(
            clusters_, centre, radius,
            [&](const Cluster& cl, double z) {
              return vjp_fits(cl, cluster_bounds(cl, k.eps, z, true), z, budget, 0.0);
            },
            &lists);
        double next = std::numeric_limits<double>::infinity();
        for (Eigen::Index j = g; j < end; ++j) {
          const double wj = weights[j];
          if (wj == 0.0) continue;
          const double y[3] = {points(j, 0), points(j, 1), points(j, 2)};
          group_vjp(view, y, wj, budget, lists, &pt);
          settle_vjp(view, y, wj, options_.tolerance, total_area_, budget == 0.0, &pt);
          next = std::min(next, pt.S);
          for (const auto& t : pt.tris)
            for (int a = 0; a < 3; ++a) c[3 * t.first + a] += t.second[a];
          for (const auto& q : pt.clusters)
            for (int i = 0; i < kLocal; ++i) L[kLocal * q.first + i] += q.second[i];
        }
        if (next < std::numeric_limits<double>::infinity()) s_guess = next;
      }
    }
  }
  const std::vector<double> sum = corner_sums(view, acc, loc);
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(point_count_, 3);
  for (std::size_t t = 0; t < count; ++t)
    for (int a = 0; a < 3; ++a)
      for (int i = 0; i < 3; ++i)
        out(corners_[3 * t + a], i) += sum[3 * t + a] * triangles_[t].n[i];
  return out;
}

}  // namespace softhd::detail
