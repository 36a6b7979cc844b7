// BodyIntegral's far rules (Dunavant's 16 points, Radon's 7) and the triangles summed one by
// one, near or far (body_integral.hpp).

#include <cmath>

#include "body_integral_internal.hpp"

namespace softhd::detail::body {

namespace {

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

}  // namespace

// The far triangles' exact Σ ω_t from the rule's estimate: off the surface the total solid angle
// Σ_all ω_t is 4π × the winding number, so Σ_far ω_t = 4π round((S_near + S_est)/4π) − S_near
// (the estimate's error, ~1e-6 of 4π, is far below 2π). On the surface the total is the
// interior angle at y (2π on a face): the estimate stays, and J ~ G∞ there is not small.
double far_solid_angle(double near_sum, double estimate, bool on_surface) {
  if (on_surface) return estimate;
  const double four_pi = 4.0 * 3.14159265358979323846;
  return four_pi * std::round((near_sum + estimate) / four_pi) - near_sum;
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

// The triangles tris[begin, end) one by one (a leaf of the tree, or all of them).
void direct_range(const std::vector<Triangle>& tris, int begin, int end, const Radial& k,
                  const Rules& rule, const double* y, bool want_b, bool coulomb, PointSums* s) {
  for (int j = begin; j < end; ++j) {
    const Triangle& t = tris[j];
    const int skip = distance2(t, y) < t.near2 ? cancelled_edges(tris, j, y) : 0;
    direct_triangle(t, k, rule, y, want_b, coulomb, s, skip);
  }
}

}  // namespace softhd::detail::body
