// Pair-sum passes on sampled outer points (issue 13, round 4): N = M uniform cubes too
// large for a full exact evaluation, timed for methods exact and tree on the SAME random
// subset of K outer points of each pass, against ALL sources. Both passes of a value +
// gradient evaluation are timed as the library runs them (hausdorff.cpp): pass 1, targets
// over the moving points, S only; pass 2, moving points over the targets, S, G, H, G2.
// Differences from the library's evaluation (so the ratio is of these passes only): the
// pass-2 coefficients h_j are the target weights (the library uses the pass-1 results,
// which exist only for the sampled targets here); nearest-neighbour scales and tree builds
// are outside the timings (the same for both methods). The dual tree over K sampled
// outer points has sparse outer boxes, so it shares less far-field work among outer points
// than over all N of them: the ratio understates the full evaluation's.
//
//   bench_pass_sample [--n N] [--m M] [--k K] [--tau T] [--alpha A] [--repeats R]
//                     [--no-fallback] [--csv FILE]

#include <Eigen/Core>
#include <algorithm>
#include <chrono>
#include <ctime>
#include <fstream>
#include <iostream>
#include <memory>
#include <numeric>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "hausdorff/dual_tree.hpp"
#include "hausdorff/kd_tree.hpp"
#include "hausdorff/nearest_index.hpp"
#include "hausdorff/pair_backend.hpp"
#include "hausdorff/pair_kernel.hpp"

namespace {

using namespace softhd::detail;

struct Config {
  double n = 1e6, m = 1e6, k = 1e4, tau = 1e-4, alpha = 4.0;
  int repeats = 1;
  bool fallback = true;
  std::string csv = "bench_pass_sample.csv";
};

Eigen::MatrixXd cube(Eigen::Index n, double shift, unsigned seed) {
  std::mt19937_64 gen(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Eigen::MatrixXd p(n, 3);
  for (Eigen::Index i = 0; i < n; ++i)
    for (int d = 0; d < 3; ++d) p(i, d) = shift + u(gen);
  return p;
}

Eigen::MatrixXd sample_rows(const Eigen::MatrixXd& p, Eigen::Index k, unsigned seed) {
  std::vector<Eigen::Index> idx(static_cast<size_t>(p.rows()));
  std::iota(idx.begin(), idx.end(), Eigen::Index{0});
  std::mt19937_64 gen(seed);
  std::shuffle(idx.begin(), idx.end(), gen);
  Eigen::MatrixXd out(k, p.cols());
  for (Eigen::Index i = 0; i < k; ++i) out.row(i) = p.row(idx[static_cast<size_t>(i)]);
  return out;
}

/// One pass's inputs: sampled outer points over all sources.
struct PassData {
  Eigen::MatrixXd outer;
  Eigen::VectorXd outer_scale, weight, coef, scale;
  std::unique_ptr<KdTree> outer_tree;
  unsigned flags = kOuterSum;
};

struct Timed {
  double wall = 0.0, cpu = 0.0;
  PassStats stats;
};

Timed run(const PairSumBackend& b, const Eigen::MatrixXd& src, const KdTree& src_tree,
          const PassData& d, const PassSettings& set) {
  PassSources s{&src, &src_tree, d.weight.data(), nullptr, nullptr};
  if ((d.flags & kInner) != 0) s.coef = d.coef.data(), s.scale = d.scale.data();
  const PassOuter o{&d.outer, d.outer_tree.get(), d.outer_scale.data(), d.flags, nullptr};
  const auto t0 = std::chrono::steady_clock::now();
  const std::clock_t c0 = std::clock();
  const PassSums out = b.sums(s, o, set);
  Timed t;
  t.cpu = static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC;
  t.wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  t.stats = out.stats;
  return t;
}

Config parse(int argc, char** argv) {
  Config c;
  for (int a = 1; a < argc; ++a) {
    const std::string arg = argv[a];
    auto value = [&]() -> std::string {
      if (a + 1 >= argc) throw std::runtime_error("missing value after " + arg);
      return argv[++a];
    };
    auto number = [&]() {
      const std::string v = value();
      size_t used = 0;
      double x = 0.0;
      try {
        x = std::stod(v, &used);
      } catch (const std::exception&) {
        used = 0;
      }
      if (used != v.size() || !(x > 0.0))
        throw std::runtime_error(arg + ": not a positive number: " + v);
      return x;
    };
    if (arg == "--n")
      c.n = number();
    else if (arg == "--m")
      c.m = number();
    else if (arg == "--k")
      c.k = number();
    else if (arg == "--tau")
      c.tau = number();
    else if (arg == "--alpha")
      c.alpha = number();
    else if (arg == "--repeats")
      c.repeats = static_cast<int>(number());
    else if (arg == "--no-fallback")
      c.fallback = false;
    else if (arg == "--csv")
      c.csv = value();
    else
      throw std::runtime_error("unknown flag " + arg);
  }
  if (!(c.k >= 1 && c.k <= std::min(c.n, c.m)))
    throw std::runtime_error("--k must be in [1, min(n, m)]");
  return c;
}

}  // namespace

int main(int argc, char** argv) try {
  const Config c = parse(argc, argv);
  const double eps = 1e-3;
  const auto N = static_cast<Eigen::Index>(c.n), M = static_cast<Eigen::Index>(c.m),
             K = static_cast<Eigen::Index>(c.k);
  // The goal's clouds: moving X in [0,1]³, targets Y shifted by 0.05 (bench_hausdorff's
  // seeds), uniform weights.
  const Eigen::MatrixXd X = cube(N, 0.0, 1), Y = cube(M, 0.05, 2);
  const KdTree xt(X, kLeafSize), yt(Y, kLeafSize);
  const NearestIndex xi(X), yi(Y);
  PassData p1, p2;
  p1.outer = sample_rows(Y, K, 3);
  p1.outer_scale = xi.distances(p1.outer, 2, nullptr).array() + eps;
  p1.weight = Eigen::VectorXd::Constant(N, 1.0 / static_cast<double>(N));
  p1.flags = kOuterSum;
  p2.outer = sample_rows(X, K, 4);
  p2.outer_scale = yi.distances(p2.outer, 2, nullptr).array() + eps;
  p2.weight = Eigen::VectorXd::Constant(M, 1.0 / static_cast<double>(M));
  p2.coef = p2.weight;
  p2.scale = xi.distances(Y, 2, nullptr).array() + eps;
  p2.flags = kOuterSum | kOuterGrad | kInner;
  p1.outer_tree = std::make_unique<KdTree>(p1.outer, kLeafSize);
  p2.outer_tree = std::make_unique<KdTree>(p2.outer, kLeafSize);
  const KernelPower power(c.alpha);
  PassSettings set{&power, eps, c.tau, 2, nullptr};
  DualTreeConfig cfg;
  cfg.cost_model = c.fallback;
  const auto tree = make_dual_tree_backend(cfg, nullptr);
  const auto exact = make_exact_backend();
  std::ofstream csv(c.csv, std::ios::app);
  csv << "N,M,K,alpha,tau,repeat,method,pass,wall_s,cpu_s,near_pairs,far_kernel,far_basis,"
         "node_pairs,plan_s,fell_back\n";
  for (int r = 0; r < c.repeats; ++r)
    for (const char* name : {"exact", "tree"}) {
      const PairSumBackend& b = name[0] == 'e' ? *exact : *tree;
      const Timed t1 = run(b, X, xt, p1, set), t2 = run(b, Y, yt, p2, set);
      for (int pass = 1; pass <= 2; ++pass) {
        const Timed& t = pass == 1 ? t1 : t2;
        csv << N << ',' << M << ',' << K << ',' << c.alpha << ',' << c.tau << ',' << r << ','
            << name << ',' << pass << ',' << t.wall << ',' << t.cpu << ',' << t.stats.near_pairs
            << ',' << t.stats.far_kernel << ',' << t.stats.far_basis << ',' << t.stats.node_pairs
            << ',' << t.stats.plan_seconds << ',' << t.stats.fell_back << '\n';
      }
      std::cerr << name << " repeat " << r << ": pass 1 " << t1.wall << " s (cpu " << t1.cpu
                << "), pass 2 " << t2.wall << " s (cpu " << t2.cpu << "), both "
                << t1.wall + t2.wall << " s (cpu " << t1.cpu + t2.cpu << "); near "
                << t1.stats.near_pairs + t2.stats.near_pairs << " far "
                << t1.stats.far_kernel + t2.stats.far_kernel << " fell back " << t1.stats.fell_back
                << "/" << t2.stats.fell_back << "\n";
    }
  return 0;
} catch (const std::exception& e) {
  std::cerr << "bench_pass_sample: " << e.what() << "\n";
  return 2;
}
