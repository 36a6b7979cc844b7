#pragma once
// The rules of BodyIntegral (internal to body_integral*.cpp; body_integral.hpp describes the
// method): the far triangles' Dunavant and Radon rules, the kernel's radial functions and the
// Gauss–Legendre panels of the polar rule.

#include <algorithm>
#include <cmath>
#include <vector>

#include "body_integral.hpp"

namespace softhd::detail::body {

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

inline const FarRule& far_rule() {
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

inline const CoarseRule& coarse_rule() {
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
inline FarPoints far_points(const Triangle& t, double d2) {
  if (d2 < t.far2) {
    const FarRule& r = far_rule();
    return {t.qx, t.qy, t.qz, t.wq, r.corner[0], r.corner[1], r.corner[2], kFarPoints};
  }
  const CoarseRule& r = coarse_rule();
  return {t.cx, t.cy, t.cz, t.cw, r.corner[0], r.corner[1], r.corner[2], kCoarsePoints};
}

// d_m(z) = ε^−(m+1) ∫_ε^{ε(1+z)} w^m dw: log(1 + z) for m = −1, else ((1 + z)^{m+1} − 1)/(m+1)
// (log1p/expm1: no cancellation for small z).
inline double power_primitive(double m, double z) {
  if (m == -1.0) return std::log1p(z);
  return std::expm1((m + 1.0) * std::log1p(z)) / (m + 1.0);
}

// Σ_k c_k z^{k+j}/(k+j), c_k = binom(−α, k): ε^{α−j} ∫₀^{εz} u^{j−1}(u + ε)^−α du for z < 1.
inline double binomial_series(double alpha, int j, double z) {
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

}  // namespace softhd::detail::body
