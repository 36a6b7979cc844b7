// BodyIntegral's tree (tolerance > 0): the clusters' moments and second-order expansions, the
// proved bounds of their remainders, one point's traversal (body_integral.hpp,
// docs/formulation.md §2.8).

#include <algorithm>
#include <cmath>

#include "body_integral_internal.hpp"

namespace softhd::detail::body {

namespace {

// The tree's expansions need ε ≤ kTreeX (|p − y| − ρ): the remainder bounds below sum the
// kernels' series in ε/r up to there.
constexpr double kTreeX = 0.05;

// C_H: the remainder of the second-order expansion of n·d H(|d|) (α = 4) at s = x − p is at
// most C_H |s|³/z⁶, z = |p − y| − ρ ≥ ε/kTreeX, so a cluster's at most C_H ∫|s|³ dA/z⁶. With
// x = ε/r, H = (1/3) Σ_{m=1}^{3} r^−4 (1 + x)^−m = Σ_k a_k ε^k r^−(4+k),
// |a_k| ≤ (1/3) Σ_m C(m+k−1, k); each term d r^−(4+k) = −∇ r^−(2+k)/(2 + k), and the order-2
// remainder of n·∇f at s is D⁴f(ξ)[n, s, s, s]/6, by polarisation at most max_u |D⁴f[u⁴]| |s|³/6,
// and for f = r^−2λ the Gegenbauer expansion |z + t u|^−2λ = Σ_n C_n^λ(cos) tⁿ |z|^−(2λ+n),
// |C_n^λ| ≤ C(n + 2λ − 1, n), gives |D⁴f[u⁴]| ≤ 4! C(5 + k, 4)/|z|^(6+k). So
// C_H(x) = Σ_k |a_k| x^k 4 C(5+k, 4)/(2 + k), x = ε/z. C_K likewise for the scalar
// k = (r + ε)^−4 = Σ_k C(k+3, 3)(−ε)^k r^−(4+k) at order 2: D³f[s³]/6 ≤ C(6 + k, 3) |s|³/|z|^(7+k),
// so C_K(x) = Σ_k C(k+3, 3) C(6+k, 3) x^k. Both are power series with coefficients ≥ 0, so
// convex: on [0, kTreeX] below their chords, C(x) ≤ C(0) + (C(kTreeX) − C(0)) x/kTreeX (C_H(0) =
// 10, C_K(0) = 20). The solid angle's n·d/r³ = −n·∇(1/r): 4 |s|³/z⁵ (Legendre, |P_4| ≤ 1).
struct TreeConstants {
  double c_h0 = 0.0, c_h = 0.0, c_k0 = 0.0, c_k = 0.0;  // C(0) and C(kTreeX)
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
    c_h0 = 4.0 * binom(5, 4) / 2.0;
    c_k0 = binom(6, 3);
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

}  // namespace

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
  double s4 = 0.0;  // ∫|s|⁴ dA
  for (int j = node.begin; j < node.end; ++j) {
    const Triangle& t = tris[order[j]];
    for (int a = 0; a < 3; ++a) {
      const double e[3] = {t.v[a][0] - c.p[0], t.v[a][1] - c.p[1], t.v[a][2] - c.p[2]};
      c.rho = std::max(c.rho, std::sqrt(dot(e, e)));
    }
    c.reach = std::max(c.reach, std::sqrt(t.near2));
    for (int q = 0; q < kFarPoints; ++q) {
      const double sv[3] = {t.qx[q] - c.p[0], t.qy[q] - c.p[1], t.qz[q] - c.p[2]};
      const double w = t.wq[q], ss = dot(sv, sv);
      s4 += w * ss * ss;
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
  // ∫|s|³ dA ≤ √(∫|s|² dA ∫|s|⁴ dA) (Cauchy–Schwarz; the moments exact), and ≤ ρ³ area
  c.r3 = std::min(c.rho * c.rho * c.rho, std::sqrt(c.tr2 * s4) / area);
  return c;
}

// A cluster's remainder bounds per unit area at z = |p − y| − ρ (valid: z > 0, ε ≤ kTreeX z),
// r3 ≥ (1/area) ∫|s|³ dA: J's tail C_H(ε/z) r3/z⁶, the solid angle's 4 r3/z⁵, and with the
// gradient k's C_K(ε/z) r3/z⁷. Taken only beyond its triangles' near radii (z ≥ reach, so
// |y − c_t| ≥ z: none of them near y): a triangle near y is always summed one by one
// (cancelled_edges relies on it).
Bounds cluster_bounds(const BodyIntegral::Cluster& c, double eps, double z, bool want_b) {
  if (!(z > 0.0 && eps <= kTreeX * z && z >= c.reach)) return {false, 0.0, 0.0, 0.0};
  const TreeConstants& tc = tree_constants();
  const double x = eps / (kTreeX * z);  // ε/z as a fraction of kTreeX, ≤ 1
  const double c_h = tc.c_h0 + (tc.c_h - tc.c_h0) * x, c_k = tc.c_k0 + (tc.c_k - tc.c_k0) * x;
  const double r3 = c.r3, z2 = z * z, z5 = z2 * z2 * z;
  return {true, c_h * r3 / (z5 * z), 4.0 * r3 / z5, want_b ? c_k * r3 / (z5 * z2) : 0.0};
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

}  // namespace softhd::detail::body
