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
// between the two results (rho and the gradient), the share of the one-rank time in the
// pair sums ("pairs") and the share of passes method tree summed exactly ("exact"). Every
// number is measured.
//
// On a machine shared with other work the wall-clock ratio depends on how much of the
// cores the others leave. The CPU-time ratio is the speed-up on otherwise idle cores: rank
// 0's CPU seconds alone against the largest rank's CPU seconds outside the reductions plus
// the wall time of the same reductions when every rank arrives at once (measured after a
// barrier): a rank descheduled by other work makes the others wait, spinning, in the
// reductions, which is not the cost of the method. Both are printed, with the load average.

#include <mpi.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
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

double cpu_seconds();

/// Forwards to the MPI share and counts the bytes this rank puts into the reductions and
/// the CPU seconds it spends in them (waiting for the other ranks included).
class CountingShare final : public WorkShare {
 public:
  explicit CountingShare(std::shared_ptr<const WorkShare> inner) : inner_(std::move(inner)) {}
  int size() const override { return inner_->size(); }
  int rank() const override { return inner_->rank(); }
  void sum(double* data, std::size_t n) const override {
    bytes += 8.0 * static_cast<double>(n);
    const double start = cpu_seconds();
    inner_->sum(data, n);
    reduce_cpu += cpu_seconds() - start;
  }
  void sum(std::int64_t* data, std::size_t n) const override {
    bytes += 8.0 * static_cast<double>(n);
    const double start = cpu_seconds();
    inner_->sum(data, n);
    reduce_cpu += cpu_seconds() - start;
  }
  mutable double bytes = 0.0, reduce_cpu = 0.0;

 private:
  std::shared_ptr<const WorkShare> inner_;
};

/// Points on a sphere of radius `radius` centred at (shift, 0, 0), volumes in [0.5, 1.5]: a
/// surface, as a scan is (on a cube of uniform points method tree sums every pass exactly,
/// docs/bench_hausdorff.md).
PointCloud shell(Eigen::Index n, unsigned seed, double radius, double shift) {
  std::mt19937_64 gen(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::MatrixXd p(n, 3);
  Eigen::VectorXd v(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    Eigen::Vector3d x(g(gen), g(gen), g(gen));
    x *= radius / x.norm();
    x[0] += shift;
    p.row(i) = x.transpose();
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

double cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

/// Peak resident memory of this process, MB (VmHWM), or −1.
double peak_mb() {
  std::ifstream in("/proc/self/status");
  for (std::string line; std::getline(in, line);)
    if (line.rfind("VmHWM:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;
  return -1.0;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

struct Row {
  std::string method;
  double t1 = 0, tk = 0, c1 = 0, ck = 0, comm = 0, exact_passes = 0, pair_share = 0, bytes = 0,
         diff = 0;
};

/// Wall seconds of summing `bytes` of doubles over the ranks when all arrive together (after
/// a barrier): the reductions' cost without waiting. Median of 5.
double reduction_seconds(const WorkShare& share, double bytes) {
  std::vector<double> buffer(static_cast<size_t>(bytes / 8.0), 1.0), t;
  for (int rep = 0; rep < 5; ++rep) {
    MPI_Barrier(MPI_COMM_WORLD);
    const auto start = std::chrono::steady_clock::now();
    share.sum(buffer.data(), buffer.size());
    t.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  return median(t);
}

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
  std::vector<double> t1, tk, c1, ck, pair;
  HausdorffResult r1, rk;
  for (int rep = 0; rep < repeats; ++rep) {
    MPI_Barrier(MPI_COMM_WORLD);
    if (rank == 0) {
      const auto start = std::chrono::steady_clock::now();
      const double cpu = cpu_seconds();
      r1 = alone.evaluate(X, req);
      c1.push_back(cpu_seconds() - cpu);
      t1.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
      pair.push_back(r1.work.run_seconds);
    }
    wait_asleep();
    counting->bytes = counting->reduce_cpu = 0.0;
    MPI_Barrier(MPI_COMM_WORLD);
    const auto start = std::chrono::steady_clock::now();
    double cpu = cpu_seconds();
    rk = shared.evaluate(X, req);
    // Each rank's own work: CPU seconds outside the reductions; the largest over the ranks.
    double work = cpu_seconds() - cpu - counting->reduce_cpu;
    MPI_Allreduce(MPI_IN_PLACE, &work, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
    ck.push_back(work);
    tk.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  Row row;
  row.method = to_string(method);
  const double bytes = counting->bytes;
  const double comm = reduction_seconds(*counting, bytes);  // collective
  if (rank != 0) return row;
  row.t1 = median(t1);
  row.tk = median(tk);
  row.c1 = median(c1);
  row.comm = comm;
  row.ck = median(ck) + row.comm;
  row.pair_share = method == Method::nearest ? 0.0 : median(pair) / row.t1;
  row.bytes = bytes;
  row.exact_passes =
      r1.work.passes > 0 ? static_cast<double>(r1.work.exact_passes) / r1.work.passes : 0.0;
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
  const PointCloud X = shell(n, 1, 1.0, 0.0), Y = shell(m, 2, 1.1, 0.1);
  std::vector<Row> rows;
  for (const std::string& name : split(methods))
    rows.push_back(run_case(method_from_string(name), X, Y, tau, grad, repeats));
  double peak = peak_mb();
  MPI_Allreduce(MPI_IN_PLACE, &peak, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  if (rank != 0) return 0;
  std::printf(
      "peak resident memory of a rank: %.0f MB (both clouds, the target twice: alone "
      "and shared)\n",
      peak);
  std::printf(
      "N = %ld moving, M = %ld target points (shells), %s, tau %g (tree), %d repeats, medians\n", n,
      m, grad ? "value + gradient" : "value", tau, repeats);
  double load[3] = {0, 0, 0};
  if (FILE* f = std::fopen("/proc/loadavg", "r")) {
    if (std::fscanf(f, "%lf %lf %lf", &load[0], &load[1], &load[2]) != 3) load[0] = -1;
    std::fclose(f);
  }
  std::printf("load average at the end %.2f (1 min) on %u cores\n", load[0],
              std::thread::hardware_concurrency());
  std::printf("%-8s %9s %9s %8s %9s %9s %8s %6s %6s %9s %8s\n", "method", "wall 1", "wall K",
              "wall x", "cpu 1", "cpu K max", "cpu x", "pairs", "exact", "MB/rank", "rel diff");
  std::ofstream out;
  if (!csv.empty()) {
    out.open(csv);
    out << "method,n,m,grad,tau,ranks,seconds_1,seconds_k,speedup,cpu_1,cpu_k,cpu_speedup,"
           "pair_share,exact_passes,bytes_per_rank,rel_diff,load1,peak_mb\n";
  }
  for (const Row& r : rows) {
    std::printf("%-8s %9.4f %9.4f %7.2fx %9.4f %9.4f %7.2fx %5.0f%% %5.0f%% %9.2f %8.1e\n",
                r.method.c_str(), r.t1, r.tk, r.t1 / r.tk, r.c1, r.ck, r.c1 / r.ck,
                100.0 * r.pair_share, 100.0 * r.exact_passes, r.bytes / 1e6, r.diff);
    if (out)
      out << r.method << ',' << n << ',' << m << ',' << grad << ',' << tau << ',' << size << ','
          << r.t1 << ',' << r.tk << ',' << r.t1 / r.tk << ',' << r.c1 << ',' << r.ck << ','
          << r.c1 / r.ck << ',' << r.pair_share << ',' << r.exact_passes << ',' << r.bytes << ','
          << r.diff << ',' << load[0] << ',' << peak << '\n';
  }
  return 0;
}
