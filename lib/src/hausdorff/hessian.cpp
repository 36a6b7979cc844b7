// Hessian-vector products of ρ̃ w.r.t. the moving points (docs/formulation.md §2.7).
//
// With D = d̃ + ε, u = (x − y)/r, t = 1/(r + ε), the soft-min weights π_ij and a direction δ:
//     ∇_i d̃_j   = D_j π_ij t_ij u_ij
//     ∇²d̃_j δ  = D_j [ a1 π_ij t_ij u_ij m_j + π_ij ((t/r) P⊥_ij δ_i − a1 t² (u·δ_i) u) ]_i,
//     m_j = Σ_k π_kj t_kj u_kj·δ_k,  a1 = α + 1,  P⊥ = I − u uᵀ,
// and the β- and γ-means' second derivatives as coefficients of ∇d̃ (§2.7). The Gauss–Newton
// part keeps the positive semi-definite terms: a1 → 0, ψ'' → 0, β − 1 → max(β − 1, 0),
// γ − 1 → max(γ − 1, 0).

#include "hessian.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <type_traits>

#include "scaled_means.hpp"
#include "softhd/error.hpp"
#include "softhd/interrupt.hpp"

namespace softhd::detail {

namespace {

/// The factors that differ between the full Hessian and its Gauss–Newton part.
struct Factors {
  double a1;           ///< α + 1 (the soft-min covariance; GN: 0)
  double beta1;        ///< β − 1 (GN: max(β − 1, 0))
  double gamma1;       ///< γ − 1 (GN: max(γ − 1, 0))
  bool cap_curvature;  ///< keep ψ''/ψ' (GN: no)
};

Factors factors(const HausdorffParams& prm, HessianPart part) {
  if (part == HessianPart::full) return {prm.alpha + 1.0, prm.beta - 1.0, prm.gamma - 1.0, true};
  return {0.0, std::max(prm.beta - 1.0, 0.0), std::max(prm.gamma - 1.0, 0.0), false};
}

/// q^P by repeated squaring (P = 0: any α through KernelPower::scalar).
template <unsigned P>
inline double kernel_power(double q, const KernelPower& kp) {
  if constexpr (P == 0) {
    return kp.scalar(q);
  } else if constexpr (P == 1) {
    return q;
  } else {
    const double half = kernel_power<P / 2>(q, kp);
    return (P % 2 != 0) ? half * half * q : half * half;
  }
}

/// Calls f(std::integral_constant<unsigned, P>) with P = α for the integers α ≤ 8 and 16
/// (unrolled, the loops vectorise), else P = 0.
template <class F>
auto with_power(const KernelPower& kp, F&& f) {
  switch (kp.fixed()) {
    case 1:
      return f(std::integral_constant<unsigned, 1>{});
    case 2:
      return f(std::integral_constant<unsigned, 2>{});
    case 3:
      return f(std::integral_constant<unsigned, 3>{});
    case 4:
      return f(std::integral_constant<unsigned, 4>{});
    case 5:
      return f(std::integral_constant<unsigned, 5>{});
    case 6:
      return f(std::integral_constant<unsigned, 6>{});
    case 7:
      return f(std::integral_constant<unsigned, 7>{});
    case 8:
      return f(std::integral_constant<unsigned, 8>{});
    case 16:
      return f(std::integral_constant<unsigned, 16>{});
    default:
      return f(std::integral_constant<unsigned, 0>{});
  }
}

/// Column pointers of an N by d matrix (structure of arrays; column-major storage).
struct Columns {
  const double* c[3] = {nullptr, nullptr, nullptr};
  explicit Columns(const Eigen::MatrixXd& m) {
    for (Eigen::Index k = 0; k < m.cols() && k < 3; ++k) c[k] = m.col(k).data();
  }
};

/// μ_j = Σ_i v_i p_ij (t_ij/r_ij) (x_i − y_j)·δ_i,  p_ij = (c_j t_ij)^α. Selects, no branches
/// (the loop vectorises): a coincident pair gets t/r = 0, so contributes 0.
template <int D, unsigned P>
double target_moment(const double* y, double c_j, const Columns& x, const Columns& dir,
                     const double* v, Eigen::Index n, double eps, const KernelPower& kp) {
  const double* px = x.c[0];
  const double* py = x.c[1];
  const double* pz = D == 3 ? x.c[2] : x.c[1];
  const double* ex = dir.c[0];
  const double* ey = dir.c[1];
  const double* ez = D == 3 ? dir.c[2] : dir.c[1];
  const double y0 = y[0], y1 = y[1], y2 = D == 3 ? y[2] : 0.0, inv_eps = 1.0 / eps;
  double mu = 0.0;
#pragma omp simd reduction(+ : mu)
  for (Eigen::Index i = 0; i < n; ++i) {
    const double dx = px[i] - y0, dy = py[i] - y1, dz = D == 3 ? pz[i] - y2 : 0.0;
    const double r = std::sqrt(dx * dx + dy * dy + dz * dz);
    const double inv = 1.0 / (r * (r + eps));  // t/r
    const bool apart = r > 0.0;
    const double tr = apart ? inv : 0.0, t = apart ? r * inv : inv_eps;
    const double dd = dx * ex[i] + dy * ey[i] + (D == 3 ? dz * ez[i] : 0.0);
    mu += v[i] * kernel_power<P>(c_j * t, kp) * tr * dd;
  }
  return mu;
}

/// Pass 1 of a product, targets over moving points: m_j = μ_j / S_j (δd̃_j = D_j m_j).
Eigen::VectorXd target_moments(const HausdorffHessian& h, const Eigen::MatrixXd& Y,
                               const Eigen::MatrixXd& delta, const KernelPower& kp, int threads) {
  const Eigen::Index M = Y.rows(), N = h.x.rows();
  const int dim = static_cast<int>(Y.cols());
  const Columns x(h.x), dir(delta);
  Eigen::VectorXd m(M);
  with_power(kp, [&](auto p) {
    constexpr unsigned kP = decltype(p)::value;
#pragma omp parallel for schedule(static) num_threads(threads)
    for (Eigen::Index j = 0; j < M; ++j) {
      double y[3] = {Y(j, 0), Y(j, 1), dim == 3 ? Y(j, 2) : 0.0};
      const double mu =
          dim == 3
              ? target_moment<3, kP>(y, h.scale_y[j], x, dir, h.v.data(), N, h.prm.epsilon, kp)
              : target_moment<2, kP>(y, h.scale_y[j], x, dir, h.v.data(), N, h.prm.epsilon, kp);
      m[j] = mu / h.S_y[j];
    }
    return 0;
  });
  return m;
}

/// ψ''/ψ' of the soft cap: −(q+1) κ/d, κ = (d/c)^q/(1 + (d/c)^q) (0 without a cap or at d = 0).
double cap_curvature(double d, const SoftCap& cap) {
  if (cap.c == 0.0 || !(d > 0.0)) return 0.0;
  const double kappa = 1.0 / (1.0 + std::pow(cap.c / d, cap.q));  // (c/d)^q may be inf: κ = 0
  return -(cap.q + 1.0) * kappa / d;
}

/// The coefficient of ∇M (M = A or B, δM = ∇M·δ) in H·δ from the γ-mean's second derivatives:
///     c_M = (γ−1) ρ̃_M (δM/M − δρ̃/ρ̃)      (0 for scan_to_body, where ρ̃ = A).
double gamma_coefficient(double rho_M, double M, double dM, double rho, double drho,
                         const Factors& f, Sides sides) {
  if (sides == Sides::scan_to_body || !(M > 0.0) || !(rho > 0.0)) return 0.0;
  return f.gamma1 * rho_M * (dM / M - drho / rho);
}

/// κ_n = ρ̃_M e_n + c_M s_n, the coefficient of ∇d̃_n in H·δ from the second derivatives of the
/// β-mean M and of the cap, with s_n = ∂M/∂d̃_n, δd_n = ∇d̃_n·δ:
///     e_n = s_n [ (β−1)(ψ'_n δd_n/ψ_n − δM/M) + (ψ''_n/ψ'_n) δd_n ].
double field_coefficient(double s, double d, double psi, double dd, double M, double dM,
                         double rho_M, double c_M, const SoftCap& cap, const Factors& f) {
  if (!(s != 0.0) || !(psi > 0.0) || !(M > 0.0)) return c_M * s;
  const double psi_ratio = soft_cap_derivative(d, cap.c, cap.q) / psi;  // ψ'/ψ
  double e = f.beta1 * (psi_ratio * dd - dM / M);
  if (f.cap_curvature) e += cap_curvature(d, cap) * dd;
  return rho_M * s * e + c_M * s;
}

/// One moving point's pair sums of pass 2, over the targets y_j (d = x_i − y_j, dd = d·δ_i):
///     VA = Σ_j p'_j [hh_j (t/r) − kk_j ((t/r) dd/r² + a1 (t/r)² dd)] d,  SA = Σ_j p'_j kk_j t/r
///     VB = Σ_j w_j p_j [−(t/r) dd/r² − a1 (t/r)² dd] d,                 SB = Σ_j w_j p_j t/r
/// with p'_j = (c_j t)^α (the target's scale), p_j = (c_i t)^α (the moving point's).
struct RowSums {
  double VA[3] = {0.0, 0.0, 0.0}, SA = 0.0, VB[3] = {0.0, 0.0, 0.0}, SB = 0.0;
};

template <int D, unsigned P, bool kB>
RowSums moving_row(const double* x, const double* del, double c_i, const Columns& y,
                   const double* c_y, const double* hh, const double* kk, const double* w,
                   Eigen::Index m, double eps, double a1, const KernelPower& kp) {
  const double* qx = y.c[0];
  const double* qy = y.c[1];
  const double* qz = D == 3 ? y.c[2] : y.c[1];
  const double x0 = x[0], x1 = x[1], x2 = x[2], e0 = del[0], e1 = del[1], e2 = del[2];
  const double inv_eps = 1.0 / eps;
  double ax = 0.0, ay = 0.0, az = 0.0, sa = 0.0, bx = 0.0, by = 0.0, bz = 0.0, sb = 0.0;
  // Selects, no branches (the loop vectorises): a coincident pair gets t/r = 0 and 1/r² = 0,
  // so contributes 0.
#pragma omp simd reduction(+ : ax, ay, az, sa, bx, by, bz, sb)
  for (Eigen::Index j = 0; j < m; ++j) {
    const double dx = x0 - qx[j], dy = x1 - qy[j], dz = D == 3 ? x2 - qz[j] : 0.0;
    const double r2 = dx * dx + dy * dy + dz * dz;
    const double r = std::sqrt(r2);
    const double inv = 1.0 / (r * (r + eps));  // t/r
    const bool apart = r > 0.0;
    const double tr = apart ? inv : 0.0, t = apart ? r * inv : inv_eps;
    const double ir2 = apart ? 1.0 / r2 : 0.0;
    const double dd = dx * e0 + dy * e1 + dz * e2;
    const double radial = tr * dd * ir2 + a1 * tr * tr * dd;  // (t/r) dd/r² + a1 (t/r)² dd
    const double pa = kernel_power<P>(c_y[j] * t, kp);
    const double ga = pa * (hh[j] * tr - kk[j] * radial);
    sa += pa * kk[j] * tr;
    ax += ga * dx;
    ay += ga * dy;
    az += ga * dz;
    if constexpr (kB) {
      const double pb = w[j] * kernel_power<P>(c_i * t, kp);
      const double gb = -pb * radial;
      sb += pb * tr;
      bx += gb * dx;
      by += gb * dy;
      bz += gb * dz;
    }
  }
  RowSums s;
  s.VA[0] = ax;
  s.VA[1] = ay;
  s.VA[2] = az;
  s.SA = sa;
  s.VB[0] = bx;
  s.VB[1] = by;
  s.VB[2] = bz;
  s.SB = sb;
  return s;
}

/// The per-product coefficients: of the targets (pass 2's hh_j, kk_j) and of the moving
/// points (κ_i, for side B).
struct Coefficients {
  Eigen::VectorXd hh, kk, kappa_x, nu;
};

/// δA, δB, the γ-slopes and every coefficient pass 2 needs, from pass 1's m_j:
///     δd̃_j = D_j m_j, δd̃_i = D_i ν_i (ν_i = n_i·δ_i), δA = Σ a_j δd̃_j, δB = Σ b_i δd̃_i,
///     kk_j = ρ̃_A a_j D_j/S_j,  hh_j = kk_j a1 m_j + κ_j D_j/S_j.
Coefficients coefficients(const HausdorffHessian& h, const Eigen::VectorXd& m,
                          const Eigen::MatrixXd& delta, const Factors& f) {
  const bool one_sided = h.form.sides == Sides::scan_to_body;
  Coefficients c;
  const Eigen::VectorXd ddy = h.D_y.cwiseProduct(m);
  Eigen::VectorXd ddx;
  double dA = h.a.dot(ddy), dB = 0.0;
  if (!one_sided) {
    c.nu = h.n_x.cwiseProduct(delta).rowwise().sum();
    ddx = h.D_x.cwiseProduct(c.nu);
    dB = h.b.dot(ddx);
  }
  const double drho = h.rho_A * dA + h.rho_B * dB;
  const double cA = gamma_coefficient(h.rho_A, h.A, dA, h.rho, drho, f, h.form.sides);
  const double cB = gamma_coefficient(h.rho_B, h.B, dB, h.rho, drho, f, h.form.sides);
  const Eigen::Index M = m.size();
  c.hh.resize(M);
  c.kk.resize(M);
  for (Eigen::Index j = 0; j < M; ++j) {
    const double kappa = field_coefficient(h.a[j], h.D_y[j] - h.prm.epsilon, h.psi_y[j], ddy[j],
                                           h.A, dA, h.rho_A, cA, h.form.cap, f);
    const double ratio = h.D_y[j] / h.S_y[j];
    c.kk[j] = h.rho_A * h.a[j] * ratio;
    c.hh[j] = c.kk[j] * f.a1 * m[j] + kappa * ratio;
  }
  if (one_sided) return c;
  c.kappa_x.resize(h.x.rows());
  for (Eigen::Index i = 0; i < h.x.rows(); ++i)
    c.kappa_x[i] = field_coefficient(h.b[i], h.D_x[i] - h.prm.epsilon, h.psi_x[i], ddx[i], h.B, dB,
                                     h.rho_B, cB, h.form.cap, f);
  return c;
}

/// Row i of H·δ from its pair sums:
///     v_i (VA + SA δ_i) + ρ̃_B b_i D_i [a1 n_i ν_i + (VB + SB δ_i)/S_i] + κ_i D_i n_i.
template <bool kB>
void assemble_row(const HausdorffHessian& h, const Coefficients& c, const RowSums& s,
                  const double* del, double a1, Eigen::Index i, int dim, Eigen::MatrixXd& out) {
  for (int k = 0; k < dim; ++k) out(i, k) = h.v[i] * (s.VA[k] + s.SA * del[k]);
  if constexpr (kB) {
    const double scale = h.rho_B * h.b[i] * h.D_x[i];
    for (int k = 0; k < dim; ++k)
      out(i, k) += scale * (a1 * h.n_x(i, k) * c.nu[i] + (s.VB[k] + s.SB * del[k]) / h.S_x[i]);
  }
  if (c.kappa_x.size() != 0)
    for (int k = 0; k < dim; ++k) out(i, k) += c.kappa_x[i] * h.D_x[i] * h.n_x(i, k);
}

/// Pass 2 of a product, moving points over targets: every row of H·δ.
Eigen::MatrixXd moving_rows(const HausdorffHessian& h, const Eigen::MatrixXd& Y,
                            const Eigen::VectorXd& w, const Eigen::MatrixXd& delta,
                            const Coefficients& c, const Factors& f, const KernelPower& kp,
                            int threads) {
  const Eigen::Index N = h.x.rows(), M = Y.rows();
  const int dim = static_cast<int>(Y.cols());
  const Columns y(Y);
  const bool one_sided = h.form.sides == Sides::scan_to_body;
  const double eps = h.prm.epsilon;
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(N, dim);
  with_power(kp, [&](auto p) {
    constexpr unsigned kP = decltype(p)::value;
#pragma omp parallel for schedule(static) num_threads(threads)
    for (Eigen::Index i = 0; i < N; ++i) {
      if (h.differentiate.size() != 0 && !h.differentiate[i]) continue;
      const double x[3] = {h.x(i, 0), h.x(i, 1), dim == 3 ? h.x(i, 2) : 0.0};
      const double del[3] = {delta(i, 0), delta(i, 1), dim == 3 ? delta(i, 2) : 0.0};
      const bool side_b = !one_sided && h.b[i] != 0.0;
      const double ci = side_b ? h.scale_x[i] : 0.0;
      const double* hh = c.hh.data();
      const double* kk = c.kk.data();
      const double* cy = h.scale_y.data();
      RowSums s;
      if (dim == 3)
        s = side_b
                ? moving_row<3, kP, true>(x, del, ci, y, cy, hh, kk, w.data(), M, eps, f.a1, kp)
                : moving_row<3, kP, false>(x, del, ci, y, cy, hh, kk, w.data(), M, eps, f.a1, kp);
      else
        s = side_b
                ? moving_row<2, kP, true>(x, del, ci, y, cy, hh, kk, w.data(), M, eps, f.a1, kp)
                : moving_row<2, kP, false>(x, del, ci, y, cy, hh, kk, w.data(), M, eps, f.a1, kp);
      if (side_b)
        assemble_row<true>(h, c, s, del, f.a1, i, dim, out);
      else
        assemble_row<false>(h, c, s, del, f.a1, i, dim, out);
    }
    return 0;
  });
  return out;
}

}  // namespace

Eigen::MatrixXd hessian_product(const HausdorffHessian& h, const Eigen::MatrixXd& Y,
                                const Eigen::VectorXd& w, const Eigen::MatrixXd& dir,
                                HessianPart part, int threads, SumWork* work) {
  const auto start = std::chrono::steady_clock::now();
  const Factors f = factors(h.prm, part);
  const KernelPower kp(h.prm.alpha);
  Eigen::MatrixXd delta = dir;  // δ with the rows of points not differentiated zeroed
  if (h.differentiate.size() != 0)
    for (Eigen::Index i = 0; i < delta.rows(); ++i)
      if (!h.differentiate[i]) delta.row(i).setZero();
  const Eigen::VectorXd m = target_moments(h, Y, delta, kp, threads);
  check_interrupt("between the passes of a Hessian-vector product");
  const Coefficients c = coefficients(h, m, delta, f);
  Eigen::MatrixXd out = moving_rows(h, Y, w, delta, c, f, kp, threads);
  if (work != nullptr) {
    const std::int64_t pairs = static_cast<std::int64_t>(h.x.rows()) * Y.rows();
    work->near_pairs += 2 * pairs;
    work->passes += 2;
    work->run_seconds +=
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  return out;
}

}  // namespace softhd::detail
