// bench_resolution (issue 6): the bending scene against targets of differing resolution
// and regularity, and the state mesh at three refinements against one fixed target.
// Every target is the analytic arc (docs/formulation.md §5.2), so each run reports the true shape
// error.
//
//   bench_resolution [--quick] [--csv FILE] [--max-iter N] [--max-seconds S]
//
// Studies (h = the FE node spacing along each axis, L/(2·cells) for Q2):
//   grid  cell-centred arc grids with spacing h_d = f·h, f ∈ {4, 2, 1, 1/2, 1/4}
//   scan  n random points (uniform; 5:1 non-uniform density), the h/2 grid with Gaussian
//         noise σ = thickness/10 on the deformed points, the surface only (a grid of
//         spacing h_X1/2; and a non-uniform, noisy random scan of it)
//   mesh  the state mesh with cells × {1/2, 1, 2} (X3 cells: 1, 2, 2) against the fixed
//         target of the base mesh (the h/2 grid); the base mesh's row is the grid study's
//         h/2 run (the same body, target and settings), not run twice
// --quick: a 10×2×1 mesh, 4 iterations, small scans (the smoke test of the suite).

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "tracking_bench.hpp"

using namespace softhd;
using namespace softhd::bench;

namespace {

Eigen::Vector3i grid_counts(const Eigen::Vector3i& cells, double f) {
  // Node intervals per axis are 2·cells (Q2); spacing f·h means 2·cells/f cells.
  Eigen::Vector3i c;
  for (int k = 0; k < 3; ++k) c[k] = std::max(1, static_cast<int>(std::lround(2 * cells[k] / f)));
  return c;
}

std::string cells_label(const Eigen::Vector3i& c) {
  return std::to_string(c[0]) + "x" + std::to_string(c[1]) + "x" + std::to_string(c[2]);
}

}  // namespace

int main(int argc, char** argv) {
  if (has_flag(argc, argv, "--help")) {
    std::printf(
        "usage: bench_resolution [--quick] [--csv FILE] [--max-iter N] [--max-seconds S]\n"
        "Bending scene: targets of spacing f*h (f = 4..1/4) and scan-like clouds, and three\n"
        "state-mesh refinements against one target; final rho/floor and true shape error.\n");
    return 0;
  }
  const bool quick = has_flag(argc, argv, "--quick");
  const std::string csv = option(argc, argv, "--csv", "bench_resolution.csv");
  RunSettings settings;
  settings.run.optimiser.max_iterations =
      std::stoi(option(argc, argv, "--max-iter", quick ? "4" : "40"));
  settings.run.optimiser.max_seconds = std::stod(option(argc, argv, "--max-seconds", "0"));

  const softhd::Scene scene = scene_file("bending");
  // The Q2 25×3×1 mesh (1 071 nodes): 40 iterations of the 50×5×2 mesh cost 5× more, and the
  // studies are stated relative to h, so the coarser body keeps them within make bench's hour.
  const Eigen::Vector3i cells = quick ? Eigen::Vector3i(10, 2, 1) : Eigen::Vector3i(25, 3, 1);
  const int scan_n = quick ? 600 : 16000;
  const ArcMap T = arc_of(scene);
  const double thickness = scene.body.upper[2] - scene.body.lower[2];
  std::vector<Run> runs;
  auto record = [&](Run r) {
    runs.push_back(std::move(r));
    write_csv(csv, runs);  // after every run: nothing is lost if the benchmark is stopped
  };

  Body body = make_body(scene, cells);
  const Eigen::VectorXd map = arc_displacement(T, body.mesh());
  std::fprintf(stderr, "bench_resolution: bending, Q2 %s mesh, %ld nodes\n",
               cells_label(cells).c_str(), static_cast<long>(body.mesh().num_nodes()));

  size_t half_run = 0;  // the h/2 grid's run, reused by the mesh study
  for (double f : {4.0, 2.0, 1.0, 0.5, 0.25}) {
    const Eigen::Vector3i c = grid_counts(cells, f);
    if (f == 0.5) half_run = runs.size();
    record(run_tracking({{"study", "grid"},
                         {"variant", "grid " + cells_label(c)},
                         {"mesh", cells_label(cells)},
                         {"spacing_over_h", fmt(f)}},
                        body, arc_grid(scene, T, c), map, settings));
  }
  const Eigen::Vector3i half = grid_counts(cells, 0.5);
  const double h1 = (scene.body.upper[0] - scene.body.lower[0]) / (2 * cells[0]);
  const std::vector<std::pair<std::string, PointCloud>> scans = {
      {"random", arc_random(scene, T, scan_n, 11)},
      {"nonuniform 5:1", arc_nonuniform(scene, T, scan_n, 12)},
      {"jittered h/2 grid", jittered(arc_grid(scene, T, half), thickness / 10, 13)},
      {"surface grid", arc_surface(scene, T, h1 / 2)},
      {"surface scan", jittered(arc_surface(scene, T, 0, scan_n, 14), thickness / 10, 15)},
  };
  for (const auto& [name, cloud] : scans)
    record(run_tracking({{"study", "scan"},
                         {"variant", name},
                         {"mesh", cells_label(cells)},
                         {"spacing_over_h", ""}},
                        body, cloud, map, settings));

  // The state mesh at three refinements against the base mesh's h/2 grid.
  const PointCloud fixed = arc_grid(scene, T, half);
  const std::vector<Eigen::Vector3i> meshes = {
      Eigen::Vector3i(cells[0] / 2, (cells[1] + 1) / 2, 1), cells,
      Eigen::Vector3i(2 * cells[0], 2 * cells[1], cells[2])};
  for (const Eigen::Vector3i& mc : meshes) {
    const std::vector<std::pair<std::string, std::string>> params = {
        {"study", "mesh"},
        {"variant", "target grid " + cells_label(half)},
        {"mesh", cells_label(mc)},
        {"spacing_over_h", ""}};
    if (mc == cells) {  // the same body, target and settings as the grid study's h/2 run
      Run same = runs[half_run];
      same.params = params;
      record(std::move(same));
      continue;
    }
    Body b = make_body(scene, mc);
    record(run_tracking(params, b, fixed, arc_displacement(T, b.mesh()), settings));
  }
  std::fprintf(stderr, "wrote %s\n", csv.c_str());
  for (const Run& r : runs)
    if (!r.error.empty() || !r.finite()) return 1;
  return 0;
}
