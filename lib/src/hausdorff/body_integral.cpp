#include "body_integral.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "../common/decimal.hpp"
#include "../common/gauss_legendre.hpp"
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
  }
};

const CoarseRule& coarse_rule() {
  static const CoarseRule rule;
  return rule;
}

// The points of a far rule on one triangle, by coordinate, weights times the area.
struct FarPoints {
  const double *x, *y, *z, *w;
  const double (*lam)[3];
  int n;
};

// The 16-point rule within (kCoarseRatio · near_ratio · R_t)² = t.far2 of y, else the 7-point.
FarPoints far_points(const Triangle& t, double d2) {
  if (d2 < t.far2) return {t.qx, t.qy, t.qz, t.wq, far_rule().lam, kFarPoints};
  return {t.cx, t.cy, t.cz, t.cw, coarse_rule().lam, kCoarsePoints};
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

// The wedge of one edge seen from the foot p of y (in-plane distance |p_e| > 0 to the edge's
// line, t1 < t2 its ends along it), polar about p, T(u) = √(p_e² cosh²u + h²), θ = gd(u):
//   W_A = ∫ [Φ_A(T) − Φ_A(|h|)] dθ = ∫ ∫₀^R G(r)/r³ s ds dθ
//   W_B = ∫ [K₁(T) − K₁(|h|)] dθ   = ∫ ∫₀^R k(r) s ds dθ
void edge_wedge(const Radial& k, const Rules& rule, double pe, double h, double t1, double t2,
                bool want_a, bool want_b, double* wa, double* wb) {
  const double ah = std::abs(h), p2 = pe * pe, h2 = h * h;
  const double fa = want_a ? k.phi_a(ah) : 0.0, fb = want_b ? k.k1(ah) : 0.0;
  double sa = 0.0, sb = 0.0;
  panel_rule(rule.x, rule.w, rule.width, std::asinh(t1 / pe), std::asinh(t2 / pe),
             [&](double u, double wt) {
               const double ch = std::cosh(u), T = std::sqrt(p2 * ch * ch + h2);
               const double f = wt / ch;
               if (want_a) sa += f * (k.phi_a(T) - fa);
               if (want_b) sb += f * (k.k1(T) - fb);
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
    panel_rule(rule.x, rule.w, rule.width, std::asinh(t1 / q), std::asinh(t2 / q),
               [&](double u, double wt) {
                 const double r = q * std::cosh(u);
                 s += wt * k.k1(r) * r;
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

// Near triangle, polar rule: A = ∫_t G(r)/r³ dA = Σ_e sign(p_e) W_A,e, likewise B = ∫_t k dA.
void near_pair(const Triangle& t, const Radial& k, const Rules& rule, const EdgeFrame& f,
               bool want_a, bool want_b, double* a, double* b) {
  double sa = 0.0, sb = 0.0;
  for (int e = 0; e < 3; ++e) {
    if (f.pe[e] == 0.0) continue;  // a degenerate wedge
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
    const double inv_eps = 1.0 / k.eps;
#pragma omp simd reduction(+ : s, c)
    for (int q = 0; q < t.n; ++q) {
      const double dx = t.x[q] - y[0], dy = t.y[q] - y[1], dz = t.z[q] - y[2];
      const double r = std::sqrt(dx * dx + dy * dy + dz * dz), W = 1.0 + r * inv_eps;
      const double W3 = W * W * W, wi = t.w[q] / (r * r * r * W3);  // one division
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
#pragma omp simd reduction(+ : s)
    for (int q = 0; q < t.n; ++q) {
      const double dx = t.x[q] - y[0], dy = t.y[q] - y[1], dz = t.z[q] - y[2];
      const double u = 1.0 / (std::sqrt(dx * dx + dy * dy + dz * dz) + k.eps);
      s += t.w[q] * (u * u) * (u * u);
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
  if (k.four) {
#pragma omp simd reduction(+ : c0, c1, c2)
    for (int q = 0; q < t.n; ++q) {
      const double dx = t.x[q] - y[0], dy = t.y[q] - y[1], dz = t.z[q] - y[2];
      const double u = 1.0 / (std::sqrt(dx * dx + dy * dy + dz * dz) + k.eps);
      const double kw = t.w[q] * (u * u) * (u * u);
      c0 += kw * t.lam[q][0];
      c1 += kw * t.lam[q][1];
      c2 += kw * t.lam[q][2];
    }
  } else {
    for (int q = 0; q < t.n; ++q) {
      const double dx = t.x[q] - y[0], dy = t.y[q] - y[1], dz = t.z[q] - y[2];
      const double kw = t.w[q] * k.kernel(std::sqrt(dx * dx + dy * dy + dz * dz));
      c0 += kw * t.lam[q][0];
      c1 += kw * t.lam[q][1];
      c2 += kw * t.lam[q][2];
    }
  }
  c[0] = c0;
  c[1] = c1;
  c[2] = c2;
}

// |y − c_t|²: near below t.near2 (the polar rule), the 16-point rule below t.far2.
double distance2(const Triangle& t, const double* y) {
  const double dx = y[0] - t.c[0], dy = y[1] - t.c[1], dz = y[2] - t.c[2];
  return dx * dx + dy * dy + dz * dz;
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
  const FarRule& rule = far_rule();
  double* coord[3] = {t.qx, t.qy, t.qz};
  for (int q = 0; q < kFarPoints; ++q) {
    const double* lam = rule.lam[q];
    for (int i = 0; i < 3; ++i)
      coord[i][q] = lam[0] * v[0][i] + lam[1] * v[1][i] + lam[2] * v[2][i];
    t.wq[q] = 0.5 * *area2 * rule.w[q];
  }
  const CoarseRule& coarse = coarse_rule();
  double* ccoord[3] = {t.cx, t.cy, t.cz};
  for (int q = 0; q < kCoarsePoints; ++q) {
    const double* lam = coarse.lam[q];
    for (int i = 0; i < 3; ++i)
      ccoord[i][q] = lam[0] * v[0][i] + lam[1] * v[1][i] + lam[2] * v[2][i];
    t.cw[q] = 0.5 * *area2 * coarse.w[q];
  }
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
  gauss_legendre_unit(options.angle_points, &rule_x_, &rule_w_);
}

void BodyIntegral::evaluate(const Eigen::MatrixXd& points, Eigen::VectorXd* value,
                            Eigen::MatrixXd* grad) const {
  if (points.cols() != 3) throw InvalidArgument("body integral: the points must be M by 3");
  const Eigen::Index m = points.rows();
  value->resize(m);
  if (grad) grad->resize(m, 3);
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
    double J = 0.0, g[3] = {0.0, 0.0, 0.0};
    double near_omega = 0.0, far_omega = 0.0;  // Σ ω_t: near (exact), far (the rule's)
    bool on_surface = false;
    for (const Triangle& t : triangles_) {
      double b = 0.0;
      const double d2 = distance2(t, y);
      if (d2 < t.near2) {
        const EdgeFrame f = edge_frame(t, y);
        double a;
        near_pair(t, k, rule, f, true, want_b, &a, &b);
        J += f.h * a;  // h_t ∫_t G(r)/r³ dA
        if (coulomb) {
          near_omega += solid_angle(t, y);
          on_surface = on_surface || on_triangle(t, f);
        }
      } else {
        const double h =
            t.n[0] * (t.v[0][0] - y[0]) + t.n[1] * (t.v[0][1] - y[1]) + t.n[2] * (t.v[0][2] - y[2]);
        const FarPoints p = far_points(t, d2);
        double omega;
        J += far_value(p, k, y, h, &omega);
        far_omega += omega;
        if (want_b) b = far_kernel(p, k, y);
      }
      if (want_b)
        for (int i = 0; i < 3; ++i) g[i] -= b * t.n[i];  // −n_t ∫_t k dA
    }
    if (coulomb) J += k.g_inf * far_solid_angle(near_omega, far_omega, on_surface);
    (*value)[j] = J;
    if (grad)
      for (int i = 0; i < 3; ++i) (*grad)(j, i) = g[i];
  }
}

Eigen::MatrixXd BodyIntegral::surface_vjp(const Eigen::MatrixXd& points,
                                          const Eigen::VectorXd& weights) const {
  if (points.cols() != 3) throw InvalidArgument("body integral: the points must be M by 3");
  if (weights.size() != points.rows())
    throw InvalidArgument("body integral: weights must have one entry per point");
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
        const double d2 = distance2(tri, y);
        if (d2 < tri.near2)
          near_moments(tri, k, rule, edge_frame(tri, y), y, ct);
        else
          far_moments(far_points(tri, d2), k, y, ct);
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

}  // namespace softhd::detail
