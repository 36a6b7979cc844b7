// The continuum inner integral of a body from its boundary (lib/src/hausdorff/body_integral.hpp):
// J(y) = ∫_Ω (|y − x| + ε)^−α dx against independent references (the half-space profile, the
// box code of studies/continuum_reference.py, a brute-force quadrature over corner boxes, the
// multipole expansion far away), and its derivatives by Taylor tests.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <map>
#include <random>
#include <vector>

#include "common/gauss_legendre.hpp"
#include "common/surface_bvh.hpp"
#include "hausdorff/body_integral.hpp"
#include "hausdorff/body_integral_internal.hpp"
#include "softhd/error.hpp"
#include "softhd/fe/boundary.hpp"
#include "softhd/fe/mesh.hpp"

namespace {

using softhd::TriangleSurface;
using softhd::detail::BodyIntegral;
using softhd::detail::BodyIntegralOptions;
constexpr double kPi = 3.14159265358979323846;

// The box [lo, hi], each face split into n × n squares of two triangles, outward oriented,
// the points shared between faces.
TriangleSurface box_surface(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, int n) {
  std::map<long, int> index;
  std::vector<Eigen::Vector3d> pts;
  std::vector<Eigen::Vector3i> tris;
  auto point = [&](int i, int j, int k) {
    const long key = (static_cast<long>(i) * (n + 1) + j) * (n + 1) + k;
    auto it = index.find(key);
    if (it != index.end()) return it->second;
    const Eigen::Vector3d f(i / double(n), j / double(n), k / double(n));
    pts.push_back(lo + (hi - lo).cwiseProduct(f));
    index[key] = static_cast<int>(pts.size()) - 1;
    return static_cast<int>(pts.size()) - 1;
  };
  for (int ax = 0; ax < 3; ++ax)
    for (int side = 0; side < 2; ++side)
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
          int q[4];
          const int di[4] = {0, 1, 1, 0}, dj[4] = {0, 0, 1, 1};
          for (int c = 0; c < 4; ++c) {  // (b1, b2) = (ax + 1, ax + 2): e_b1 × e_b2 = e_ax
            int ijk[3];
            ijk[ax] = side * n;
            ijk[(ax + 1) % 3] = i + di[c];
            ijk[(ax + 2) % 3] = j + dj[c];
            q[c] = point(ijk[0], ijk[1], ijk[2]);
          }
          if (side == 1) {
            tris.emplace_back(q[0], q[1], q[2]);
            tris.emplace_back(q[0], q[2], q[3]);
          } else {
            tris.emplace_back(q[0], q[2], q[1]);
            tris.emplace_back(q[0], q[3], q[2]);
          }
        }
  TriangleSurface s;
  s.points.resize(pts.size(), 3);
  for (std::size_t i = 0; i < pts.size(); ++i) s.points.row(i) = pts[i];
  s.triangles.resize(tris.size(), 3);
  for (std::size_t t = 0; t < tris.size(); ++t) s.triangles.row(t) = tris[t];
  return s;
}

double J_at(const BodyIntegral& body, const Eigen::Vector3d& y) {
  Eigen::VectorXd v;
  body.evaluate(y.transpose(), &v);
  return v[0];
}

// The half-space profile at depth d (d ≥ 0 inside, ε, α = 4; docs/formulation.md §2.8).
double halfspace_inside(double d, double eps) {
  return 4.0 * kPi / (3.0 * eps) - kPi / (d + eps) + kPi * eps / (3.0 * (d + eps) * (d + eps));
}
double halfspace_outside(double D, double eps) {
  return kPi / (D + eps) - kPi * eps / (3.0 * (D + eps) * (D + eps));
}

TEST(BodyIntegral, HalfSpaceProfile) {
  // The box [−L, L]² × [−2L, 0] holds the half-ball of radius L about the origin; what the
  // half-space adds lies beyond |x| = L, at distance ≥ L − 1 from y (|y| ≤ 1), so
  // 0 ≤ J_half − J_box ≤ 2π ∫_{L−1}^∞ (s + 1)² s^−4 ds < 2π/(L − 2) ≈ 6.3e-6.
  const double L = 1e6, eps = 1e-3;
  const TriangleSurface box =
      box_surface(Eigen::Vector3d(-L, -L, -2 * L), Eigen::Vector3d(L, L, 0.0), 1);
  BodyIntegralOptions o;
  const BodyIntegral body(box, o);
  const double far = 2.0 * kPi / (L - 2.0);
  for (double d : {0.0, 1e-4, 1e-3, 2e-3, 0.01, 0.1, 0.5, 1.0}) {
    const double in = J_at(body, Eigen::Vector3d(0.3, -0.2, -d));
    const double ref_in = halfspace_inside(d, eps);
    EXPECT_LE(ref_in - in, far + 1e-12 * ref_in) << "depth " << d;
    EXPECT_GE(ref_in - in, -1e-12 * ref_in) << "depth " << d;
    const double out = J_at(body, Eigen::Vector3d(0.3, -0.2, d));
    const double ref_out = halfspace_outside(d, eps);
    EXPECT_LE(ref_out - out, far + 1e-12 * ref_out) << "distance " << d;
    EXPECT_GE(ref_out - out, -1e-12 * ref_out) << "distance " << d;
  }
}

// Reference values of J on the unit cube (ε = 1e-3, α = 4) by the box code of
// studies/continuum_reference.py (corner boxes, a different decomposition), 96 angle points
// (64 points agree to 4e-12 relative):
//   cd studies && python3 -c "from continuum_reference import *; import numpy as np;
//     print(J_box(np.array(POINTS), np.zeros(3), np.ones(3), 1e-3, Rule(96)))"
// with POINTS the rows of kCubePoints.
const double kCubePoints[][3] = {{0.3, 0.45, 0.6}, {0.5, 0.5, 0.5},    {0.5, 0.4, 0.0015},
                                 {0.3, 0.6, 0.0},  {0.4, 0.0, 0.0},    {0.0, 0.0, 0.0},
                                 {1.0, 1.0, 1.0},  {1.2, 0.5, 0.3},    {-0.0005, 0.3, 0.7},
                                 {1.5, 1.5, 1.5},  {0.999, 0.002, 0.5}};
const double kCubeJ[] = {4165.5119817074219,  4167.9703912618506, 3090.3213188182008,
                         2083.9810896848112,  1043.3371098508883, 522.29534473667718,
                         522.29534473667718,  8.1101019721785406, 1617.782169203454,
                         0.13615176763073578, 2334.0725297676745};

TEST(BodyIntegral, UnitCubeAgainstTheBoxCode) {
  // near_ratio 16: every triangle of these meshes is near every point but the corner
  // (1.5, 1.5, 1.5) (the polar rule, exact to its angle rule, ~1e-13); with the default 4,
  // the far rule's error on the far triangles, measured ≤ 1.4e-9 relative on 250 points
  // around the cube at n = 4, 8, 16 (docs/formulation.md §2.8).
  const int count = sizeof(kCubeJ) / sizeof(double);
  Eigen::MatrixXd y(count, 3);
  for (int k = 0; k < count; ++k)
    y.row(k) << kCubePoints[k][0], kCubePoints[k][1], kCubePoints[k][2];
  BodyIntegralOptions near;
  near.near_ratio = 16.0;
  const TriangleSurface s1 = box_surface(Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones(), 1);
  const TriangleSurface s3 = box_surface(Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones(), 3);
  Eigen::VectorXd j1, j3, jd;
  BodyIntegral(s1, near).evaluate(y, &j1);
  BodyIntegral(s3, near).evaluate(y, &j3);
  BodyIntegral(s3, BodyIntegralOptions{}).evaluate(y, &jd);
  for (int k = 0; k < count; ++k) {
    EXPECT_NEAR(j1[k], kCubeJ[k], 1e-10 * kCubeJ[k]) << "point " << k << ", 12 triangles";
    EXPECT_NEAR(j3[k], kCubeJ[k], 1e-10 * kCubeJ[k]) << "point " << k << ", 108 triangles";
    EXPECT_NEAR(j1[k], j3[k], 1e-11 * kCubeJ[k]) << "point " << k << ": depends on the mesh";
    EXPECT_NEAR(jd[k], kCubeJ[k], 2e-9 * kCubeJ[k]) << "point " << k << ", default near_ratio";
  }
}

TEST(BodyIntegral, FeBoundaryOfAQ2Cube) {
  // fe::boundary_surface of the unit cube's 2 × 2 × 2 Q2 mesh (each Q2 facet cut into 8
  // triangles through its nodes): closed, outward, and the same J as the box code.
  const softhd::fe::Mesh mesh = softhd::fe::make_box_mesh(
      Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones(), Eigen::Vector3i(2, 2, 2), 2);
  const TriangleSurface s =
      softhd::fe::boundary_surface(mesh, Eigen::VectorXd::Zero(3 * mesh.num_nodes()));
  BodyIntegralOptions near;
  near.near_ratio = 16.0;
  const BodyIntegral body(s, near);
  const int count = sizeof(kCubeJ) / sizeof(double);
  for (int k = 0; k < count; ++k) {
    const Eigen::Vector3d y(kCubePoints[k][0], kCubePoints[k][1], kCubePoints[k][2]);
    EXPECT_NEAR(J_at(body, y), kCubeJ[k], 1e-10 * kCubeJ[k]) << "point " << k;
  }
}

// 12-point Gauss–Legendre on [−1, 1]: the positive nodes and their weights.
const double kGx[6] = {0.1252334085114689, 0.3678314989981802, 0.5873179542866175,
                       0.7699026741943047, 0.9041172563704749, 0.9815606342467192};
const double kGw[6] = {0.2491470458134028, 0.2334925365383548, 0.2031674267230659,
                       0.1600783285433462, 0.1069393259953184, 0.0471753363865118};

// ∫_lo^hi f by 12-point Gauss–Legendre on panels graded geometrically from lo (first
// width `first`, ratio 2).
template <class F>
double graded(double lo, double hi, double first, F&& f) {
  double sum = 0.0, a = lo, b = std::min(hi, lo + first);
  while (a < hi) {
    for (int i = 0; i < 6; ++i)
      for (int sg : {-1, 1})
        sum += 0.5 * (b - a) * kGw[i] * f(0.5 * (a + b) + sg * 0.5 * (b - a) * kGx[i]);
    a = b;
    b = std::min(hi, lo + 2.0 * (b - lo));
  }
  return sum;
}

// ∫_[0,a]×[0,b]×[0,c] (|x| + ε)^−α dx: three pyramids with apex 0 over the far faces,
// x = s (h, η, ζ) on the one of height h (Jacobian h s²), each axis by graded Gauss rules
// (towards s = 0 from ε/(10ρ); towards η, ζ = 0 from h/2).
double corner_bruteforce(double a, double b, double c, double eps, double alpha) {
  auto pyramid = [&](double h, double p, double q) {
    if (h == 0.0 || p == 0.0 || q == 0.0) return 0.0;
    return graded(0.0, p, 0.5 * h, [&](double eta) {
      return graded(0.0, q, 0.5 * h, [&](double zeta) {
        const double rho = std::sqrt(h * h + eta * eta + zeta * zeta);
        return h * graded(0.0, 1.0, eps / (10.0 * rho),
                          [&](double s) { return s * s * std::pow(s * rho + eps, -alpha); });
      });
    });
  };
  return pyramid(a, b, c) + pyramid(b, a, c) + pyramid(c, a, b);
}

// J of the box [lo, hi] by corner boxes split at y (signed by inclusion–exclusion outside).
double box_bruteforce(const Eigen::Vector3d& y, const Eigen::Vector3d& lo,
                      const Eigen::Vector3d& hi, double eps, double alpha) {
  double sum = 0.0;
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j)
      for (int k = 0; k < 2; ++k) {
        const int pick[3] = {i, j, k};
        double d[3], sign = ((3 - i - j - k) % 2) ? -1.0 : 1.0;
        for (int ax = 0; ax < 3; ++ax) {
          d[ax] = (pick[ax] ? hi[ax] : lo[ax]) - y[ax];
          sign *= d[ax] > 0 ? 1.0 : (d[ax] < 0 ? -1.0 : 0.0);
        }
        if (sign != 0.0)
          sum +=
              sign * corner_bruteforce(std::abs(d[0]), std::abs(d[1]), std::abs(d[2]), eps, alpha);
      }
  return sum;
}

TEST(BodyIntegral, GeneralAlphaAgainstBruteForce) {
  // The radial closed forms with logarithms (α = 1, 2, 3) and a non-integer α, inside and
  // outside, against a brute-force volume quadrature over corner boxes (no divergence
  // theorem; its accuracy: ~1e-13 relative for α = 4 at ε = 0.1 against the α = 4 closed form).
  const double eps = 0.1;  // a larger ε keeps the brute force's panels few
  const Eigen::Vector3d lo(0.0, 0.0, 0.0), hi(1.0, 0.8, 0.6);
  const TriangleSurface box = box_surface(lo, hi, 2);
  const Eigen::Vector3d points[2] = {{0.3, 0.45, 0.25}, {1.3, 0.5, 0.2}};
  for (double alpha : {1.0, 2.0, 3.0, 4.0, 5.5}) {
    BodyIntegralOptions o;
    o.epsilon = eps;
    o.alpha = alpha;
    const BodyIntegral body(box, o);
    for (const Eigen::Vector3d& y : points) {
      const double ref = box_bruteforce(y, lo, hi, eps, alpha);
      EXPECT_NEAR(J_at(body, y), ref, 1e-10 * ref) << "alpha " << alpha << " at " << y.transpose();
    }
  }
}

TEST(BodyIntegral, RadialPrimitiveBelowEpsilon) {
  // G(r) = ∫₀^r u²(u + ε)^−α du where the closed form cancels (r ≪ ε: the binomial series),
  // around the switch r = ε/4 and above, against the graded Gauss rule.
  const double eps = 1e-3;
  for (double alpha : {1.0, 2.0, 2.5, 3.0, 4.0, 7.0})
    for (double r : {1e-9, 1e-6, 1e-4, 2.4999e-4, 2.5001e-4, 1e-3, 0.3}) {
      const double ref = graded(0.0, r, std::min(r, eps) / 64.0,
                                [&](double u) { return u * u * std::pow(u + eps, -alpha); });
      EXPECT_NEAR(softhd::detail::radial_g(r, eps, alpha), ref, 1e-13 * ref)
          << "alpha " << alpha << ", r " << r;
    }
}

TEST(BodyIntegral, FarPointMultipole) {
  // With the centre c of the unit cube at distance D from y, k(r) = (r + ε)^−4 expands as
  // J = k(D) + Δk(D)/24 + R₄: the odd moments vanish, ∫ ξξᵀ = I/12, Δk = k'' + 2k'/D. The
  // remainder is bounded by (1/4!) max|∂⁴k| ∫|ξ|⁴ ≤ (840/24) (D − √3/2)^−8 · 0.0792 (a
  // directional 4th derivative of r^−4 is at most 4·5·6·7 r^−8, the Gegenbauer bound;
  // ∫|ξ|⁴ = 3/80 + 6/144; with ε/D ≤ 1.3e-4 the same bound to that order). Every triangle is
  // far here: this checks the far rule and the point-charge sum (J ~ 1e-6 at D = 32, against
  // terms ω_t/(3ε) ~ 1e-1).
  const double eps = 1e-3;
  const BodyIntegral body(box_surface(Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones(), 2), {});
  const Eigen::Vector3d c(0.5, 0.5, 0.5), dir = Eigen::Vector3d(0.6, -0.48, 0.64).normalized();
  for (double D : {8.0, 16.0, 32.0}) {
    const double w = D + eps;
    const double k = std::pow(w, -4.0), k1 = -4.0 * std::pow(w, -5.0),
                 k2 = 20.0 * std::pow(w, -6.0);
    const double monopole = k, quad = (k2 + 2.0 * k1 / D) / 24.0;
    const double bound = 35.0 * 0.0792 * std::pow(D - 0.8661, -8.0);
    const double J = J_at(body, c + D * dir);
    EXPECT_NEAR(J, monopole + quad, bound + 1e-12 * J) << "D = " << D;
    EXPECT_GT(std::abs(J - monopole), 3.0 * bound)
        << "D = " << D << ": the bound would not see a missing quadrupole";
  }
}

TEST(BodyIntegral, AdditiveOverTwoHalves) {
  BodyIntegralOptions o;  // every pair near: the polar rule alone, exact to ~1e-13
  o.near_ratio = 16.0;
  const BodyIntegral whole(box_surface(Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones(), 2), o);
  const BodyIntegral left(box_surface(Eigen::Vector3d::Zero(), Eigen::Vector3d(0.5, 1, 1), 2), o);
  const BodyIntegral right(box_surface(Eigen::Vector3d(0.5, 0, 0), Eigen::Vector3d::Ones(), 2), o);
  Eigen::MatrixXd y(5, 3);
  y << 0.5, 0.3, 0.7, 0.5005, 0.2, 0.1, 0.49, 0.5, 0.5, 0.5, 0.0, 0.0, 1.4, 0.3, -0.2;
  Eigen::VectorXd jw, jl, jr;
  Eigen::MatrixXd gw, gl, gr;
  whole.evaluate(y, &jw, &gw);
  left.evaluate(y, &jl, &gl);
  right.evaluate(y, &jr, &gr);
  for (int k = 0; k < y.rows(); ++k) {
    EXPECT_NEAR(jl[k] + jr[k], jw[k], 1e-10 * jw[k]) << "point " << k;
    EXPECT_LT((gl.row(k) + gr.row(k) - gw.row(k)).norm(), 1e-9 * gw.row(k).norm() + 1e-9 * jw[k])
        << "point " << k;
  }
}

// Taylor test: r(h) = |f(h) − f(0) − h f'(0)| for h = h0, h0/2, h0/4, h0/8; the observed
// orders log2(r(h)/r(h/2)) must reach ≥ 1.8 (the first-order term right).
template <class F>
void expect_second_order(F&& f, double slope, double h0, const char* what) {
  const double f0 = f(0.0);
  double prev = -1.0, best = 0.0;
  std::printf("%s:", what);
  for (int i = 0; i < 4; ++i) {
    const double h = h0 / (1 << i);
    const double r = std::abs(f(h) - f0 - h * slope);
    if (prev > 0.0) {
      const double order = std::log2(prev / r);
      best = std::max(best, order);
      std::printf(" %.3f", order);
    }
    prev = r;
  }
  std::printf("\n");
  EXPECT_GE(best, 1.8) << what;
  EXPECT_LE(best, 2.3) << what;
}

// J along y + h v: second order with the slope ∂J/∂y·v; returns J(y).
double expect_y_taylor(const BodyIntegral& body, const Eigen::Vector3d& v, const Eigen::Vector3d& y,
                       double h0, const char* name) {
  Eigen::VectorXd J;
  Eigen::MatrixXd g;
  body.evaluate(y.transpose(), &J, &g);
  expect_second_order([&](double h) { return J_at(body, y + h * v); }, g.row(0).dot(v), h0, name);
  return J[0];
}

TEST(BodyIntegral, GradientInYTaylor) {
  // n = 4: near (polar) and far (7-point) triangles mixed at every point.
  const BodyIntegral body(box_surface(Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones(), 4), {});
  const Eigen::Vector3d v = Eigen::Vector3d(0.3, -0.7, 0.5).normalized();
  const struct {
    Eigen::Vector3d y;
    double h0;
    const char* name;
  } cases[] = {{{0.3, 0.45, 0.6}, 0.04, "inside"},
               {{0.43, 0.37, 0.0015}, 2e-4, "within 2 eps of a face"},
               {{0.42, 0.61, -0.0012}, 2e-4, "outside, within 2 eps"},
               {{1.2, 0.5, 0.3}, 0.04, "outside"},
               {{4.0, 3.0, -2.0}, 0.2, "far"}};
  for (const auto& c : cases) expect_y_taylor(body, v, c.y, c.h0, c.name);
}

// Random directions for every surface point (seed 7).
Eigen::MatrixXd random_field(Eigen::Index rows) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::MatrixXd V(rows, 3);
  for (Eigen::Index i = 0; i < V.size(); ++i) V.data()[i] = u(rng);
  return V;
}

// A Taylor test's point, first step and name.
struct TaylorCase {
  Eigen::Vector3d y;
  double h0;
  const char* name;
};

// F(X) = 0.7 J(y; X) along V: second order with the slope Σ_a vjp_a·V_a; returns the vjp.
Eigen::MatrixXd expect_surface_taylor(const TriangleSurface& s0, const Eigen::MatrixXd& V,
                                      const BodyIntegralOptions& o, const Eigen::Vector3d& y,
                                      double h0, const char* name) {
  const Eigen::VectorXd w = Eigen::VectorXd::Constant(1, 0.7);
  const Eigen::MatrixXd vjp = BodyIntegral(s0, o).surface_vjp(y.transpose(), w);
  auto f = [&](double h) {
    TriangleSurface s = s0;
    s.points += h * V;
    return 0.7 * J_at(BodyIntegral(s, o), y);
  };
  expect_second_order(f, (vjp.array() * V.array()).sum(), h0, name);
  return vjp;
}

TEST(BodyIntegral, SurfaceVjpTaylor) {
  // F(X) = Σ_k w_k J(y_k; X) along a random field V of the surface points: dF = Σ_a vjp_a·V_a.
  const TriangleSurface s0 = box_surface(Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones(), 3);
  const Eigen::MatrixXd V = random_field(s0.points.rows());
  const TaylorCase cases[] = {{{0.3, 0.45, 0.6}, 0.02, "inside"},
                              {{0.43, 0.37, 0.0015}, 2e-4, "within 2 eps of a face"},
                              {{0.2, 1.0008, 0.7}, 2e-4, "outside, within 1 eps"},
                              {{1.2, 0.5, 0.3}, 0.02, "outside"},
                              {{4.0, 3.0, -2.0}, 0.1, "far"}};
  for (const auto& c : cases) expect_surface_taylor(s0, V, {}, c.y, c.h0, c.name);
}

// A lower bound of S = ∫_∂Ω (|y − x| + ε)^−4 dA (ε = 1e-3): Σ A_u (|y − c_u| + R_u + ε)^−4 over
// the 8² similar subtriangles u of each triangle (c_u the centroid, R_u its largest distance to
// a corner: every point of u is within |y − c_u| + R_u of y).
double kernel_area_lower(const TriangleSurface& s, const Eigen::Vector3d& y) {
  const int m = 8;
  double sum = 0.0;
  for (Eigen::Index t = 0; t < s.triangles.rows(); ++t) {
    const Eigen::Vector3d a = s.points.row(s.triangles(t, 0)), b = s.points.row(s.triangles(t, 1)),
                          c = s.points.row(s.triangles(t, 2));
    const Eigen::Vector3d e1 = (b - a) / m, e2 = (c - a) / m, g = (e1 + e2) / 3.0;
    const double sub = 0.5 * e1.cross(e2).norm();
    const double rad = std::max({g.norm(), (g - e1).norm(), (g - e2).norm()});
    auto add = [&](const Eigen::Vector3d& x) {
      const double r2 = 1.0 / ((y - x).norm() + rad + 1e-3) / ((y - x).norm() + rad + 1e-3);
      sum += sub * r2 * r2;
    };
    for (int i = 0; i < m; ++i)
      for (int j = 0; i + j < m; ++j) {  // (o, o + e1, o + e2), and (o + e1, o + e2, o + e1 + e2)
        const Eigen::Vector3d o = a + i * e1 + j * e2;
        add(o + g);
        if (i + j < m - 1) add(o + 2.0 * g);
      }
  }
  return sum;
}

// The tree (tolerance τ) against the all-pairs sums on a 3 × 1 × 0.25 box of 1728 triangles:
// |J̃ − J| ≤ τ J and ‖g̃ − g‖ ≤ τ S, S = ∫_∂Ω k dA (the documented bounds; S by a lower bound,
// so the check is stricter than they are), plus the two
// rules' own difference (the far rules' error, ≤ 1.4e-9 of J measured, §2.8: 1e-8 allowed);
// and the tree must actually differ from all pairs (clusters taken) at most points.
TEST(BodyIntegral, TreeWithinTolerance) {
  const Eigen::Vector3d hi(3.0, 1.0, 0.25);
  const TriangleSurface s = box_surface(Eigen::Vector3d::Zero(), hi, 12);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-0.4, 1.4);
  std::vector<Eigen::Vector3d> ys;
  while (ys.size() < 40) {  // at least 0.05 from the surface (S's lower bound stays close)
    const Eigen::Vector3d y = Eigen::Vector3d(u(rng), u(rng), u(rng)).cwiseProduct(hi);
    const Eigen::Vector3d in = y.cwiseMax(Eigen::Vector3d::Zero()).cwiseMin(hi);
    const double out = (y - in).norm(), depth = std::min(in.minCoeff(), (hi - in).minCoeff());
    if ((out > 0.0 ? out : depth) >= 0.05) ys.push_back(y);
  }
  Eigen::MatrixXd y(ys.size(), 3);
  Eigen::VectorXd S(ys.size());
  for (std::size_t k = 0; k < ys.size(); ++k) {
    y.row(k) = ys[k].transpose();
    S[k] = kernel_area_lower(s, ys[k]);
  }
  BodyIntegralOptions all;
  all.threads = 2;
  Eigen::VectorXd j0, jv;
  Eigen::MatrixXd g0;
  BodyIntegral(s, all).evaluate(y, &j0, &g0);
  Eigen::MatrixXd near(6, 3);  // within 3 ε of a face, on both sides, values only
  near << 0.7, 0.4, 0.0015, 2.2, 0.55, 0.2525, 1.4, -0.002, 0.1, 2.9, 0.3, -0.0008, 0.31, 1.001,
      0.2, 2.9985, 0.6, 0.15;
  Eigen::VectorXd jn0;
  BodyIntegral(s, all).evaluate(near, &jn0);
  for (double tau : {1e-2, 1e-4}) {
    BodyIntegralOptions o = all;
    o.tolerance = tau;
    const BodyIntegral tree(s, o);
    Eigen::VectorXd j1;
    Eigen::MatrixXd g1;
    tree.evaluate(y, &j1, &g1);
    tree.evaluate(y, &jv);  // value only: its own budget (no gradient's)
    int differs = 0;
    double worst_j = 0.0, worst_g = 0.0;
    for (Eigen::Index k = 0; k < y.rows(); ++k) {
      const double ej = std::abs(j1[k] - j0[k]) / j0[k], ev = std::abs(jv[k] - j0[k]) / j0[k];
      const double eg = (g1.row(k) - g0.row(k)).norm() / S[k];
      EXPECT_LE(ej, tau + 1e-8) << "tau " << tau << ", point " << k;
      EXPECT_LE(ev, tau + 1e-8) << "tau " << tau << ", point " << k << " (value only)";
      EXPECT_LE(eg, tau + 1e-8) << "tau " << tau << ", point " << k;
      differs += ev > 1e-12;
      worst_j = std::max({worst_j, ej, ev});
      worst_g = std::max(worst_g, eg);
    }
    Eigen::VectorXd jn;
    tree.evaluate(near, &jn);
    for (Eigen::Index k = 0; k < near.rows(); ++k) {
      const double e = std::abs(jn[k] - jn0[k]) / jn0[k];
      EXPECT_LE(e, tau + 1e-8) << "tau " << tau << ", near point " << k;
      differs += e > 1e-12;
      worst_j = std::max(worst_j, e);
    }
    std::printf("tau %.0e: largest |dJ|/J %.2e, |dg|/S %.2e; %d of %ld values by the tree\n", tau,
                worst_j, worst_g, differs, static_cast<long>(y.rows() + near.rows()));
    EXPECT_GE(differs, y.rows() / 2) << "tau " << tau << ": the tree took (almost) no cluster";
  }
}

// The surface product by the tree against all pairs: Σ_{t,a} of the corner sums' errors is at
// most τ Σ_k |w_k| S_k; per surface point a, ‖Δvjp_a‖ ≤ Σ_{t ∋ a} |Δ corner sum| (unit normals),
// so Σ_a ‖Δvjp_a‖ ≤ τ Σ_k |w_k| S_k (S_k by its lower bound: a stricter check).
TEST(BodyIntegral, TreeSurfaceVjpWithinTolerance) {
  const Eigen::Vector3d hi(3.0, 1.0, 0.25);
  const TriangleSurface s = box_surface(Eigen::Vector3d::Zero(), hi, 12);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-0.4, 1.4);
  std::vector<Eigen::Vector3d> ys;
  while (ys.size() < 40) {
    const Eigen::Vector3d y = Eigen::Vector3d(u(rng), u(rng), u(rng)).cwiseProduct(hi);
    const Eigen::Vector3d in = y.cwiseMax(Eigen::Vector3d::Zero()).cwiseMin(hi);
    const double out = (y - in).norm(), depth = std::min(in.minCoeff(), (hi - in).minCoeff());
    if ((out > 0.0 ? out : depth) >= 0.05) ys.push_back(y);
  }
  Eigen::MatrixXd y(ys.size(), 3);
  const Eigen::VectorXd w = Eigen::VectorXd::LinSpaced(ys.size(), -1.0, 2.0);
  double budget = 0.0;  // Σ_k |w_k| S_k
  for (std::size_t k = 0; k < ys.size(); ++k) {
    y.row(k) = ys[k].transpose();
    budget += std::abs(w[k]) * kernel_area_lower(s, ys[k]);
  }
  BodyIntegralOptions all;
  all.threads = 2;
  const Eigen::MatrixXd v0 = BodyIntegral(s, all).surface_vjp(y, w);
  for (double tau : {1e-2, 1e-4}) {
    BodyIntegralOptions o = all;
    o.tolerance = tau;
    const Eigen::MatrixXd v1 = BodyIntegral(s, o).surface_vjp(y, w);
    const double err = (v1 - v0).rowwise().norm().sum();
    std::printf("tau %.0e: sum_a |dvjp_a| %.2e = %.2e of sum_k |w_k| S_k\n", tau, err,
                err / budget);
    EXPECT_LE(err, (tau + 1e-8) * budget) << "tau " << tau;
    EXPECT_GT(err, 1e-12 * budget) << "tau " << tau << ": the tree took no cluster";
  }
}

TEST(BodyIntegral, TreeSurfaceVjpTaylor) {
  // As SurfaceVjpTaylor, the product and the values by the tree (τ = 1e-6), the box of
  // TreeWithinTolerance and points far enough from one end to take clusters there.
  const TriangleSurface s0 =
      box_surface(Eigen::Vector3d::Zero(), Eigen::Vector3d(3.0, 1.0, 0.25), 8);
  const Eigen::MatrixXd V = random_field(s0.points.rows());
  const TaylorCase cases[] = {{{0.3, 0.45, 0.12}, 0.02, "tree, inside"},
                              {{0.43, 0.37, 0.0015}, 2e-4, "tree, within 2 eps of a face"},
                              {{-0.3, 0.5, 0.1}, 0.02, "tree, outside"}};
  BodyIntegralOptions o;
  o.tolerance = 1e-6;
  int by_tree = 0;
  for (const auto& c : cases) {
    const Eigen::MatrixXd vjp = expect_surface_taylor(s0, V, o, c.y, c.h0, c.name);
    const Eigen::MatrixXd all =
        BodyIntegral(s0, {}).surface_vjp(c.y.transpose(), Eigen::VectorXd::Constant(1, 0.7));
    by_tree += (vjp - all).norm() > 1e-12 * all.norm();  // above the sums' rounding
  }
  EXPECT_GE(by_tree, 2) << "the tree took clusters at too few of the points";
}

TEST(BodyIntegral, TreeGradientInYTaylor) {
  // The tree's gradient agrees with its value up to τ S (both within τ of all pairs): at
  // τ = 1e-4 that is far below the Taylor remainders here, and the tree takes clusters.
  BodyIntegralOptions o;
  o.tolerance = 1e-4;
  const BodyIntegral body(box_surface(Eigen::Vector3d::Zero(), Eigen::Vector3d(3.0, 1.0, 0.25), 12),
                          o);
  const Eigen::Vector3d v = Eigen::Vector3d(0.3, -0.7, 0.5).normalized();
  const TaylorCase cases[] = {{{0.3, 0.45, 0.12}, 0.02, "tree, inside"},
                              {{0.43, 0.37, 0.0015}, 2e-4, "tree, within 2 eps of a face"},
                              {{-0.3, 0.5, 0.1}, 0.04, "tree, outside"},
                              {{8.0, 3.0, -2.0}, 0.2, "tree, far"}};
  const BodyIntegral all(box_surface(Eigen::Vector3d::Zero(), Eigen::Vector3d(3.0, 1.0, 0.25), 12),
                         {});
  int by_tree = 0;
  for (const auto& c : cases) {
    const double J = expect_y_taylor(body, v, c.y, c.h0, c.name);
    by_tree += std::abs(J - J_at(all, c.y)) > 1e-12 * J;  // above the sums' rounding
  }
  EXPECT_GE(by_tree, 3) << "the tree took clusters at too few of the points";
}

TEST(BodyIntegral, RigidMotionInvariance) {
  const TriangleSurface s0 =
      box_surface(Eigen::Vector3d::Zero(), Eigen::Vector3d(1.0, 0.7, 0.4), 3);
  const Eigen::Matrix3d R = (Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()) *
                             Eigen::AngleAxisd(-1.1, Eigen::Vector3d(-2, 0.5, 1).normalized()))
                                .toRotationMatrix();
  const Eigen::RowVector3d t(0.3, -1.2, 2.5);
  TriangleSurface s1 = s0;
  s1.points = (s0.points * R.transpose()).rowwise() + t;
  Eigen::MatrixXd y0(4, 3);
  y0 << 0.3, 0.2, 0.1, 0.5, 0.35, 0.4005, 1.2, -0.3, 0.2, 0.0, 0.7, 0.2;
  const Eigen::MatrixXd y1 = (y0 * R.transpose()).rowwise() + t;
  const BodyIntegralOptions o;
  const BodyIntegral b0(s0, o), b1(s1, o);
  Eigen::VectorXd j0, j1;
  Eigen::MatrixXd g0, g1;
  b0.evaluate(y0, &j0, &g0);
  b1.evaluate(y1, &j1, &g1);
  const Eigen::VectorXd w = Eigen::Vector4d(0.5, -1.0, 2.0, 0.25);
  const Eigen::MatrixXd v0 = b0.surface_vjp(y0, w), v1 = b1.surface_vjp(y1, w);
  for (int k = 0; k < 4; ++k) {
    EXPECT_NEAR(j1[k], j0[k], 1e-11 * j0[k]) << "point " << k;
    EXPECT_LT((g1.row(k) - g0.row(k) * R.transpose()).norm(), 1e-10 * g0.row(k).norm());
  }
  EXPECT_LT((v1 - v0 * R.transpose()).norm(), 1e-10 * v0.norm());
}

// J and ∂J/∂y the same bits on 1 and 2 threads (tolerance τ, 0: all pairs); the surface product
// deterministic, and within rounding of the other thread count's.
void expect_same_on_one_and_two_threads(const TriangleSurface& s, const Eigen::MatrixXd& y,
                                        const Eigen::VectorXd& w, double tau) {
  BodyIntegralOptions one, two;
  one.threads = 1;
  two.threads = 2;
  one.tolerance = two.tolerance = tau;
  Eigen::VectorXd j1, j2;
  Eigen::MatrixXd g1, g2;
  BodyIntegral(s, one).evaluate(y, &j1, &g1);
  BodyIntegral(s, two).evaluate(y, &j2, &g2);
  EXPECT_EQ(j1, j2);
  EXPECT_EQ(g1, g2);
  const BodyIntegral b2(s, two);
  EXPECT_EQ(b2.surface_vjp(y, w), b2.surface_vjp(y, w));
  EXPECT_LT((BodyIntegral(s, one).surface_vjp(y, w) - b2.surface_vjp(y, w)).norm(),
            1e-12 * b2.surface_vjp(y, w).norm());
}

TEST(BodyIntegral, ThreadsGiveTheSameNumbers) {
  // The values and y-gradients are per point (the same bits for any thread count); the
  // surface product sums per-thread accumulators in thread order (the same bits per count).
  const TriangleSurface s = box_surface(Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones(), 3);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-0.2, 1.2);
  Eigen::MatrixXd y(40, 3);
  for (Eigen::Index i = 0; i < y.size(); ++i) y.data()[i] = u(rng);
  const Eigen::VectorXd w = Eigen::VectorXd::LinSpaced(40, -1.0, 2.0);
  expect_same_on_one_and_two_threads(s, y, w, 0.0);
}

TEST(BodyIntegral, TreeGivesTheSameNumbersOnAnyThreads) {
  // The tree's budgets chain within fixed blocks of 64 points: values and y-gradients are the
  // same bits for any thread count; the surface product as the all-pairs one.
  const TriangleSurface s =
      box_surface(Eigen::Vector3d::Zero(), Eigen::Vector3d(3.0, 1.0, 0.25), 6);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-0.2, 1.2);
  Eigen::MatrixXd y(130, 3);  // three blocks
  for (Eigen::Index i = 0; i < y.rows(); ++i) y.row(i) << 3.0 * u(rng), u(rng), 0.25 * u(rng);
  const Eigen::VectorXd w = Eigen::VectorXd::LinSpaced(130, -1.0, 2.0);
  expect_same_on_one_and_two_threads(s, y, w, 1e-2);
}

// The 2×2×2 Gauss points of cubes of side 0.04 about the centres c (8 consecutive rows each, as
// the cell distance's samples: one group of the tree's traversal per cube).
Eigen::MatrixXd cube_gauss_points(const std::vector<Eigen::Vector3d>& centres) {
  Eigen::MatrixXd y(8 * centres.size(), 3);
  const double g = 0.02 / std::sqrt(3.0);
  for (std::size_t c = 0; c < centres.size(); ++c)
    for (int q = 0; q < 8; ++q)
      y.row(8 * c + q) =
          (centres[c] + g * Eigen::Vector3d(q & 1 ? 1 : -1, q & 2 ? 1 : -1, q & 4 ? 1 : -1))
              .transpose();
  return y;
}

TEST(BodyIntegral, TreeGroupsWithinTolerance) {
  // Rows in tight groups of 8 share one traversal per group (radius 0.02 within the limit
  // ρ_root/32 ≈ 0.05 here): the documented bounds against all pairs hold as for single points
  // (TreeWithinTolerance: S by a lower bound, 1e-8 for the far rules' own difference), values at
  // cubes inside, outside and across a face, gradients and the surface product at those ≥ 0.05
  // from the surface; the same numbers on one and two threads (three blocks of 64 rows).
  const Eigen::Vector3d hi(3.0, 1.0, 0.25);
  const TriangleSurface s = box_surface(Eigen::Vector3d::Zero(), hi, 8);
  std::vector<Eigen::Vector3d> away, across;
  for (int i = 0; i < 12; ++i) {
    const double x = 0.1 + 0.25 * i, yy = 0.5 + 0.3 * std::sin(1.7 * i);
    away.emplace_back(x, yy, i % 3 == 0 ? 0.125 : (i % 3 == 1 ? 0.4 : -0.2));
  }
  for (int i = 0; i < 6; ++i)  // across the top face, and about its edge y = 0
    across.emplace_back(0.3 + 0.45 * i, i % 2 ? 0.001 : 0.5, i < 4 ? 0.25 : 0.249);
  const Eigen::MatrixXd ya = cube_gauss_points(away), yc = cube_gauss_points(across);
  Eigen::VectorXd S(ya.rows());
  for (Eigen::Index k = 0; k < ya.rows(); ++k) S[k] = kernel_area_lower(s, ya.row(k).transpose());
  const Eigen::VectorXd w = Eigen::VectorXd::LinSpaced(ya.rows(), -1.0, 2.0);
  const double vjp_budget = w.cwiseAbs().dot(S);
  BodyIntegralOptions all;
  Eigen::VectorXd j0, jc0;
  Eigen::MatrixXd g0;
  const BodyIntegral pairs(s, all);
  pairs.evaluate(ya, &j0, &g0);
  pairs.evaluate(yc, &jc0);
  const Eigen::MatrixXd v0 = pairs.surface_vjp(ya, w);
  for (double tau : {1e-2, 1e-4}) {
    BodyIntegralOptions o = all;
    o.tolerance = tau;
    const BodyIntegral tree(s, o);
    Eigen::VectorXd j1, jc1;
    Eigen::MatrixXd g1;
    tree.evaluate(ya, &j1, &g1);
    tree.evaluate(yc, &jc1);
    int differs = 0;
    double worst_j = 0.0, worst_g = 0.0;
    for (Eigen::Index k = 0; k < ya.rows(); ++k) {
      worst_j = std::max(worst_j, std::abs(j1[k] - j0[k]) / j0[k]);
      worst_g = std::max(worst_g, (g1.row(k) - g0.row(k)).norm() / S[k]);
      EXPECT_LE(std::abs(j1[k] - j0[k]), (tau + 1e-8) * j0[k]) << "tau " << tau << ", row " << k;
      EXPECT_LE((g1.row(k) - g0.row(k)).norm(), (tau + 1e-8) * S[k])
          << "tau " << tau << ", row " << k;
      differs += std::abs(j1[k] - j0[k]) > 1e-12 * j0[k];
    }
    for (Eigen::Index k = 0; k < yc.rows(); ++k) {
      worst_j = std::max(worst_j, std::abs(jc1[k] - jc0[k]) / jc0[k]);
      EXPECT_LE(std::abs(jc1[k] - jc0[k]), (tau + 1e-8) * jc0[k]) << "tau " << tau << ", row " << k;
    }
    const double err = (tree.surface_vjp(ya, w) - v0).rowwise().norm().sum();
    std::printf("tau %.0e: largest |dJ|/J %.2e, |dg|/S %.2e, product %.2e of its bound\n", tau,
                worst_j, worst_g, err / vjp_budget);
    EXPECT_LE(err, (tau + 1e-8) * vjp_budget) << "tau " << tau;
    EXPECT_GT(err, 1e-12 * vjp_budget) << "tau " << tau << ": the tree took no cluster";
    EXPECT_GE(differs, ya.rows() / 2) << "tau " << tau << ": the tree took (almost) no cluster";
  }
  Eigen::MatrixXd y3(ya.rows() + yc.rows(), 3);
  y3 << ya, yc;
  expect_same_on_one_and_two_threads(s, y3, Eigen::VectorXd::LinSpaced(y3.rows(), -1.0, 2.0), 1e-2);
}

// Every cluster of the tree whose expansions are valid at y: the expansions' differences from
// its triangles summed one by one (the far rules at near_ratio 4, whose own error, ~1e-9 of
// each term, stays far below the bounds) within the proved remainder bounds (J's tail, the solid
// angles, ∂J/∂y and S), at points around and just outside a thin box; some difference comes
// within a factor 3 of its bound (the largest ratios printed), so a bound too small by 3 fails.
TEST(BodyIntegral, ClusterRemaindersWithinTheirBounds) {
  namespace body = softhd::detail::body;
  const Eigen::Vector3d hi(3.0, 1.0, 0.25);
  const TriangleSurface s = box_surface(Eigen::Vector3d::Zero(), hi, 8);
  const softhd::detail::Bvh bvh = softhd::detail::build_bvh(s);
  std::vector<body::Triangle> tris, ordered;  // in the surface's order, in the tree's
  for (Eigen::Index t = 0; t < s.triangles.rows(); ++t) {
    double v[3][3], area2;
    for (int a = 0; a < 3; ++a)
      for (int i = 0; i < 3; ++i) v[a][i] = s.points(s.triangles(t, a), i);
    tris.push_back(body::make_triangle(v, 4.0, &area2));
    std::fill(tris.back().twin, tris.back().twin + 3, -1);
  }
  for (int t : bvh.order) ordered.push_back(tris[t]);
  std::vector<body::Cluster> clusters;
  for (const softhd::detail::BvhNode& node : bvh.nodes)
    clusters.push_back(body::make_cluster(tris, bvh.order, node));
  for (const body::Cluster& c : clusters) {  // r3 bounds the mean |s|³ by ρ³ at most
    EXPECT_LE(c.r3, c.rho * c.rho * c.rho * (1.0 + 1e-14));
  }
  const double eps = 1e-3;
  const body::Radial k(eps, 4.0);
  std::vector<double> gx, gw;
  softhd::detail::gauss_legendre_unit(12, &gx, &gw);
  const body::Rules rule{gx, gw, 2.0};
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(-0.5, 1.5);
  double worst[4] = {0.0, 0.0, 0.0, 0.0};  // |difference|/bound: J, ω, g, S
  int taken = 0;
  for (int n = 0; n < 200; ++n) {
    Eigen::Vector3d y = Eigen::Vector3d(u(rng), u(rng), u(rng)).cwiseProduct(hi);
    if (n % 2) y[2] = n % 4 == 1 ? 0.2501 : -0.0001;  // just outside the large faces
    for (const body::Cluster& c : clusters) {
      const double d[3] = {c.p[0] - y[0], c.p[1] - y[1], c.p[2] - y[2]};
      const double z = std::sqrt(body::dot(d, d)) - c.rho;
      const body::Bounds e = body::cluster_bounds(c, eps, z, true);
      if (!e.valid) continue;
      body::PointSums a, b;
      body::take_cluster(c, eps, y.data(), true, e, &a);
      body::direct_range(ordered, c.begin, c.end, k, rule, y.data(), true, true, &b);
      const double diff[4] = {
          std::abs(a.J - b.J), std::abs(a.far_omega - b.far_omega),
          std::sqrt(std::pow(a.g[0] - b.g[0], 2) + std::pow(a.g[1] - b.g[1], 2) +
                    std::pow(a.g[2] - b.g[2], 2)),
          std::abs(a.S - b.S)};
      const double bound[4] = {a.err_j, a.err_omega, a.err_g, a.err_g};
      for (int q = 0; q < 4; ++q) {
        EXPECT_LE(diff[q], bound[q])
            << "quantity " << q << ", cluster " << &c - clusters.data() << ", point " << n;
        worst[q] = std::max(worst[q], diff[q] / bound[q]);
      }
      ++taken;
    }
  }
  std::printf(
      "%d cluster-point pairs; largest difference/bound: J %.3f, omega %.3f, g %.3f, S %.3f\n",
      taken, worst[0], worst[1], worst[2], worst[3]);
  EXPECT_GT(taken, 10000);
  EXPECT_GT(*std::max_element(worst, worst + 4), 1.0 / 3.0)
      << "the points found no case where a bound too small by 3 would fail";
}

TEST(BodyIntegral, CoplanarWedgesCancel) {
  // On a flat face the wedges of an edge shared by two near triangles cancel and are left out;
  // moving the surface points by ~1e-11 makes no two triangles coplanar (to 1e-13), so there
  // every wedge is summed: J and ∂J/∂y agree to what the shift itself moves (≲ 1e-8 relative at
  // 2ε from a face), many pairs near (near_ratio 8).
  const TriangleSurface flat = box_surface(Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones(), 4);
  TriangleSurface bent = flat;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1e-11, 1e-11);
  for (Eigen::Index i = 0; i < bent.points.size(); ++i) bent.points.data()[i] += u(rng);
  Eigen::MatrixXd y(6, 3);
  y << 0.5, 0.5, 0.5, 0.3, 0.6, 0.002, 0.7, 0.2, -0.002, 1.3, 0.4, 0.5, 0.12, 0.998, 0.5, 0.01,
      0.01, 0.01;
  BodyIntegralOptions o;
  o.near_ratio = 8.0;
  Eigen::VectorXd j0, j1;
  Eigen::MatrixXd g0, g1;
  BodyIntegral(flat, o).evaluate(y, &j0, &g0);
  BodyIntegral(bent, o).evaluate(y, &j1, &g1);
  for (Eigen::Index k = 0; k < y.rows(); ++k) {
    EXPECT_LE(std::abs(j1[k] - j0[k]), 1e-8 * j0[k]) << "point " << k;
    EXPECT_LE((g1.row(k) - g0.row(k)).norm(), 1e-8 * g0.row(k).norm() + 1e-8 * j0[k])
        << "point " << k;
  }
}

TEST(BodyIntegral, RejectsBadInput) {
  const TriangleSurface s = box_surface(Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones(), 1);
  BodyIntegralOptions o;
  o.alpha = 0.0;
  EXPECT_THROW(BodyIntegral(s, o), softhd::InvalidArgument);
  o = {};
  o.epsilon = -1.0;
  EXPECT_THROW(BodyIntegral(s, o), softhd::InvalidArgument);
  o = {};
  o.near_ratio = 0.5;
  EXPECT_THROW(BodyIntegral(s, o), softhd::InvalidArgument);
  o = {};
  o.tolerance = 1.0;
  EXPECT_THROW(BodyIntegral(s, o), softhd::InvalidArgument);
  o.tolerance = 1e-3;
  o.alpha = 3.0;
  EXPECT_THROW(BodyIntegral(s, o), softhd::InvalidArgument);
  TriangleSurface bad = s;
  bad.triangles(0, 2) = bad.triangles(0, 1);
  EXPECT_THROW(BodyIntegral(bad, {}), softhd::InvalidArgument);
  bad = s;
  bad.triangles(3, 0) = 99;
  EXPECT_THROW(BodyIntegral(bad, {}), softhd::InvalidArgument);
  bad = s;  // one triangle flipped
  std::swap(bad.triangles(5, 1), bad.triangles(5, 2));
  EXPECT_THROW(BodyIntegral(bad, {}), softhd::InvalidArgument);
  bad.triangles = s.triangles.topRows(11);  // an open surface
  EXPECT_THROW(BodyIntegral(bad, {}), softhd::InvalidArgument);
}

}  // namespace
