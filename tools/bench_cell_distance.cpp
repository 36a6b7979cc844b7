// The cell-integrated ρ̃ (hausdorff/cell_distance.hpp) against the continuum values of
// docs/formulation.md §2.8 (studies/continuum_reference.py) and against today's collocation
// (method exact: the nodes with lumped volumes, and the cell centres), on unit cubes of n³
// hexahedra (ε = 1e-3, α = β = 4, γ = 2):
//   bench_cell_distance [THREADS [flat|graded|exact|hybrid [T0 TP [NMAX [SPLIT]]]]]   one table:
//   case, n_X × n_Y, ρ̃ and relative error of each,
//                                   seconds of the cell value and of nodal collocation;
//                                   flat: the near cells' tangential axes by Gauss only;
//                                   exact: J itself at the near cells' points (diagnostics);
//                                   hybrid: the difference model where |g| ≤ P/2; T0, TP:
//                                   their graded rule's first panel (× ε) and points per panel;
//                                   NMAX: the largest n; SPLIT: refine_crossed
//   bench_cell_distance THREADS gradient [NMAX]   seconds of ρ̃ alone and of ρ̃ with its gradient
//                                   (both bodies' nodes), in turn, per case and n_X × n_Y
#include <Eigen/Geometry>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "hausdorff/cell_distance.hpp"
#include "softhd/hausdorff.hpp"

using namespace softhd;
using detail::HexCells;

static double now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// The nodes of a cube grid with lumped (trapezoid) volumes, or its cell centres with h³.
static PointCloud collocation_cloud(const Eigen::Vector3d& lo, double side, int n, bool nodes) {
  const double h = side / n;
  const int m = nodes ? n + 1 : n;
  Eigen::MatrixXd p(m * m * m, 3);
  Eigen::VectorXd v(m * m * m);
  for (int k = 0; k < m; ++k)
    for (int j = 0; j < m; ++j)
      for (int i = 0; i < m; ++i) {
        const int r = (k * m + j) * m + i;
        const double o = nodes ? 0.0 : 0.5;
        p.row(r) = lo.transpose() + h * Eigen::RowVector3d(i + o, j + o, k + o);
        double w = h * h * h;
        if (nodes)
          for (int a : {i, j, k})
            if (a == 0 || a == n) w *= 0.5;
        v[r] = w;
      }
  return PointCloud(p, v);
}

struct Case {
  const char* name;
  Eigen::Vector3d lo;
  double side, ref;
};
const Case cases[] = {{"self", {0, 0, 0}, 1.0, 0.124155377},
                      {"shift 0.01", {0.01, 0, 0}, 1.0, 0.126529335},
                      {"shift 0.02", {0.02, 0, 0}, 1.0, 0.133060278},
                      {"side 0.875", {0.0625, 0.0625, 0.0625}, 0.875, 0.201406692}};
const int pairs[][2] = {{4, 4}, {6, 6}, {8, 8}, {6, 8}, {12, 12}, {12, 16}, {16, 16}};

// The cost of the gradient: ρ̃ alone, then ρ̃ with ∂ρ̃/∂(both bodies' nodes), per case and pair.
static int gradient_cost(int threads, int max_n) {
  detail::CellDistanceOptions o;
  o.threads = threads;
  std::printf("%-11s %7s %12s %9s %9s %7s %12s\n", "case", "nX x nY", "rho", "t_value", "t_grad",
              "ratio", "|grad|");
  for (const Case& c : cases)
    for (const auto& p : pairs) {
      if (p[1] > max_n) continue;
      const HexCells x = detail::hex_cube(Eigen::Vector3d::Zero(), 1.0, p[0]);
      const HexCells y = detail::hex_cube(c.lo, c.side, p[1]);
      const double t0 = now();
      const double value = detail::cell_rho(x, y, o).rho;
      const double t1 = now();
      detail::CellRhoGradient g;
      const double again = detail::cell_rho(x, y, o, &g).rho;
      const double t2 = now();
      if (again != value) std::printf("(the values differ: %.17g)\n", again);
      std::printf("%-11s %3d x %-3d %12.9f %9.3f %9.3f %7.2f %12.5e\n", c.name, p[0], p[1], value,
                  t1 - t0, t2 - t1, (t2 - t1) / (t1 - t0),
                  std::sqrt(g.x.squaredNorm() + g.y.squaredNorm()));
      std::fflush(stdout);
    }
  return 0;
}

int main(int argc, char** argv) {
  const int threads = argc > 1 ? std::atoi(argv[1]) : 1;
  if (argc > 2 && std::string(argv[2]) == "gradient")
    return gradient_cost(threads, argc > 3 ? std::atoi(argv[3]) : 8);
  detail::CellDistanceOptions o;
  o.threads = threads;
  o.grade_tangential = !(argc > 2 && std::string(argv[2]) == "flat");
  o.exact_near = argc > 2 && std::string(argv[2]) == "exact";
  o.hybrid = argc > 2 && std::string(argv[2]) == "hybrid";
  if (argc > 3) o.tangential_first_panel = std::atof(argv[3]);
  if (argc > 4) o.tangential_panel_points = std::atoi(argv[4]);
  const int max_n = argc > 5 ? std::atoi(argv[5]) : 16;
  if (argc > 6) o.refine_crossed = std::atoi(argv[6]);
  HausdorffOptions ho;
  ho.method = Method::exact;
  ho.threads = threads;
  std::printf("%-11s %7s %12s %9s %12s %9s %12s %9s %8s %8s %9s\n", "case", "nX x nY", "cells",
              "err", "colloc-n", "err", "colloc-c", "err", "t_cell", "t_coll", "near_pts");
  for (const Case& c : cases)
    for (const auto& p : pairs) {
      if (p[1] > max_n) continue;
      const HexCells x = detail::hex_cube(Eigen::Vector3d::Zero(), 1.0, p[0]);
      const HexCells y = detail::hex_cube(c.lo, c.side, p[1]);
      const double t0 = now();
      const detail::CellRho r = detail::cell_rho(x, y, o);
      const double t1 = now();
      const double cn = hausdorff(collocation_cloud(Eigen::Vector3d::Zero(), 1.0, p[0], true),
                                  collocation_cloud(c.lo, c.side, p[1], true), ho)
                            .rho;
      const double t2 = now();
      const double cc = hausdorff(collocation_cloud(Eigen::Vector3d::Zero(), 1.0, p[0], false),
                                  collocation_cloud(c.lo, c.side, p[1], false), ho)
                            .rho;
      auto rel = [&](double v) { return 100.0 * (v / c.ref - 1.0); };
      std::printf(
          "%-11s %3d x %-3d %12.9f %+8.4f%% %12.6f %+8.1f%% %12.6f %+8.1f%% %8.3f %8.3f %9ld\n",
          c.name, p[0], p[1], r.rho, rel(r.rho), cn, rel(cn), cc, rel(cc), t1 - t0, t2 - t1,
          r.a.near_points + r.b.near_points);
      std::fflush(stdout);
    }
  return 0;
}
