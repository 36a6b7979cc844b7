// Run time against error of the regularised Hausdorff distance (docs/formulation.md §2): methods
// exact, tree (several τ) and nearest, value only and value + gradient, on four cloud families and
// a ladder of sizes N = M. Writes one CSV row per (cloud, size, method, τ, mode).
//
//   bench_hausdorff [--min-n 1000] [--max-n 1000000] [--repeats 3] [--csv FILE]
//                   [--exact-max 100000] [--shapes cube,shell,clusters,plate]
//                   [--taus 1e-2,1e-4,1e-6,1e-8,1e-10] [--modes value,value+grad]
//                   [--methods nearest,exact,tree]
//                   [--budget 300] [--threads 0] [--quick] [--no-fallback]
//
// Errors are measured against method exact: the full evaluation when N ≤ --exact-max,
// else exact fields on a random subset of 500 target and 500 moving points
// (error_reference = subset:1000; ρ̃ and gradient errors are then not measured).
// A (method, τ, mode) whose predicted time at the next size exceeds --budget seconds
// (time × (N'/N)^k with k = 2 for exact, 1.5 for tree, 1 for nearest) is not run.
// The work columns (near_pairs … passes) are the SumWork of the last run (plan_s and sums_s,
// the pair sums' wall time with the traversal: medians over the runs); --no-fallback makes
// method tree plan every pass (its cost model's data, docs/tree_tolerance.md §8).

#include <Eigen/Core>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <iostream>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "softhd/hausdorff.hpp"
#include "softhd/point_cloud.hpp"

namespace {

using softhd::HausdorffOptions;
using softhd::HausdorffRequest;
using softhd::HausdorffResult;
using softhd::Method;
using softhd::PointCloud;

struct Config {
  double min_n = 1e3, max_n = 1e6;
  int repeats = 3;
  std::string csv = "bench_hausdorff.csv";
  double exact_max = 1e5;
  std::vector<std::string> shapes = {"cube", "shell", "clusters", "plate"};
  std::vector<double> taus = {1e-2, 1e-4, 1e-6, 1e-8, 1e-10};
  std::vector<std::string> modes = {"value", "value+grad"};
  std::vector<std::string> methods = {"nearest", "exact", "tree"};
  double budget = 300.0;
  int threads = 0;
  bool fallback = true;  // --no-fallback: method tree plans every pass (cost-model data)
};

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream in(s);
  for (std::string item; std::getline(in, item, ',');) out.push_back(item);
  return out;
}

// ---- cloud generators (fixed seeds) -------------------------------------------------

PointCloud uniform_cube(Eigen::Index n, double shift, unsigned seed) {
  std::mt19937_64 gen(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Eigen::MatrixXd p(n, 3);
  for (Eigen::Index i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k) p(i, k) = shift + u(gen);
  return PointCloud(p);
}

PointCloud sphere_shell(Eigen::Index n, double radius, unsigned seed) {
  std::mt19937_64 gen(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::MatrixXd p(n, 3);
  for (Eigen::Index i = 0; i < n; ++i) {
    Eigen::Vector3d x(g(gen), g(gen), g(gen));
    p.row(i) = radius * x.normalized().transpose();
  }
  return PointCloud(p);
}

// Eight dense Gaussian blobs (σ = 0.02) at fixed random centres in [0, 10]^3.
PointCloud clusters(Eigen::Index n, unsigned seed) {
  std::mt19937_64 centres_gen(1234), gen(seed);
  std::uniform_real_distribution<double> u(0.0, 10.0);
  std::normal_distribution<double> g(0.0, 0.02);
  Eigen::Matrix<double, 8, 3> c;
  for (int b = 0; b < 8; ++b)
    for (int k = 0; k < 3; ++k) c(b, k) = u(centres_gen);
  Eigen::MatrixXd p(n, 3);
  for (Eigen::Index i = 0; i < n; ++i) {
    const int b = static_cast<int>(gen() % 8);
    for (int k = 0; k < 3; ++k) p(i, k) = c(b, k) + g(gen);
  }
  return PointCloud(p);
}

// A grid over [0,10]×[0,2]×[0,0.1] with about n points (at least 2 across the thickness),
// optionally bent by the arc map of docs/formulation.md §5.2 (total angle θ).
PointCloud plate(double n, double theta) {
  auto count = [](double h, double len) { return static_cast<int>(std::lround(len / h)) + 1; };
  double lo = 1e-4, hi = 10.0;
  for (int it = 0; it < 100; ++it) {  // bisection on the spacing h
    const double h = std::sqrt(lo * hi);
    const double total = 1.0 * count(h, 10) * count(h, 2) * std::max(2, count(h, 0.1));
    (total > n ? lo : hi) = h;
  }
  const double h = hi;
  const int n1 = count(h, 10), n2 = count(h, 2), n3 = std::max(2, count(h, 0.1));
  Eigen::MatrixXd p(static_cast<Eigen::Index>(n1) * n2 * n3, 3);
  Eigen::Index row = 0;
  const double R = theta > 0 ? 10.0 / theta : 0.0;
  for (int a = 0; a < n1; ++a)
    for (int b = 0; b < n2; ++b)
      for (int c = 0; c < n3; ++c, ++row) {
        const double X1 = 10.0 * a / (n1 - 1), X2 = 2.0 * b / (n2 - 1), X3 = 0.1 * c / (n3 - 1);
        if (theta > 0) {
          const double z = X3 - 0.05;
          p.row(row) << (R - z) * std::sin(X1 / R), X2, 0.05 + R - (R - z) * std::cos(X1 / R);
        } else {
          p.row(row) << X1, X2, X3;
        }
      }
  return PointCloud(p);
}

// Moving and target clouds of one family at size n.
std::pair<PointCloud, PointCloud> make_pair_of(const std::string& shape, Eigen::Index n) {
  if (shape == "cube") return {uniform_cube(n, 0.0, 1), uniform_cube(n, 0.05, 2)};
  if (shape == "shell") return {sphere_shell(n, 1.0, 3), sphere_shell(n, 1.02, 4)};
  if (shape == "clusters") return {clusters(n, 5), clusters(n, 6)};
  if (shape == "plate") return {plate(static_cast<double>(n), 0.0), plate(0.8 * n, 1.0)};
  throw std::runtime_error("unknown shape " + shape);
}

// ---- timing and errors -------------------------------------------------------------

struct Timed {
  double median = 0, min = 0, cpu = 0;  // wall median, wall min, CPU-time median (all threads)
  double plan = 0, sums = 0;            // medians of SumWork's plan_seconds and run_seconds
  HausdorffResult last;
};

Timed run(const softhd::HausdorffTarget& target, const PointCloud& X, const HausdorffRequest& req,
          int repeats) {
  std::vector<double> t, cpu, plan, sums;
  Timed out;
  for (int r = 0; r < repeats; ++r) {
    const auto start = std::chrono::steady_clock::now();
    const std::clock_t cpu_start = std::clock();
    out.last = target.evaluate(X, req);
    cpu.push_back(static_cast<double>(std::clock() - cpu_start) / CLOCKS_PER_SEC);
    t.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    plan.push_back(out.last.work.plan_seconds);
    sums.push_back(out.last.work.run_seconds);
  }
  std::sort(t.begin(), t.end());
  std::sort(cpu.begin(), cpu.end());
  std::sort(plan.begin(), plan.end());
  std::sort(sums.begin(), sums.end());
  out.median = t[t.size() / 2];
  out.min = t.front();
  out.cpu = cpu[cpu.size() / 2];
  out.plan = plan[plan.size() / 2];
  out.sums = sums[sums.size() / 2];
  return out;
}

// Exact values to compare with: the full exact result, or exact fields on subsets.
struct ExactReference {
  bool full = false;
  HausdorffResult result;                  // full: value, fields, gradient of the points
  std::vector<Eigen::Index> sub_y, sub_x;  // subset: indices
  Eigen::VectorXd field_y, field_x;        // subset: exact fields there
  std::string label() const {
    return full ? "full" : "subset:" + std::to_string(sub_y.size() + sub_x.size());
  }
};

ExactReference subset_reference(const PointCloud& X, const PointCloud& Y, int k,
                                const HausdorffOptions& exact) {
  ExactReference ref;
  std::mt19937_64 gen(77);
  auto pick = [&](Eigen::Index n) {
    std::vector<Eigen::Index> idx;
    for (int i = 0; i < k; ++i) idx.push_back(static_cast<Eigen::Index>(gen() % n));
    return idx;
  };
  ref.sub_y = pick(Y.size());
  ref.sub_x = pick(X.size());
  auto rows = [](const PointCloud& c, const std::vector<Eigen::Index>& idx) {
    Eigen::MatrixXd p(static_cast<Eigen::Index>(idx.size()), c.dim());
    Eigen::VectorXd v(p.rows());
    for (Eigen::Index r = 0; r < p.rows(); ++r) {
      p.row(r) = c.points().row(idx[static_cast<size_t>(r)]);
      v[r] = c.volumes()[idx[static_cast<size_t>(r)]];
    }
    return PointCloud(p, v);
  };
  HausdorffRequest fields;
  fields.fields = true;
  // d̃_X(y) depends only on X and y: a subset of Y as the target gives it exactly.
  ref.field_y = softhd::hausdorff(X, rows(Y, ref.sub_y), exact, fields).field_target;
  ref.field_x = softhd::hausdorff(rows(X, ref.sub_x), Y, exact, fields).field_moving;
  return ref;
}

struct Errors {
  double rho = NAN, S = NAN, field = NAN, grad = NAN;
};

// S ∝ (d̃ + ε)^(−α) at fixed r_min, so the relative error of S follows from the fields.
void field_errors(double a, double b, double eps, double alpha, Errors& e) {
  const double s = std::fabs(std::pow((b + eps) / (a + eps), alpha) - 1.0);
  e.S = std::isnan(e.S) ? s : std::max(e.S, s);
  const double f = std::fabs(a - b) / (b + eps);
  e.field = std::isnan(e.field) ? f : std::max(e.field, f);
}

Errors measure(const HausdorffResult& r, const ExactReference& ref, double eps, double alpha) {
  Errors e;
  if (ref.full) {
    e.rho = std::fabs(r.rho - ref.result.rho) / ref.result.rho;
    if (r.field_target.size() > 0) {
      for (Eigen::Index j = 0; j < r.field_target.size(); ++j)
        field_errors(r.field_target[j], ref.result.field_target[j], eps, alpha, e);
      for (Eigen::Index i = 0; i < r.field_moving.size(); ++i)
        field_errors(r.field_moving[i], ref.result.field_moving[i], eps, alpha, e);
    }
    if (r.gradient_points.size() > 0)
      e.grad = (r.gradient_points - ref.result.gradient_points).norm() /
               ref.result.gradient_points.norm();
  } else if (r.field_target.size() > 0) {
    for (size_t s = 0; s < ref.sub_y.size(); ++s)
      field_errors(r.field_target[ref.sub_y[s]], ref.field_y[static_cast<Eigen::Index>(s)], eps,
                   alpha, e);
    for (size_t s = 0; s < ref.sub_x.size(); ++s)
      field_errors(r.field_moving[ref.sub_x[s]], ref.field_x[static_cast<Eigen::Index>(s)], eps,
                   alpha, e);
  }
  return e;
}

std::string num(double x) {
  if (std::isnan(x)) return "";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", x);
  return buf;
}

// ---- goal cases of issue 13: one configuration, ratios against exact in one run ------

// A 101×11×5 grid of the plate [0,10]×[0,2]×[0,0.1]: the 5 555 nodes of the bending mesh.
PointCloud plate_nodes() {
  Eigen::MatrixXd p(101 * 11 * 5, 3);
  Eigen::Index row = 0;
  for (int a = 0; a <= 100; ++a)
    for (int b = 0; b <= 10; ++b)
      for (int c = 0; c <= 4; ++c, ++row) p.row(row) << 0.1 * a, 0.2 * b, 0.025 * c;
  return PointCloud(p);
}

// m random points on the six faces of the plate bent by the arc map (θ = 1), area-weighted
// (the faces are mapped from the flat plate; the arc map nearly preserves area here).
PointCloud arc_faces(Eigen::Index m, unsigned seed) {
  std::mt19937_64 gen(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double L = 10.0, W = 2.0, T = 0.1, R = L / 1.0;
  const double areas[3] = {L * W, L * T, W * T};  // top/bottom, front/back, ends
  const double total = 2.0 * (areas[0] + areas[1] + areas[2]);
  Eigen::MatrixXd p(m, 3);
  for (Eigen::Index i = 0; i < m; ++i) {
    double pick = u(gen) * total, X1 = u(gen) * L, X2 = u(gen) * W, X3 = u(gen) * T;
    const double side = u(gen) < 0.5 ? 0.0 : 1.0;
    if ((pick -= 2.0 * areas[0]) < 0.0) {
      X3 = side * T;
    } else if ((pick -= 2.0 * areas[1]) < 0.0) {
      X2 = side * W;
    } else {
      X1 = side * L;
    }
    const double z = X3 - 0.05;
    p.row(i) << (R - z) * std::sin(X1 / R), X2, 0.05 + R - (R - z) * std::cos(X1 / R);
  }
  return PointCloud(p);
}

// m random points on the surfaces of a synthetic indoor scene (area-weighted), a
// stand-in for a laser scan (no real scan is kept in the repository): the floor, ceiling
// and walls of a 6 × 4 × 3 room, a table and a cabinet; the whole scan shifted by `shift`
// along x (a second, slightly misaligned scan).
PointCloud room_scan(Eigen::Index m, unsigned seed, double shift) {
  struct Face {
    int axis;             // the fixed coordinate
    double value;         // its value
    double lo[3], hi[3];  // ranges of the other two coordinates
  };
  std::vector<Face> faces;
  auto box = [&](const double lo[3], const double hi[3], bool bottom) {
    for (int k = 0; k < 3; ++k)
      for (int side = 0; side < 2; ++side) {
        if (k == 2 && side == 0 && !bottom) continue;
        Face f{k, side == 0 ? lo[k] : hi[k], {lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}};
        faces.push_back(f);
      }
  };
  const double room_lo[3] = {0, 0, 0}, room_hi[3] = {6, 4, 3};
  const double table_lo[3] = {2, 1.5, 0}, table_hi[3] = {3.5, 2.5, 0.8};
  const double cab_lo[3] = {5, 0, 0}, cab_hi[3] = {6, 0.6, 2};
  box(room_lo, room_hi, true);
  box(table_lo, table_hi, false);
  box(cab_lo, cab_hi, false);
  std::vector<double> area;
  double total = 0.0;
  for (const Face& f : faces) {
    double a = 1.0;
    for (int k = 0; k < 3; ++k)
      if (k != f.axis) a *= f.hi[k] - f.lo[k];
    total += a;
    area.push_back(total);
  }
  std::mt19937_64 gen(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Eigen::MatrixXd p(m, 3);
  for (Eigen::Index i = 0; i < m; ++i) {
    const double pick = u(gen) * total;
    const size_t fi =
        static_cast<size_t>(std::lower_bound(area.begin(), area.end(), pick) - area.begin());
    const Face& f = faces[std::min(fi, faces.size() - 1)];
    for (int k = 0; k < 3; ++k)
      p(i, k) = k == f.axis ? f.value : f.lo[k] + u(gen) * (f.hi[k] - f.lo[k]);
    p(i, 0) += shift;
  }
  return PointCloud(p);
}

struct GoalConfig {
  std::string name = "cube";  // cube | asym | room
  double n = 1e5, m = 1e5, tau = 1e-4, alpha = 4.0;
  int exact_sample = 0;  // 0: time exact on the full clouds; K: on K target points, scaled
  int error_sample = 500;
  std::vector<std::string> methods = {"nearest", "exact", "tree"};
  std::string csv = "bench_hausdorff_goal.csv";
  int threads = 0;
  bool fallback = true;  // --no-fallback: method tree never sums a pass exactly
  int repeats = 1;       // --repeats R: each method R times, interleaved; medians
};

PointCloud first_rows(const PointCloud& c, Eigen::Index k) {
  return PointCloud(c.points().topRows(k), c.volumes().head(k));
}

std::pair<PointCloud, PointCloud> goal_clouds(const GoalConfig& g) {
  const auto n = static_cast<Eigen::Index>(g.n), m = static_cast<Eigen::Index>(g.m);
  if (g.name == "asym") return {plate_nodes(), arc_faces(m, 8)};
  if (g.name == "room") return {room_scan(n, 11, 0.02), room_scan(m, 12, 0.0)};
  return {uniform_cube(n, 0.0, 1), uniform_cube(m, 0.05, 2)};
}

/// One timed evaluation of `method` (value + gradient w.r.t. the moving points, with
/// fields): wall and process CPU seconds, scaled by M/K when exact is timed on K targets.
struct GoalRun {
  double wall = 0.0, cpu = 0.0;
  HausdorffResult res;
};
GoalRun time_method(const GoalConfig& g, const PointCloud& X, const PointCloud& Y,
                    const HausdorffOptions& o, std::string& exact_basis) {
  HausdorffRequest r;
  r.fields = true;
  r.gradient_points = o.method != Method::nearest;
  GoalRun run;
  const bool sample = o.method == Method::exact && g.exact_sample > 0;
  // Pair work is 2·N·M (value + gradient of the points): time it on K target points.
  const double scale = sample ? static_cast<double>(Y.size()) / g.exact_sample : 1.0;
  const softhd::HausdorffTarget target(sample ? first_rows(Y, g.exact_sample) : Y, o);
  const std::clock_t c0 = std::clock();
  run.res = target.evaluate(X, r);
  run.cpu = scale * static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC;
  run.wall = scale * run.res.seconds;
  if (sample) exact_basis = "sample:" + std::to_string(g.exact_sample);
  return run;
}

double median_of(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? NAN : v[v.size() / 2];
}

int run_goal(const GoalConfig& g) {
  const auto [X, Y] = goal_clouds(g);
  HausdorffOptions base;
  base.threads = g.threads;
  base.params.alpha = g.alpha;
  base.tolerance = g.tau;
  base.tree_fallback = g.fallback;
  std::ofstream csv(g.csv, std::ios::app);
  csv << "case,N,M,alpha,tau,method,seconds,exact_seconds,exact_basis,speedup,cpu_seconds,"
         "cpu_speedup,repeats,err_S_sample,near_pairs,far_kernel,far_basis,node_pairs,plan_s,"
         "exact_passes,passes\n";
  std::cerr << g.name << " N=" << X.size() << " M=" << Y.size() << " alpha=" << g.alpha
            << " tau=" << g.tau << "\n";
  HausdorffOptions exact = base;
  exact.method = Method::exact;
  const ExactReference ref = subset_reference(X, Y, g.error_sample, exact);
  // Methods interleaved per repeat, so that each one meets the machine's load at
  // several times; medians of wall and CPU time.
  std::string exact_basis = "full";
  std::vector<std::vector<GoalRun>> runs(g.methods.size());
  for (int rep = 0; rep < g.repeats; ++rep)
    for (size_t m = 0; m < g.methods.size(); ++m) {
      HausdorffOptions o = base;
      o.method = softhd::method_from_string(g.methods[m]);
      runs[m].push_back(time_method(g, X, Y, o, exact_basis));
    }
  double exact_s = NAN, exact_cpu = NAN;
  std::vector<double> wall(g.methods.size()), cpu(g.methods.size());
  for (size_t m = 0; m < g.methods.size(); ++m) {
    std::vector<double> w, c;
    for (const GoalRun& run : runs[m]) w.push_back(run.wall), c.push_back(run.cpu);
    wall[m] = median_of(w), cpu[m] = median_of(c);
    if (g.methods[m] == "exact") exact_s = wall[m], exact_cpu = cpu[m];
  }
  for (size_t m = 0; m < g.methods.size(); ++m) {
    const HausdorffResult& res = runs[m].front().res;
    Errors e;
    if (softhd::method_from_string(g.methods[m]) == Method::tree)
      e = measure(res, ref, base.params.epsilon, g.alpha);
    const softhd::SumWork& w = res.work;
    csv << g.name << ',' << X.size() << ',' << Y.size() << ',' << g.alpha << ',' << num(g.tau)
        << ',' << g.methods[m] << ',' << num(wall[m]) << ',' << num(exact_s) << ',' << exact_basis
        << ',' << num(exact_s / wall[m]) << ',' << num(cpu[m]) << ',' << num(exact_cpu / cpu[m])
        << ',' << g.repeats << ',' << num(e.S) << ',' << w.near_pairs << ',' << w.far_kernel << ','
        << w.far_basis << ',' << w.node_pairs << ',' << num(w.plan_seconds) << ',' << w.exact_passes
        << ',' << w.passes << '\n';
    std::cerr << "  " << g.methods[m] << " " << wall[m] << " s (cpu " << cpu[m] << " s)"
              << (std::isnan(exact_s) ? ""
                                      : ", exact/this " + num(exact_s / wall[m]) + " (cpu " +
                                            num(exact_cpu / cpu[m]) + ")")
              << (std::isnan(e.S) ? "" : ", err_S " + num(e.S)) << ", near " << w.near_pairs
              << " far " << w.far_kernel << " basis " << w.far_basis << " node pairs "
              << w.node_pairs << " plan " << num(w.plan_seconds) << " s, exact passes "
              << w.exact_passes << "/" << w.passes << "\n";
  }
  return 0;
}

int goal_main(int argc, char** argv) {
  GoalConfig g;
  for (int a = 1; a < argc; ++a) {
    const std::string arg = argv[a];
    auto value = [&]() -> std::string {
      if (a + 1 >= argc) throw std::runtime_error("missing value after " + arg);
      return argv[++a];
    };
    if (arg == "--goal")
      g.name = value();
    else if (arg == "--n")
      g.n = std::stod(value());
    else if (arg == "--m")
      g.m = std::stod(value());
    else if (arg == "--tau")
      g.tau = std::stod(value());
    else if (arg == "--alpha")
      g.alpha = std::stod(value());
    else if (arg == "--exact-sample")
      g.exact_sample = std::stoi(value());
    else if (arg == "--error-sample")
      g.error_sample = std::stoi(value());
    else if (arg == "--methods")
      g.methods = split(value());
    else if (arg == "--csv")
      g.csv = value();
    else if (arg == "--threads")
      g.threads = std::stoi(value());
    else if (arg == "--no-fallback")
      g.fallback = false;
    else if (arg == "--repeats")
      g.repeats = std::max(1, std::stoi(value()));
    else
      throw std::runtime_error("unknown argument " + arg);
  }
  if (g.name != "cube" && g.name != "asym" && g.name != "room")
    throw std::runtime_error("--goal cube|asym|room");
  return run_goal(g);
}

void usage() {
  std::cout
      << "usage: bench_hausdorff [--min-n N] [--max-n N] [--repeats R] [--csv FILE]\n"
         "       [--exact-max N] [--shapes a,b,...] [--taus t1,t2,...]\n"
         "       [--modes value,value+grad] [--methods nearest,exact,tree]\n"
         "       [--budget SECONDS]\n"
         "       [--threads T] [--quick] [--no-fallback]\n"
         "  --quick: sizes 1e3..1e4, one repeat, shapes cube,plate, taus 1e-2,1e-6\n"
         "  --no-fallback: method tree plans every pass (never sums one exactly);\n"
         "  the work columns then calibrate its cost model\n"
         "   or: bench_hausdorff --goal cube|asym|room [--n N] [--m M] [--tau T] [--alpha A]\n"
         "       [--exact-sample K] [--error-sample K] [--methods ...] [--csv FILE]\n"
         "  --goal: one case of issue 13 (asym: the 5 555 plate nodes against M points\n"
         "  on the arc's faces; room: N and M points of a synthetic indoor scan),\n"
         "  value + gradient; exact timed on K target points and\n"
         "  scaled by M/K when --exact-sample K is given; the work split per method.\n";
}

}  // namespace

int main(int argc, char** argv) {
  for (int a = 1; a < argc; ++a)
    if (std::string(argv[a]) == "--goal") {
      try {
        return goal_main(argc, argv);
      } catch (const std::exception& e) {
        std::cerr << "bench_hausdorff: " << e.what() << "\n";
        return 2;
      }
    }
  Config cfg;
  for (int a = 1; a < argc; ++a) {
    const std::string arg = argv[a];
    auto value = [&]() -> std::string {
      if (a + 1 >= argc) throw std::runtime_error("missing value after " + arg);
      return argv[++a];
    };
    if (arg == "--help" || arg == "-h") {
      usage();
      return 0;
    } else if (arg == "--min-n") {
      cfg.min_n = std::stod(value());
    } else if (arg == "--max-n") {
      cfg.max_n = std::stod(value());
    } else if (arg == "--repeats") {
      cfg.repeats = std::stoi(value());
    } else if (arg == "--csv") {
      cfg.csv = value();
    } else if (arg == "--exact-max") {
      cfg.exact_max = std::stod(value());
    } else if (arg == "--shapes") {
      cfg.shapes = split(value());
    } else if (arg == "--taus") {
      cfg.taus.clear();
      for (const std::string& t : split(value())) cfg.taus.push_back(std::stod(t));
    } else if (arg == "--methods") {
      cfg.methods = split(value());
    } else if (arg == "--modes") {
      cfg.modes = split(value());
    } else if (arg == "--budget") {
      cfg.budget = std::stod(value());
    } else if (arg == "--threads") {
      cfg.threads = std::stoi(value());
    } else if (arg == "--no-fallback") {
      cfg.fallback = false;
    } else if (arg == "--quick") {
      cfg.min_n = 1e3;
      cfg.max_n = 1e4;
      cfg.repeats = 1;
      cfg.shapes = {"cube", "plate"};
      cfg.taus = {1e-2, 1e-6};
    } else {
      std::cerr << "bench_hausdorff: unknown argument " << arg << "\n";
      usage();
      return 2;
    }
  }
  std::ofstream csv(cfg.csv);
  if (!csv) {
    std::cerr << "bench_hausdorff: cannot write " << cfg.csv << "\n";
    return 1;
  }
  csv << "shape,N,M,method,tau,mode,threads,median_s,min_s,cpu_s,runs,kernel_evaluations,rho,"
         "err_rho,err_S,err_field,err_grad,error_reference,near_pairs,far_kernel,far_basis,"
         "node_pairs,bound_axes,plan_s,sums_s,exact_passes,passes\n";
  const int threads = cfg.threads;
  std::vector<double> sizes;
  for (double n = cfg.min_n; n <= cfg.max_n * 1.0001; n *= std::sqrt(10.0))
    sizes.push_back(std::round(n));

  for (const std::string& shape : cfg.shapes) {
    // Last measured time per (method, τ, mode) and the size it was measured at.
    std::map<std::string, std::pair<double, double>> last;
    for (double n : sizes) {
      const auto [X, Y] = make_pair_of(shape, static_cast<Eigen::Index>(n));
      const double N = static_cast<double>(X.size());
      std::cerr << shape << " N=" << X.size() << " M=" << Y.size() << "\n";
      HausdorffOptions base;
      base.threads = threads;
      const double eps = base.params.epsilon, alpha = base.params.alpha;
      auto skip = [&](const std::string& key, double exponent) {
        auto it = last.find(key);
        if (it == last.end()) return false;
        const double growth = std::pow(N / it->second.second, exponent);
        return it->second.first * growth * cfg.repeats > cfg.budget;
      };
      auto row = [&](const std::string& method, double tau, const std::string& mode, const Timed& t,
                     const Errors& e, const std::string& reference) {
        const softhd::SumWork& w = t.last.work;
        csv << shape << ',' << X.size() << ',' << Y.size() << ',' << method << ',' << num(tau)
            << ',' << mode << ',' << (threads > 0 ? threads : 0) << ',' << num(t.median) << ','
            << num(t.min) << ',' << num(t.cpu) << ',' << cfg.repeats << ','
            << t.last.kernel_evaluations << ',' << num(t.last.rho) << ',' << num(e.rho) << ','
            << num(e.S) << ',' << num(e.field) << ',' << num(e.grad) << ',' << reference << ','
            << w.near_pairs << ',' << w.far_kernel << ',' << w.far_basis << ',' << w.node_pairs
            << ',' << w.bound_axes << ',' << num(t.plan) << ',' << num(t.sums) << ','
            << w.exact_passes << ',' << w.passes << '\n';
        csv.flush();
        std::cerr << "  " << method << " tau=" << num(tau) << " " << mode << " " << t.median
                  << " s, err_S " << num(e.S) << " err_grad " << num(e.grad) << "\n";
      };
      HausdorffRequest value_req, grad_req;
      value_req.fields = true;
      grad_req.fields = true;
      grad_req.gradient_points = true;

      auto wanted = [&](const std::string& m) {
        return std::find(cfg.methods.begin(), cfg.methods.end(), m) != cfg.methods.end();
      };
      // nearest: value only (it has no gradient).
      if (wanted("nearest")) {
        HausdorffOptions o = base;
        o.method = Method::nearest;
        const std::string key = "nearest";
        if (!skip(key, 1.0)) {
          const softhd::HausdorffTarget target(Y, o);
          const Timed t = run(target, X, value_req, cfg.repeats);
          last[key] = {t.median, N};
          row("nearest", NAN, "value", t, Errors{}, "none");
        }
      }
      // exact: the reference (full when small enough, else fields on subsets).
      ExactReference ref;
      const bool full = N <= cfg.exact_max;
      {
        HausdorffOptions o = base;
        o.method = Method::exact;
        const softhd::HausdorffTarget target(Y, o);
        for (const std::string& mode : cfg.modes) {
          const std::string key = "exact " + mode;
          if (wanted("exact") && (full || !skip(key, 2.0))) {
            const Timed t = run(target, X, mode == "value" ? value_req : grad_req, cfg.repeats);
            last[key] = {t.median, N};
            if (mode == "value+grad" && full) {
              ref.full = true;
              ref.result = t.last;
            }
            row("exact", NAN, mode, t, Errors{}, "self");
          }
        }
        if (!ref.full) ref = subset_reference(X, Y, 500, o);
      }
      for (double tau : cfg.taus) {
        if (!wanted("tree")) break;
        HausdorffOptions o = base;
        o.method = Method::tree;
        o.tolerance = tau;
        o.tree_fallback = cfg.fallback;
        const auto built = std::chrono::steady_clock::now();
        const softhd::HausdorffTarget target(Y, o);
        const double build_s =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - built).count();
        std::cerr << "  tree target build " << build_s << " s\n";
        for (const std::string& mode : cfg.modes) {
          const std::string key = "tree " + num(tau) + " " + mode;
          if (skip(key, 1.5)) continue;
          const Timed t = run(target, X, mode == "value" ? value_req : grad_req, cfg.repeats);
          last[key] = {t.median, N};
          row("tree", tau, mode, t, measure(t.last, ref, eps, alpha), ref.label());
        }
      }
    }
  }
  return 0;
}
