#include "softhd/samplers.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>

#include "softhd/error.hpp"

namespace softhd {
namespace {

constexpr double kPi = 3.14159265358979323846;

[[noreturn]] void invalid(const char* function, const std::string& what) {
  throw InvalidArgument(std::string(function) + ": " + what);
}

// Checks lo/hi and returns the box volume.
double check_box(const char* function, const Eigen::VectorXd& lo, const Eigen::VectorXd& hi) {
  if (lo.size() != 2 && lo.size() != 3) {
    invalid(function, "lo must have size 2 or 3, got " + std::to_string(lo.size()));
  }
  if (hi.size() != lo.size()) {
    invalid(function, "hi has size " + std::to_string(hi.size()) + " but lo has size " +
                          std::to_string(lo.size()));
  }
  double volume = 1.0;
  for (Eigen::Index k = 0; k < lo.size(); ++k) {
    const std::string at = "[" + std::to_string(k) + "]";
    if (!std::isfinite(lo[k])) invalid(function, "lo" + at + " is not finite");
    if (!std::isfinite(hi[k])) invalid(function, "hi" + at + " is not finite");
    if (!(lo[k] < hi[k])) {
      invalid(function, "need lo < hi, but lo" + at + " = " + std::to_string(lo[k]) + " >= hi" +
                            at + " = " + std::to_string(hi[k]));
    }
    volume *= hi[k] - lo[k];
  }
  if (!std::isfinite(volume)) invalid(function, "lo, hi: the box volume overflows");
  return volume;
}

// Checks per-direction counts (>= 1, same size as lo) and returns the number of
// points when direction k has factor * counts[k] + offset of them.
Eigen::Index check_counts(const char* function, const char* name, const Eigen::VectorXi& counts,
                          Eigen::Index dim, Eigen::Index factor, Eigen::Index offset) {
  if (counts.size() != dim) {
    invalid(function, std::string(name) + " has size " + std::to_string(counts.size()) +
                          " but lo has size " + std::to_string(dim));
  }
  constexpr Eigen::Index kMaxPoints = Eigen::Index(1) << 40;
  Eigen::Index total = 1;
  for (Eigen::Index k = 0; k < dim; ++k) {
    if (counts[k] < 1) {
      invalid(function, std::string(name) + "[" + std::to_string(k) + "] must be >= 1, got " +
                            std::to_string(counts[k]));
    }
    const Eigen::Index points = factor * counts[k] + offset;
    if (points > kMaxPoints / total) invalid(function, std::string(name) + ": too many points");
    total *= points;
  }
  return total;
}

void check_n(const char* function, Eigen::Index n) {
  if (n < 1) invalid(function, "n must be >= 1, got " + std::to_string(n));
}

void check_volume(const char* function, double volume) {
  if (!(volume > 0.0) || !std::isfinite(volume)) {
    invalid(function,
            "the volume per point (" + std::to_string(volume) + ") underflows or overflows");
  }
}

// Uniform in [0, 1) from the 53 high bits of one draw.
double uniform01(std::mt19937_64& rng) {
  return static_cast<double>(rng() >> 11) * (1.0 / 9007199254740992.0);  // 2^-53
}

}  // namespace

PointCloud sample_box_grid(const Eigen::VectorXd& lo, const Eigen::VectorXd& hi,
                           const Eigen::VectorXi& counts) {
  const char* fn = "sample_box_grid";
  check_box(fn, lo, hi);
  const Eigen::Index d = lo.size();
  const Eigen::Index n = check_counts(fn, "counts", counts, d, 1, 0);
  double cell = 1.0;
  for (Eigen::Index k = 0; k < d; ++k) cell *= (hi[k] - lo[k]) / counts[k];
  check_volume(fn, cell);

  Eigen::MatrixXd points(n, d);
  for (Eigen::Index i = 0; i < n; ++i) {
    Eigen::Index rest = i;
    for (Eigen::Index k = 0; k < d; ++k) {
      const Eigen::Index j = rest % counts[k];
      rest /= counts[k];
      points(i, k) = lo[k] + (hi[k] - lo[k]) * ((2.0 * j + 1.0) / (2.0 * counts[k]));
    }
  }
  return PointCloud(std::move(points), Eigen::VectorXd::Constant(n, cell));
}

PointCloud sample_q2_nodes(const Eigen::VectorXd& lo, const Eigen::VectorXd& hi,
                           const Eigen::VectorXi& elements) {
  const char* fn = "sample_q2_nodes";
  check_box(fn, lo, hi);
  const Eigen::Index d = lo.size();
  const Eigen::Index n = check_counts(fn, "elements", elements, d, 2, 1);

  // 1D node positions and Simpson weights per direction.
  Eigen::VectorXd x[3], w[3];
  for (Eigen::Index k = 0; k < d; ++k) {
    const Eigen::Index m = 2 * Eigen::Index(elements[k]);  // last node index
    const double h = (hi[k] - lo[k]) / elements[k];
    x[k].resize(m + 1);
    w[k].resize(m + 1);
    for (Eigen::Index j = 0; j <= m; ++j) {
      x[k][j] = j == m ? hi[k] : lo[k] + (hi[k] - lo[k]) * (double(j) / double(m));
      w[k][j] = h / 6.0 * (j % 2 == 1 ? 4.0 : (j == 0 || j == m ? 1.0 : 2.0));
    }
  }
  double corner = 1.0;  // the smallest volume
  for (Eigen::Index k = 0; k < d; ++k) corner *= w[k][0];
  check_volume(fn, corner);
  Eigen::MatrixXd points(n, d);
  Eigen::VectorXd volumes(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    Eigen::Index rest = i;
    double v = 1.0;
    for (Eigen::Index k = 0; k < d; ++k) {
      const Eigen::Index j = rest % x[k].size();
      rest /= x[k].size();
      points(i, k) = x[k][j];
      v *= w[k][j];
    }
    volumes[i] = v;
  }
  return PointCloud(std::move(points), std::move(volumes));
}

PointCloud sample_uniform_random(const Eigen::VectorXd& lo, const Eigen::VectorXd& hi,
                                 Eigen::Index n, std::uint64_t seed) {
  const char* fn = "sample_uniform_random";
  const double box = check_box(fn, lo, hi);
  check_n(fn, n);
  check_volume(fn, box / static_cast<double>(n));
  const Eigen::Index d = lo.size();
  std::mt19937_64 rng(seed);
  Eigen::MatrixXd points(n, d);
  for (Eigen::Index i = 0; i < n; ++i) {
    for (Eigen::Index k = 0; k < d; ++k) {
      const double x = lo[k] + (hi[k] - lo[k]) * uniform01(rng);
      points(i, k) = x < hi[k] ? x : std::nextafter(hi[k], lo[k]);  // rounding may hit hi
    }
  }
  return PointCloud(std::move(points), Eigen::VectorXd::Constant(n, box / static_cast<double>(n)));
}

PointCloud sample_sphere_shell(const Eigen::VectorXd& center, double radius, Eigen::Index n,
                               std::uint64_t seed) {
  const char* fn = "sample_sphere_shell";
  const Eigen::Index d = center.size();
  if (d != 2 && d != 3) invalid(fn, "center must have size 2 or 3, got " + std::to_string(d));
  if (!center.allFinite()) invalid(fn, "center is not finite");
  if (!(radius > 0.0) || !std::isfinite(radius)) {
    invalid(fn, "radius must be finite and > 0, got " + std::to_string(radius));
  }
  check_n(fn, n);
  const double measure = d == 3 ? 4.0 * kPi * radius * radius : 2.0 * kPi * radius;
  if (!std::isfinite(measure)) invalid(fn, "radius: the surface measure overflows");
  check_volume(fn, measure / static_cast<double>(n));

  std::mt19937_64 rng(seed);
  Eigen::MatrixXd points(n, d);
  for (Eigen::Index i = 0; i < n; ++i) {
    if (d == 3) {
      const double z = 2.0 * uniform01(rng) - 1.0;
      const double phi = 2.0 * kPi * uniform01(rng);
      const double s = std::sqrt(std::max(0.0, 1.0 - z * z));
      points(i, 0) = center[0] + radius * s * std::cos(phi);
      points(i, 1) = center[1] + radius * s * std::sin(phi);
      points(i, 2) = center[2] + radius * z;
    } else {
      const double phi = 2.0 * kPi * uniform01(rng);
      points(i, 0) = center[0] + radius * std::cos(phi);
      points(i, 1) = center[1] + radius * std::sin(phi);
    }
  }
  return PointCloud(std::move(points),
                    Eigen::VectorXd::Constant(n, measure / static_cast<double>(n)));
}

}  // namespace softhd
