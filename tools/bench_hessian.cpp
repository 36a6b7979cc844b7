// The cost of one Hessian-vector product of ρ̃ (docs/formulation.md §2.7) against one value and
// one gradient evaluation, on two random overlapping clouds, in one process; medians of the
// repeats, the evaluations interleaved.
//
//   bench_hessian [--n N] [--m M] [--dim D] [--alpha A] [--method exact|tree] [--tau T]
//                 [--repeats R] [--threads T]
//
// Prints the medians (s) of: value, gradient (points), gradient with hessian_points (the
// state kept), the full product and the Gauss–Newton product, and product/gradient.

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "softhd/hausdorff.hpp"

namespace {

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

softhd::PointCloud cube_cloud(int n, int d, unsigned seed, double lo, double hi) {
  std::mt19937_64 gen(seed);
  std::uniform_real_distribution<double> u(lo, hi), vol(0.5, 1.5);
  Eigen::MatrixXd p(n, d);
  Eigen::VectorXd v(n);
  for (int i = 0; i < n; ++i) {
    for (int k = 0; k < d; ++k) p(i, k) = u(gen);
    v[i] = vol(gen);
  }
  return softhd::PointCloud(p, v);
}

template <class F>
double seconds(F&& f) {
  const auto start = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

int main(int argc, char** argv) try {
  int n = 4000, m = 4000, dim = 3, repeats = 7, threads = 0;
  double alpha = 4.0, tau = 1e-6;
  std::string method = "exact";
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool more = i + 1 < argc;
    if (a == "--n" && more)
      n = std::stoi(argv[++i]);
    else if (a == "--m" && more)
      m = std::stoi(argv[++i]);
    else if (a == "--dim" && more)
      dim = std::stoi(argv[++i]);
    else if (a == "--alpha" && more)
      alpha = std::stod(argv[++i]);
    else if (a == "--method" && more)
      method = argv[++i];
    else if (a == "--tau" && more)
      tau = std::stod(argv[++i]);
    else if (a == "--repeats" && more)
      repeats = std::max(1, std::stoi(argv[++i]));
    else if (a == "--threads" && more)
      threads = std::stoi(argv[++i]);
    else {
      std::fprintf(stderr, "bench_hessian: unknown argument %s\n", a.c_str());
      return 2;
    }
  }
  const softhd::PointCloud X = cube_cloud(n, dim, 1, 0.0, 1.0), Y = cube_cloud(m, dim, 2, 0.1, 1.1);
  softhd::HausdorffOptions o;
  o.params.alpha = alpha;
  o.method = softhd::method_from_string(method);
  o.tolerance = tau;
  o.threads = threads;
  const softhd::HausdorffTarget target(Y, o);
  softhd::HausdorffRequest value, gradient, state;
  gradient.gradient_points = true;
  state.gradient_points = true;
  state.hessian_points = true;
  Eigen::MatrixXd dir = cube_cloud(n, dim, 3, -1.0, 1.0).points();
  std::vector<double> tv, tg, ts, th, tn;
  softhd::SumWork work;
  for (int r = 0; r < repeats; ++r) {
    tv.push_back(seconds([&] { (void)target.evaluate(X, value); }));
    tg.push_back(seconds([&] { (void)target.evaluate(X, gradient); }));
    softhd::HausdorffResult at;
    ts.push_back(seconds([&] { at = target.evaluate(X, state); }));
    th.push_back(seconds([&] {
      dir = target.hessian_product(at, dir, softhd::HessianPart::full, &work);
      dir /= dir.norm();
    }));
    tn.push_back(seconds([&] {
      dir = target.hessian_product(at, dir, softhd::HessianPart::gauss_newton);
      dir /= dir.norm();
    }));
  }
  const double g = median(tg);
  std::printf("%s N %d M %d %dD alpha %g tau %g threads %d repeats %d\n", method.c_str(), n, m, dim,
              alpha, tau, threads, repeats);
  std::printf("  value %.4f s  gradient %.4f s  gradient+state %.4f s\n", median(tv), g,
              median(ts));
  std::printf("  product full %.4f s (%.2f x gradient)  gauss-newton %.4f s (%.2f x gradient)\n",
              median(th), median(th) / g, median(tn), median(tn) / g);
  std::printf("  product passes %d, pairs summed directly %lld\n", work.passes,
              static_cast<long long>(work.near_pairs));
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "bench_hessian: %s\n", e.what());
  return 1;
}
