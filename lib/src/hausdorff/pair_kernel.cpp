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

template <int D, unsigned F>
PairSums pair_sums_impl(const double* o, double c_o, const PairSources& src,
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
