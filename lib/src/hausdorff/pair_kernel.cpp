#include "pair_kernel.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

namespace softhd::detail {

namespace {
constexpr int kBlock = 256;  // pairs per block: buffers stay in L1
}

KernelPower::KernelPower(double alpha) : alpha_(alpha) {
  if (alpha == std::floor(alpha) && alpha >= 1.0 && alpha <= 1073741824.0) {
    integer_ = static_cast<unsigned long long>(alpha);
  }
}

void KernelPower::apply(const double* q, double* p, int len) const {
  if (integer_ == 0) {
    for (int k = 0; k < len; ++k) p[k] = std::exp(alpha_ * std::log(q[k]));
    return;
  }
  // Binary exponentiation, each step one vectorised sweep over the block.
  alignas(64) double base[kBlock];
#pragma omp simd
  for (int k = 0; k < len; ++k) {
    base[k] = q[k];
    p[k] = 1.0;
  }
  for (unsigned long long n = integer_;;) {
    if (n & 1u) {
#pragma omp simd
      for (int k = 0; k < len; ++k) p[k] *= base[k];
    }
    n >>= 1;
    if (n == 0) break;
#pragma omp simd
    for (int k = 0; k < len; ++k) base[k] *= base[k];
  }
}

double KernelPower::scalar(double q) const {
  if (integer_ == 0) return std::exp(alpha_ * std::log(q));
  double p = 1.0, base = q;
  for (unsigned long long n = integer_;;) {
    if (n & 1u) p *= base;
    n >>= 1;
    if (n == 0) break;
    base *= base;
  }
  return p;
}

namespace {

/// p · base^N by the steps of KernelPower's binary exponentiation, unrolled at compile time;
/// fixed_power<N>(q) = power_steps<N>(1, q) is the same number, bit for bit, as KernelPower::apply.
template <unsigned N>
inline double power_steps(double p, double base) {
  if constexpr ((N & 1u) != 0) p *= base;
  if constexpr ((N >> 1) == 0) {
    return p;
  } else {
    return power_steps<(N >> 1)>(p, base * base);
  }
}

template <unsigned P>
inline double fixed_power(double q) {
  return power_steps<P>(1.0, q);
}

/// The sums of one outer point for α = P, the power inlined: one vectorised loop over the
/// sources, no buffers.
template <int D, unsigned F, unsigned P>
PairSums fused_sums(const double* o, double c_o, const PairSources& src, double eps) {
  constexpr bool kSum = (F & kOuterSum) != 0;
  constexpr bool kGrad = (F & kOuterGrad) != 0;
  constexpr bool kIn = (F & kInner) != 0;
  constexpr bool kMag = (F & kMagnitude) != 0;
  const double* bx = src.coord[0];
  const double* by = src.coord[1];
  const double* bz = D == 3 ? src.coord[2] : src.coord[1];
  const double* w = src.weight;
  const double* h = src.coef;
  const double* c = src.scale;
  const double ox = o[0], oy = o[1], oz = D == 3 ? o[2] : 0.0;
  double S = 0.0, Gx = 0.0, Gy = 0.0, Gz = 0.0, H = 0.0, Hx = 0.0, Hy = 0.0, Hz = 0.0;
  double Gm = 0.0, G2m = 0.0;
  const Eigen::Index n1 = src.size;
  const double inv_eps = 1.0 / eps;
  // Selects only, no branches, so that the loop vectorises: a coincident pair (r = 0)
  // gets t = 1/ε and t/r = 0 (its 1/0 is computed and discarded).
#pragma omp simd reduction(+ : S, Gx, Gy, Gz, Gm, H, Hx, Hy, Hz, G2m)
  for (Eigen::Index k = 0; k < n1; ++k) {
    const double dx = ox - bx[k], dy = oy - by[k];
    const double dz = D == 3 ? oz - bz[k] : 0.0;
    const double r = std::sqrt(dx * dx + dy * dy + dz * dz);
    const bool apart = r > 0.0;
    double t, tr = 0.0;
    if constexpr (kGrad || kIn) {
      const double inv = 1.0 / (r * (r + eps));  // t/r = 1/(r (r + ε)), t = r · t/r
      const double rt = r * inv;
      t = apart ? rt : inv_eps;
      tr = apart ? inv : 0.0;
    } else {
      t = 1.0 / (r + eps);
    }
    const double t_apart = apart ? t : 0.0;  // the magnitude sums skip coincident pairs
    if constexpr (kSum || kGrad) {
      const double wp = w[k] * fixed_power<P>(c_o * t);  // w (c_o t)^α
      if constexpr (kSum) S += wp;
      if constexpr (kGrad) {
        const double g = wp * tr;  // w p t / r
        Gx += g * dx;
        Gy += g * dy;
        Gz += g * dz;
        if constexpr (kMag) Gm += wp * t_apart;
      }
    }
    if constexpr (kIn) {
      const double hp = h[k] * fixed_power<P>(c[k] * t);  // h (c_n t)^α
      H += hp;
      const double g = hp * tr;
      Hx += g * dx;
      Hy += g * dy;
      Hz += g * dz;
      if constexpr (kMag) G2m += hp * t_apart;
    }
  }
  PairSums out;
  out.S = S;
  out.G[0] = Gx;
  out.G[1] = Gy;
  out.G[2] = D == 3 ? Gz : 0.0;
  out.H = H;
  out.G2[0] = Hx;
  out.G2[1] = Hy;
  out.G2[2] = D == 3 ? Hz : 0.0;
  out.Gm = Gm;
  out.G2m = G2m;
  return out;
}

/// The sums of one outer point for any α: the powers of a block of 256 pairs at a time
/// (KernelPower::apply) between vectorised sweeps.
template <int D, unsigned F>
PairSums buffered_sums(const double* o, double c_o, const PairSources& src,
                       const KernelPower& power, double eps) {
  constexpr bool kSum = (F & kOuterSum) != 0;
  constexpr bool kGrad = (F & kOuterGrad) != 0;
  constexpr bool kIn = (F & kInner) != 0;
  constexpr bool kMag = (F & kMagnitude) != 0;
  PairSums out;
  const double* x[3] = {src.coord[0], src.coord[1], D == 3 ? src.coord[2] : src.coord[1]};
  const double ox = o[0], oy = o[1], oz = D == 3 ? o[2] : 0.0;
  double S = 0.0, Gx = 0.0, Gy = 0.0, Gz = 0.0, H = 0.0, Hx = 0.0, Hy = 0.0, Hz = 0.0;
  double Gm = 0.0, G2m = 0.0;
  alignas(64) double tinv[kBlock], trinv[kBlock], q[kBlock], p[kBlock];

  for (Eigen::Index n0 = 0; n0 < src.size; n0 += kBlock) {
    const int len = static_cast<int>(std::min<Eigen::Index>(kBlock, src.size - n0));
    const double* bx = x[0] + n0;
    const double* by = x[1] + n0;
    const double* bz = x[2] + n0;
    // r = |o − x|, t = φ(r) = 1/(r + ε), q = c_o t; 1/r only where it is needed.
#pragma omp simd
    for (int k = 0; k < len; ++k) {
      const double dx = ox - bx[k], dy = oy - by[k];
      double r2 = dx * dx + dy * dy;
      if constexpr (D == 3) {
        const double dz = oz - bz[k];
        r2 += dz * dz;
      }
      const double r = std::sqrt(r2);
      if constexpr (kGrad || kIn) {
        // One division for both t = 1/(r + ε) and t/r = 1/(r (r + ε)); a coincident
        // pair (r = 0) gets t = 1/ε and t/r = 0.
        const double inv = 1.0 / (r * (r + eps));
        const double t = r > 0.0 ? r * inv : 1.0 / eps;
        tinv[k] = t;
        trinv[k] = r > 0.0 ? inv : 0.0;
        q[k] = c_o * t;
      } else {
        const double t = 1.0 / (r + eps);
        tinv[k] = t;
        q[k] = c_o * t;
      }
    }
    if constexpr (kSum || kGrad) {
      power.apply(q, p, len);  // p = (c_o t)^α
      const double* w = src.weight + n0;
#pragma omp simd reduction(+ : S, Gx, Gy, Gz, Gm)
      for (int k = 0; k < len; ++k) {
        const double wp = w[k] * p[k];
        if constexpr (kSum) S += wp;
        if constexpr (kGrad) {
          const double g = wp * trinv[k];  // w p t / r
          Gx += g * (ox - bx[k]);
          Gy += g * (oy - by[k]);
          if constexpr (D == 3) Gz += g * (oz - bz[k]);
          if constexpr (kMag) Gm += trinv[k] > 0.0 ? wp * tinv[k] : 0.0;
        }
      }
    }
    if constexpr (kIn) {
      const double* c = src.scale + n0;
#pragma omp simd
      for (int k = 0; k < len; ++k) q[k] = c[k] * tinv[k];
      power.apply(q, p, len);  // p' = (c_n t)^α
      const double* h = src.coef + n0;
#pragma omp simd reduction(+ : H, Hx, Hy, Hz, G2m)
      for (int k = 0; k < len; ++k) {
        const double hp = h[k] * p[k];
        H += hp;
        const double g = hp * trinv[k];
        Hx += g * (ox - bx[k]);
        Hy += g * (oy - by[k]);
        if constexpr (D == 3) Hz += g * (oz - bz[k]);
        if constexpr (kMag) G2m += trinv[k] > 0.0 ? hp * tinv[k] : 0.0;
      }
    }
  }
  out.S = S;
  out.G[0] = Gx;
  out.G[1] = Gy;
  out.G[2] = Gz;
  out.H = H;
  out.G2[0] = Hx;
  out.G2[1] = Hy;
  out.G2[2] = Hz;
  out.Gm = Gm;
  out.G2m = G2m;
  return out;
}

/// The fused loop where α is one of the unrolled powers, else the buffered one.
template <int D, unsigned F>
PairSums pair_sums_impl(const double* o, double c_o, const PairSources& src,
                        const KernelPower& power, double eps) {
  switch (power.fixed()) {
    case 2:
      return fused_sums<D, F, 2>(o, c_o, src, eps);
    case 4:
      return fused_sums<D, F, 4>(o, c_o, src, eps);
    case 8:
      return fused_sums<D, F, 8>(o, c_o, src, eps);
    case 16:
      return fused_sums<D, F, 16>(o, c_o, src, eps);
    case 64:
      return fused_sums<D, F, 64>(o, c_o, src, eps);
    default:
      return buffered_sums<D, F>(o, c_o, src, power, eps);
  }
}

using PairFn = PairSums (*)(const double*, double, const PairSources&, const KernelPower&, double);

// One instantiation per combination of the four flags, indexed by the flag bits.
template <int D, unsigned... F>
constexpr std::array<PairFn, sizeof...(F)> table(std::integer_sequence<unsigned, F...>) {
  return {&pair_sums_impl<D, F>...};
}

template <int D>
PairSums dispatch_flags(const double* o, double c_o, const PairSources& src,
                        const KernelPower& power, double eps, unsigned flags) {
  static constexpr auto kTable = table<D>(std::make_integer_sequence<unsigned, 16>{});
  if ((flags & (kOuterSum | kOuterGrad | kInner)) == 0) return PairSums{};  // nothing requested
  return kTable[flags & 15u](o, c_o, src, power, eps);
}

}  // namespace

PairSums pair_sums(const double* o, double c_o, const PairSources& src, const KernelPower& power,
                   double eps, unsigned flags) {
  return src.dim == 2 ? dispatch_flags<2>(o, c_o, src, power, eps, flags)
                      : dispatch_flags<3>(o, c_o, src, power, eps, flags);
}

}  // namespace softhd::detail
