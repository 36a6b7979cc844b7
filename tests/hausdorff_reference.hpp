#pragma once
// Independent oracles for the Hausdorff tests: the naive formulas of docs/formulation.md §2.1 in
// long double (no scaling, no trees), brute-force nearest distances, and random clouds.

#include <Eigen/Core>
#include <cmath>
#include <random>
#include <vector>

#include "softhd/hausdorff.hpp"
#include "softhd/point_cloud.hpp"

namespace softhd::test {

/// N random points in [lo, hi]^d with random volumes in [0.5, 1.5] (fixed seed).
inline PointCloud random_cloud(int n, int d, unsigned seed, double lo = 0.0, double hi = 1.0) {
  std::mt19937_64 gen(seed);
  auto uniform = [&gen] { return static_cast<double>(gen() >> 11) * 0x1.0p-53; };
  Eigen::MatrixXd p(n, d);
  Eigen::VectorXd v(n);
  for (int i = 0; i < n; ++i) {
    for (int k = 0; k < d; ++k) p(i, k) = lo + (hi - lo) * uniform();
    v[i] = 0.5 + uniform();
  }
  return PointCloud(p, v);
}

struct Reference {
  long double rho = 0, A = 0, B = 0;
  std::vector<long double> field_target, field_moving;  // d̃_X(y_j), d̃_Y(x_i)
  bool representable = true;  // false if an intermediate overflowed or underflowed to 0
};

/// d̃_P(q) = 1/I − ε with I = ((1/|P|) Σ V φ(|q − p|)^α)^(1/α), naively in long double.
inline long double naive_distance(const PointCloud& P, const Eigen::VectorXd& q,
                                  const HausdorffParams& prm, bool& ok) {
  const long double a = prm.alpha, eps = prm.epsilon;
  long double sum = 0;
  for (Eigen::Index i = 0; i < P.size(); ++i) {
    long double r2 = 0;
    for (int k = 0; k < P.dim(); ++k) {
      const long double d = static_cast<long double>(q[k]) - P.points()(i, k);
      r2 += d * d;
    }
    const long double phi = 1.0L / (std::sqrt(r2) + eps);
    const long double term = P.volumes()[i] * std::pow(phi, a);
    if (!std::isfinite(term)) ok = false;
    sum += term;
  }
  const long double I = std::pow(sum / static_cast<long double>(P.total_volume()), 1.0L / a);
  if (!std::isfinite(I) || !(I > 0)) ok = false;
  return 1.0L / I - eps;
}

inline long double naive_mean(const std::vector<long double>& d, const Eigen::VectorXd& V,
                              long double p, bool& ok) {
  long double sum = 0, total = 0;
  for (size_t i = 0; i < d.size(); ++i) {
    sum += V[static_cast<Eigen::Index>(i)] * std::pow(d[i], p);
    total += V[static_cast<Eigen::Index>(i)];
  }
  if (!std::isfinite(sum) || !(sum > 0)) ok = false;
  return std::pow(sum / total, 1.0L / p);
}

inline Reference naive_hausdorff(const PointCloud& X, const PointCloud& Y,
                                 const HausdorffParams& prm) {
  Reference r;
  bool ok = true;
  for (Eigen::Index j = 0; j < Y.size(); ++j)
    r.field_target.push_back(naive_distance(X, Y.points().row(j).transpose(), prm, ok));
  for (Eigen::Index i = 0; i < X.size(); ++i)
    r.field_moving.push_back(naive_distance(Y, X.points().row(i).transpose(), prm, ok));
  r.A = naive_mean(r.field_target, Y.volumes(), prm.beta, ok);
  r.B = naive_mean(r.field_moving, X.volumes(), prm.beta, ok);
  const long double g = prm.gamma;
  r.rho = std::pow((std::pow(r.A, g) + std::pow(r.B, g)) / 2.0L, 1.0L / g);
  if (!std::isfinite(r.rho)) ok = false;
  r.representable = ok;
  return r;
}

/// Brute-force distance from q to the nearest point of P.
inline double brute_nearest(const PointCloud& P, const Eigen::VectorXd& q) {
  double best = INFINITY;
  for (Eigen::Index i = 0; i < P.size(); ++i)
    best = std::min(best, (P.points().row(i).transpose() - q).norm());
  return best;
}

inline double relative_error(long double value, long double reference) {
  const long double scale = std::max(std::fabs(reference), 1e-300L);
  return static_cast<double>(std::fabs(value - reference) / scale);
}

}  // namespace softhd::test
