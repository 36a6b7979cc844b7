#pragma once
/// \file gauss_legendre.hpp
/// Gauss–Legendre nodes and weights, shared by the continuum distance's rules (hausdorff/).

#include <cmath>
#include <vector>

namespace softhd::detail {

/// The n-point Gauss–Legendre rule on [−1, 1], nodes ascending: Newton on P_n from the
/// Chebyshev-like guesses cos(π(i + 3/4)/(n + 1/2)), P_n by (k+1)P_{k+1} = (2k+1) z P_k − k
/// P_{k−1}, weights 2/((1 − z²) P_n′(z)²).
inline void gauss_legendre(int n, std::vector<double>* x, std::vector<double>* w) {
  x->assign(n, 0.0);
  w->assign(n, 0.0);
  const double pi = 3.14159265358979323846;
  for (int i = 0; i < n; ++i) {
    double z = std::cos(pi * (i + 0.75) / (n + 0.5)), dp = 1.0;
    for (int it = 0; it < 100; ++it) {
      double p0 = 1.0, p1 = z;
      for (int k = 1; k < n; ++k) {
        const double p2 = ((2.0 * k + 1.0) * z * p1 - k * p0) / (k + 1.0);
        p0 = p1;
        p1 = p2;
      }
      dp = n * (z * p1 - p0) / (z * z - 1.0);  // P_n'(z)
      const double dz = p1 / dp;
      z -= dz;
      if (std::abs(dz) < 1e-16) break;
    }
    (*x)[n - 1 - i] = z;
    (*w)[n - 1 - i] = 2.0 / ((1.0 - z * z) * dp * dp);
  }
}

/// The same rule mapped to [0, 1].
inline void gauss_legendre_unit(int n, std::vector<double>* x, std::vector<double>* w) {
  gauss_legendre(n, x, w);
  for (int i = 0; i < n; ++i) {
    (*x)[i] = 0.5 * ((*x)[i] + 1.0);
    (*w)[i] *= 0.5;
  }
}

}  // namespace softhd::detail
