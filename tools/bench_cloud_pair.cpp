// Method tree against method exact on two cloud files, value + gradient, in one process:
// the evaluations of the methods interleaved, medians of the repeats, and the work split
// of the tree's last evaluation (issue 13: passes too small for the ladder, e.g. a
// 765-node body against the 30 753-point torsion target).
//
//   bench_cloud_pair MOVING TARGET [--taus 1e-2,1e-4,1e-6] [--repeats 15] [--threads 0]
//
// One line per τ: exact s, tree s and tree/exact, with the cost model (default) and with
// every pass planned (tree_fallback = false), then the work split of each.

#include <algorithm>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include "softhd/hausdorff.hpp"
#include "softhd/io/cloud_io.hpp"

namespace {

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

void print_work(const char* name, const softhd::HausdorffResult& r) {
  const softhd::SumWork& w = r.work;
  std::printf(
      "  %-7s near %lld far %lld basis %lld node pairs %lld axes %lld plan %.4f s, "
      "exact passes %d/%d\n",
      name, static_cast<long long>(w.near_pairs), static_cast<long long>(w.far_kernel),
      static_cast<long long>(w.far_basis), static_cast<long long>(w.node_pairs),
      static_cast<long long>(w.bound_axes), w.plan_seconds, w.exact_passes, w.passes);
}

}  // namespace

int main(int argc, char** argv) try {
  if (argc < 3) {
    std::fprintf(stderr,
                 "usage: bench_cloud_pair MOVING TARGET [--taus t1,t2,...] [--repeats R] "
                 "[--threads T]\n");
    return 2;
  }
  std::vector<double> taus = {1e-2, 1e-4, 1e-6};
  int repeats = 15, threads = 0;
  for (int i = 3; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--taus" && i + 1 < argc) {
      taus.clear();
      std::stringstream list(argv[++i]);
      for (std::string t; std::getline(list, t, ',');) taus.push_back(std::stod(t));
    } else if (a == "--repeats" && i + 1 < argc) {
      repeats = std::max(1, std::stoi(argv[++i]));
    } else if (a == "--threads" && i + 1 < argc) {
      threads = std::stoi(argv[++i]);
    } else {
      std::fprintf(stderr, "bench_cloud_pair: unknown argument %s\n", a.c_str());
      return 2;
    }
  }
  const softhd::PointCloud X = softhd::read_cloud(argv[1]);
  const softhd::PointCloud Y = softhd::read_cloud(argv[2]);
  softhd::HausdorffRequest request;
  request.gradient_points = true;
  softhd::HausdorffOptions exact;
  exact.threads = threads;
  const softhd::HausdorffTarget te(Y, exact);
  std::printf("N = %lld, M = %lld, value + gradient, medians of %d\n",
              static_cast<long long>(X.size()), static_cast<long long>(Y.size()), repeats);
  for (const double tau : taus) {
    softhd::HausdorffOptions model = exact;
    model.method = softhd::Method::tree;
    model.tolerance = tau;
    softhd::HausdorffOptions forced = model;
    forced.tree_fallback = false;
    const softhd::HausdorffTarget tm(Y, model), tf(Y, forced);
    std::vector<double> se, sm, sf;
    softhd::HausdorffResult rm, rf;
    for (int r = 0; r < repeats; ++r) {
      se.push_back(te.evaluate(X, request).seconds);
      rm = tm.evaluate(X, request);
      sm.push_back(rm.seconds);
      rf = tf.evaluate(X, request);
      sf.push_back(rf.seconds);
    }
    const double e = median(se), m = median(sm), f = median(sf);
    std::printf(
        "tau %g: exact %.4f s, tree %.4f s (%.2f x exact), every pass planned %.4f s "
        "(%.2f x)\n",
        tau, e, m, m / e, f, f / e);
    print_work("tree", rm);
    print_work("planned", rf);
  }
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "bench_cloud_pair: %s\n", e.what());
  return 2;
}
