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
//   bench_cell_distance THREADS plate NX NY NZ MX MY MZ [REPS [TOL [NR AP]]]   the plate 10 × 2 ×
//   0.1
//                                   of NX·NY·NZ hexahedra against one of MX·MY·MZ: seconds of
//                                   the cell ρ̃ (J over all pairs, by the tree at TOL, 1e-2, and
//                                   so with J's near_ratio NR, 2, and angle_points AP, 8)
//                                   and of collocation at the nodes (lumped volumes; method
//                                   exact, tree at TOL and at its default), REPS repeats
//                                   interleaved (REPS < 0: the last cell configuration alone)
//   bench_cell_distance THREADS rules CONFIG...   the outer rule's options compared (see rules())
//   bench_cell_distance THREADS gradient [NMAX]   seconds of ρ̃ alone and of ρ̃ with its gradient
//                                   (both bodies' nodes), in turn, per case and n_X × n_Y
#include <Eigen/Geometry>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

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

// The box [0, 10] × [0, 2] × [0, 0.1] meshed by nx · ny · nz hexahedra.
static HexCells plate_cells(int nx, int ny, int nz) {
  return detail::hex_box(Eigen::Vector3d::Zero(), Eigen::Vector3d(10, 2, 0.1),
                         Eigen::Vector3i(nx, ny, nz));
}

// The nodes of a hexahedral body with lumped volumes (an eighth of each cell's, the cells
// being boxes here).
static PointCloud node_cloud(const HexCells& b) {
  Eigen::VectorXd v = Eigen::VectorXd::Zero(b.nodes.rows());
  for (Eigen::Index c = 0; c < b.cells.rows(); ++c) {
    const Eigen::Vector3d d = b.nodes.row(b.cells(c, 6)) - b.nodes.row(b.cells(c, 0));
    for (int i = 0; i < 8; ++i) v[b.cells(c, i)] += d.prod() / 8.0;
  }
  return PointCloud(b.nodes, v);
}

static int plate(int threads, int argc, char** argv) {
  if (argc < 9) {
    std::fprintf(stderr, "bench_cell_distance THREADS plate NX NY NZ MX MY MZ [REPS [TOL]]\n");
    return 2;
  }
  const HexCells x = plate_cells(std::atoi(argv[3]), std::atoi(argv[4]), std::atoi(argv[5]));
  const HexCells y = plate_cells(std::atoi(argv[6]), std::atoi(argv[7]), std::atoi(argv[8]));
  int reps = argc > 9 ? std::atoi(argv[9]) : 1;
  const double tol = argc > 10 ? std::atof(argv[10]) : 1e-2;
  detail::CellDistanceOptions all, tree, loose;
  all.threads = tree.threads = loose.threads = threads;
  tree.tolerance = loose.tolerance = tol;
  loose.j_near_ratio = argc > 11 ? std::atof(argv[11]) : 2.0;
  loose.j_angle_points = argc > 12 ? std::atoi(argv[12]) : 8;
  HausdorffOptions he, ht, hd;
  he.method = Method::exact;
  he.threads = ht.threads = hd.threads = threads;
  ht.method = hd.method = Method::tree;
  ht.tolerance = tol;  // hd: the default tolerance
  const PointCloud cx = node_cloud(x), cy = node_cloud(y);
  std::printf(
      "# plate: %ld cells (%ld nodes) against %ld cells (%ld nodes), threads %d, J's and "
      "the collocation tree's tolerance %.0e (and the tree's default %.0e)\n",
      (long)x.cells.rows(), (long)x.nodes.rows(), (long)y.cells.rows(), (long)y.nodes.rows(),
      threads, tol, hd.tolerance);
  if (reps < 0) {  // the last configuration alone (profiles)
    for (int rep = 0; rep < -reps; ++rep) {
      const double t0 = now();
      const detail::CellRho r = detail::cell_rho(x, y, loose);
      std::printf("rep %d: cells, J tree, near_ratio %.1f, angle_points %d: rho %.17g %.3f s\n",
                  rep, loose.j_near_ratio, loose.j_angle_points, r.rho, now() - t0);
    }
    return 0;
  }
  for (int rep = 0; rep < reps; ++rep) {
    const double t0 = now();
    const detail::CellRho r0 = detail::cell_rho(x, y, all);
    const double t1 = now();
    const detail::CellRho r1 = detail::cell_rho(x, y, tree);
    const double t2 = now();
    const detail::CellRho r2 = detail::cell_rho(x, y, loose);
    const double t2b = now();
    const double re = hausdorff(cx, cy, he).rho;
    const double t3 = now();
    const double rt = hausdorff(cx, cy, ht).rho;
    const double t4 = now();
    const double rd = hausdorff(cx, cy, hd).rho;
    const double t5 = now();
    std::printf(
        "rep %d: cells, J all pairs: rho %.9f %.3f s; J tree: %+.1e %.3f s; J tree, near_ratio "
        "%.1f, angle_points %d: %+.1e %.3f s (near points %ld) | collocation: exact %.6f %.3f s, "
        "tree %.6f %.3f s, tree default %.6f %.3f s\n",
        rep, r0.rho, t1 - t0, r1.rho / r0.rho - 1.0, t2 - t1, loose.j_near_ratio,
        loose.j_angle_points, r2.rho / r0.rho - 1.0, t2b - t2, r1.a.near_points + r1.b.near_points,
        re, t3 - t2b, rt, t4 - t3, rd, t5 - t4);
    std::fflush(stdout);
  }
  return 0;
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

// The plate bent into a half-turn (radius 10/π about the axis X₂, the fibre side outside):
// (x, y, z) → ((R − z) sin(x/R), y, R − (R − z) cos(x/R)).
static HexCells arc_cells(int nx, int ny, int nz) {
  HexCells b = plate_cells(nx, ny, nz);
  const double r = 10.0 / 3.14159265358979323846;
  for (Eigen::Index i = 0; i < b.nodes.rows(); ++i) {
    const double x = b.nodes(i, 0), z = b.nodes(i, 2);
    b.nodes(i, 0) = (r - z) * std::sin(x / r);
    b.nodes(i, 2) = r - (r - z) * std::cos(x / r);
  }
  return b;
}

// One option of the outer rule by name (the rules mode's configurations).
static void set_option(detail::CellDistanceOptions* o, const std::string& key, double v) {
  if (key == "tp")
    o->tangential_points = static_cast<int>(v);
  else if (key == "d0")
    o->first_panel = v;
  else if (key == "q")
    o->grading = v;
  else if (key == "pp")
    o->panel_points = static_cast<int>(v);
  else if (key == "near")
    o->near_factor = v;
  else if (key == "t0")
    o->tangential_first_panel = v;
  else if (key == "tpp")
    o->tangential_panel_points = static_cast<int>(v);
  else if (key == "tol")
    o->tolerance = v;
  else if (key == "nr")
    o->j_near_ratio = v;
  else if (key == "ap")
    o->j_angle_points = static_cast<int>(v);
  else if (key == "ns")
    o->node_samples = v != 0.0;
  else if (key == "cf")
    o->corner_factor = v;
  else {
    std::fprintf(stderr, "rules: unknown key %s\n", key.c_str());
    std::exit(2);
  }
}

// bench_cell_distance THREADS rules CONFIG...: each CONFIG "key=v,key=v" (keys: tp d0 q pp near t0
// tpp tol nr ap ns cf; "-" the defaults), interleaved per case: ρ̃, its error against the continuum
// (cubes, the flat plate) or its difference from the first configuration (the arcs), seconds
// and near points.
static int rules(int threads, int argc, char** argv) {
  std::vector<detail::CellDistanceOptions> configs;
  for (int a = 3; a < argc; ++a) {
    detail::CellDistanceOptions o;
    o.threads = threads;
    std::string s = argv[a];
    for (std::size_t start = 0; s != "-" && start < s.size();) {
      std::size_t comma = s.find(',', start);
      if (comma == std::string::npos) comma = s.size();
      const std::string kv = s.substr(start, comma - start);
      const std::size_t eq = kv.find('=');
      set_option(&o, kv.substr(0, eq), std::atof(kv.substr(eq + 1).c_str()));
      start = comma + 1;
    }
    o.validate();
    configs.push_back(o);
  }
  struct Body {
    const char* name;
    HexCells x, y;
    double ref;  // 0: against the first configuration
  };
  const std::vector<Body> bodies = {
      {"cube self 8x8", detail::hex_cube({0, 0, 0}, 1, 8), detail::hex_cube({0, 0, 0}, 1, 8),
       0.124155377},
      {"cube self 6x8", detail::hex_cube({0, 0, 0}, 1, 6), detail::hex_cube({0, 0, 0}, 1, 8),
       0.124155377},
      {"cube shift 0.01 8x8", detail::hex_cube({0, 0, 0}, 1, 8),
       detail::hex_cube({0.01, 0, 0}, 1, 8), 0.126529335},
      {"cube side 0.875 8x8", detail::hex_cube({0, 0, 0}, 1, 8),
       detail::hex_cube({0.0625, 0.0625, 0.0625}, 0.875, 8), 0.201406692},
      {"plate 100x10x4 self", plate_cells(100, 10, 4), plate_cells(100, 10, 4), 0.149702598},
      {"plate 50x5x2 x 100x10x4", plate_cells(50, 5, 2), plate_cells(100, 10, 4), 0.149702598},
      {"arc 50x5x2 x 100x10x4", arc_cells(50, 5, 2), arc_cells(100, 10, 4), 0.0},
      {"arc 100x10x4 x 76x8x3", arc_cells(100, 10, 4), arc_cells(76, 8, 3), 0.0}};
  std::printf(
      "# threads %d; per case, configuration: rho, error (or difference from #0), s, near points\n",
      threads);
  for (const Body& b : bodies) {
    double first = 0.0;
    for (std::size_t k = 0; k < configs.size(); ++k) {
      const double t0 = now();
      const detail::CellRho r = detail::cell_rho(b.x, b.y, configs[k]);
      const double t = now() - t0;
      if (k == 0) first = r.rho;
      const double ref = b.ref > 0 ? b.ref : first;
      std::printf("%-26s #%zu %-28s %.17g %+9.4f%% %8.3f s %9ld\n", b.name, k, argv[3 + k], r.rho,
                  100.0 * (r.rho / ref - 1.0), t, r.a.near_points + r.b.near_points);
      std::fflush(stdout);
    }
  }
  return 0;
}

int main(int argc, char** argv) {
  const int threads = argc > 1 ? std::atoi(argv[1]) : 1;
  if (argc > 2 && std::string(argv[2]) == "plate") return plate(threads, argc, argv);
  if (argc > 2 && std::string(argv[2]) == "rules") return rules(threads, argc, argv);
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
