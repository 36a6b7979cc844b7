// Throughput of the exact pair kernel (docs/formulation.md §2.5): kernel (pair) evaluations per
// second for value only and for value + gradient, on 1 and 2 threads, against a measured ceiling:
// the rate at which this core retires the kernel's unavoidable sqrt and division (r = √(r²), t =
// 1/(r + ε)), which bound the pair loop.
//
//   bench_kernel [--n N] [--repeats R] [--csv FILE]
//
// Every number printed is measured in this run; nothing is typed in.

#include <Eigen/Core>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "softhd/hausdorff.hpp"

namespace {

softhd::PointCloud random_cloud(Eigen::Index n, unsigned seed) {
  std::mt19937_64 gen(seed);
  Eigen::MatrixXd p(n, 3);
  for (Eigen::Index i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k) p(i, k) = static_cast<double>(gen() >> 11) * 0x1.0p-53;
  return softhd::PointCloud(p);
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// Elements per second of y = 1/(√x + ε) over an L1-resident array, one thread: the
// sqrt/divide ceiling of the pair kernel on this core.
double sqrt_div_ceiling() {
  constexpr int kLen = 1024;
  std::vector<double> x(kLen), y(kLen);
  for (int k = 0; k < kLen; ++k) x[k] = 1.0 + k * 1e-3;
  const long reps = 200000;
  const auto t0 = std::chrono::steady_clock::now();
  double sink = 0.0;
  for (long r = 0; r < reps; ++r) {
#pragma omp simd
    for (int k = 0; k < kLen; ++k) y[k] = 1.0 / (std::sqrt(x[k]) + 1e-3);
    sink += y[r % kLen];
    x[r % kLen] += 1e-300;  // keep the loop from being hoisted
  }
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (sink == 42.0) std::puts("");
  return static_cast<double>(reps) * kLen / s;
}

}  // namespace

int main(int argc, char** argv) {
  Eigen::Index n = 20000;
  int repeats = 3;
  std::string csv;
  for (int a = 1; a < argc; ++a) {
    const std::string arg = argv[a];
    if (arg == "--n" && a + 1 < argc) {
      n = std::stol(argv[++a]);
    } else if (arg == "--repeats" && a + 1 < argc) {
      repeats = std::stoi(argv[++a]);
    } else if (arg == "--csv" && a + 1 < argc) {
      csv = argv[++a];
    } else {
      std::fprintf(stderr, "usage: bench_kernel [--n N] [--repeats R] [--csv FILE]\n");
      return arg == "--help" ? 0 : 2;
    }
  }
  if (n < 1 || repeats < 1) {
    std::fprintf(stderr, "bench_kernel: --n and --repeats must be >= 1\n");
    return 2;
  }
  const softhd::PointCloud X = random_cloud(n, 1), Y = random_cloud(n, 2);
  const double ceiling = sqrt_div_ceiling();
  std::printf("exact pair kernel, N = M = %ld, 3D, alpha = 4, median of %d runs\n",
              static_cast<long>(n), repeats);
  std::printf("ceiling (measured): %.3g sqrt+div per second on one core\n\n", ceiling);
  std::printf("%-14s %7s %10s %14s %12s\n", "work", "threads", "seconds", "pairs/s", "of ceiling");
  std::ofstream out;
  if (!csv.empty()) {
    out.open(csv);
    out << "work,threads,n,seconds,pairs_per_second,ceiling_per_core,fraction_of_ceiling\n";
  }
  double rate_one[2] = {0, 0};
  for (int gradient = 0; gradient <= 1; ++gradient) {
    for (int threads = 1; threads <= 2; ++threads) {
      softhd::HausdorffOptions opt;
      opt.threads = threads;
      softhd::HausdorffRequest req;
      req.gradient_points = req.gradient_volumes = gradient == 1;
      const softhd::HausdorffTarget target(Y, opt);
      std::vector<double> times;
      std::int64_t pairs = 0;
      for (int r = 0; r < repeats; ++r) {
        const softhd::HausdorffResult res = target.evaluate(X, req);
        times.push_back(res.seconds);
        pairs = res.kernel_evaluations;
      }
      const double s = median(times), rate = static_cast<double>(pairs) / s;
      const double fraction = rate / (ceiling * threads);
      if (threads == 1) rate_one[gradient] = rate;
      const char* work = gradient ? "value+gradient" : "value";
      std::printf("%-14s %7d %10.3f %14.4g %11.0f%%", work, threads, s, rate, 100 * fraction);
      if (threads == 2) std::printf("   (speed-up %.2f)", rate / rate_one[gradient]);
      std::printf("\n");
      if (out) {
        out << work << ',' << threads << ',' << n << ',' << s << ',' << rate << ',' << ceiling
            << ',' << fraction << '\n';
      }
    }
  }
  return 0;
}
