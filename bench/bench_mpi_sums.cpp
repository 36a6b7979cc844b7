// bench_mpi_sums: distributed pair sums, 1 rank against 2 (or K) ranks in one run.
//
//   mpiexec -n 2 bench_mpi_sums [--n N] [--m M] [--methods exact,tree,nearest]
//                               [--tau T] [--grad] [--repeats R] [--csv FILE]
//
// Each case is evaluated alternately by rank 0 alone (the other ranks wait asleep, not
// spinning) and by every rank with the pair sums shared over MPI_COMM_WORLD, one OpenMP
// thread per rank; R repeats of each, medians, and their ratio (the speed-up). Also printed:
// the share of the one-rank time spent in the pair sums, the bytes each rank sends into the
// reductions per evaluation (counted by the share), and the largest relative difference
// between the two results (rho and the gradient). Every number is measured.

#include <mpi.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "softhd/hausdorff.hpp"
#include "softhd/mpi/work_share.hpp"

namespace {

using namespace softhd;

/// Forwards to the MPI share and counts the bytes this rank puts into the reductions.
class CountingShare final : public WorkShare {
 public:
  explicit CountingShare(std::shared_ptr<const WorkShare> inner) : inner_(std::move(inner)) {}
  int size() const override { return inner_->size(); }
  int rank() const override { return inner_->rank(); }
  void sum(double* data, std::size_t n) const override {
    bytes += 8.0 * static_cast<double>(n);
    inner_->sum(data, n);
  }
  void sum(std::int64_t* data, std::size_t n) const override {
    bytes += 8.0 * static_cast<double>(n);
    inner_->sum(data, n);
  }
  mutable double bytes = 0.0;

 private:
  std::shared_ptr<const WorkShare> inner_;
};

/// Points in [0, 1]^3 with volumes in [0.5, 1.5]; the target is shifted by `shift` so the
/// clouds overlap but differ.
PointCloud cube(Eigen::Index n, unsigned seed, double shift) {
  std::mt19937_64 gen(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Eigen::MatrixXd p(n, 3);
  Eigen::VectorXd v(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) p(i, k) = u(gen) + (k == 0 ? shift : 0.0);
    v[i] = 0.5 + u(gen);
  }
  return PointCloud(p, v);
}

/// Waits for the barrier that ends a one-rank evaluation without occupying a core.
void wait_asleep() {
  MPI_Request req;
  MPI_Ibarrier(MPI_COMM_WORLD, &req);
  int done = 0;
  while (!done) {
    MPI_Test(&req, &done, MPI_STATUS_IGNORE);
    if (!done) std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

struct Row {
  std::string method;
  double t1 = 0, tk = 0, pair_share = 0, bytes = 0, diff = 0;
};

double max_relative(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  if (b.size() == 0) return 0.0;
  return (a - b).cwiseAbs().maxCoeff() / b.cwiseAbs().maxCoeff();
}

Row run_case(Method method, const PointCloud& X, const PointCloud& Y, double tau, bool grad,
             int repeats) {
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  HausdorffOptions opt;
  opt.method = method;
  opt.tolerance = tau;
  opt.threads = 1;
  HausdorffRequest req;
  req.gradient_points = grad && method != Method::nearest;
  const HausdorffTarget alone(Y, opt);
  auto counting = std::make_shared<CountingShare>(mpi::work_share(MPI_COMM_WORLD));
  opt.share = counting;
  const HausdorffTarget shared(Y, opt);
  std::vector<double> t1, tk, pair;
  HausdorffResult r1, rk;
  for (int rep = 0; rep < repeats; ++rep) {
    MPI_Barrier(MPI_COMM_WORLD);
    if (rank == 0) {
      const auto start = std::chrono::steady_clock::now();
      r1 = alone.evaluate(X, req);
      t1.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
      pair.push_back(r1.work.run_seconds);
    }
    wait_asleep();
    counting->bytes = 0.0;
    MPI_Barrier(MPI_COMM_WORLD);
    const auto start = std::chrono::steady_clock::now();
    rk = shared.evaluate(X, req);
    MPI_Barrier(MPI_COMM_WORLD);  // the slowest rank's time
    tk.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  Row row;
  row.method = to_string(method);
  if (rank != 0) return row;
  row.t1 = median(t1);
  row.tk = median(tk);
  row.pair_share = method == Method::nearest ? 0.0 : median(pair) / row.t1;
  row.bytes = counting->bytes;
  row.diff = std::fabs(rk.rho - r1.rho) / r1.rho;
  if (req.gradient_points)
    row.diff = std::max(row.diff, max_relative(rk.gradient_points, r1.gradient_points));
  return row;
}

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream in(s);
  for (std::string item; std::getline(in, item, ',');) out.push_back(item);
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  const mpi::Session session(&argc, &argv);
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  long n = 20000, m = 20000;
  int repeats = 3;
  double tau = 1e-2;
  bool grad = false;
  std::string methods = "exact,tree,nearest", csv;
  for (int a = 1; a < argc; ++a) {
    const std::string arg = argv[a];
    auto next = [&]() -> std::string {
      if (a + 1 >= argc) throw std::runtime_error(arg + " needs a value");
      return argv[++a];
    };
    if (arg == "--n")
      n = std::stol(next());
    else if (arg == "--m")
      m = std::stol(next());
    else if (arg == "--tau")
      tau = std::stod(next());
    else if (arg == "--repeats")
      repeats = std::stoi(next());
    else if (arg == "--methods")
      methods = next();
    else if (arg == "--csv")
      csv = next();
    else if (arg == "--grad")
      grad = true;
    else {
      if (rank == 0)
        std::fprintf(stderr, "bench_mpi_sums: unknown option %s (see the source's header)\n",
                     arg.c_str());
      return 2;
    }
  }
  if (size < 2) {
    std::fprintf(stderr, "bench_mpi_sums: run under mpiexec -n 2 (or more)\n");
    return 2;
  }
  const PointCloud X = cube(n, 1, 0.0), Y = cube(m, 2, 0.2);
  std::vector<Row> rows;
  for (const std::string& name : split(methods))
    rows.push_back(run_case(method_from_string(name), X, Y, tau, grad, repeats));
  if (rank != 0) return 0;
  std::printf(
      "N = %ld moving, M = %ld target points (cube), %s, tau %g (tree), %d repeats, medians\n", n,
      m, grad ? "value + gradient" : "value", tau, repeats);
  std::printf("%-8s %10s %10s %8s %10s %12s %10s\n", "method", "1 rank s", "ranks", "speed-up",
              "pair share", "MB per rank", "rel diff");
  std::ofstream out;
  if (!csv.empty()) {
    out.open(csv);
    out << "method,n,m,grad,tau,ranks,seconds_1,seconds_k,speedup,pair_share,bytes_per_rank,rel_"
           "diff\n";
  }
  for (const Row& r : rows) {
    std::printf("%-8s %10.4f %7d: %6.4f %6.2fx %9.0f%% %12.2f %10.1e\n", r.method.c_str(), r.t1,
                size, r.tk, r.t1 / r.tk, 100.0 * r.pair_share, r.bytes / 1e6, r.diff);
    if (out)
      out << r.method << ',' << n << ',' << m << ',' << grad << ',' << tau << ',' << size << ','
          << r.t1 << ',' << r.tk << ',' << r.t1 / r.tk << ',' << r.pair_share << ',' << r.bytes
          << ',' << r.diff << '\n';
  }
  return 0;
}
