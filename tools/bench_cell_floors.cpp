// The floors of a scene with a known map under the cell-integrated ρ̃ (docs/formulation.md §2.8):
// the matched floor (the body deformed by the known map against the target's cells) and the self
// floor (the target's cells against themselves), two values of the same continuum quantity when
// the target has cells (an arc, or a solved_on target).
//
//   bench_cell_floors SCENE [THREADS [TOL]]
//
// TOL > 0: J by the tree at τ = TOL with near_ratio 2 and 8 angle points (as the objective's
// loop); default 0: all pairs at the accurate rules.
// Prints the cell counts, both floors and the seconds of each.

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "fe/hex_decomposition.hpp"
#include "hausdorff/cell_distance.hpp"
#include "softhd/control/scene.hpp"
#include "softhd/control/scene_target.hpp"
#include "softhd/error.hpp"

using namespace softhd;

namespace {

double now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// A 3D mesh at node positions `x` (N by 3) as trilinear hexahedra.
detail::HexCells hex_cells(const fe::Mesh& mesh, const Eigen::MatrixXd& x) {
  const fe::HexDecomposition d = fe::hex_decomposition(mesh);
  return {d.map * x, d.cells};
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || argc > 4) {
    std::fprintf(stderr, "usage: bench_cell_floors SCENE [THREADS [TOL]]\n");
    return 2;
  }
  std::setvbuf(stdout, nullptr, _IOLBF, 0);  // each line as it is printed (long runs)
  try {
    const Scene scene = load_scene(argv[1]);
    const fe::Mesh mesh = scene.body.make_mesh();
    const SceneTarget target = scene_target(scene, mesh);
    if (!target.map_displacement || !target.cells || mesh.dim != 3) {
      std::fprintf(stderr, "%s: needs a 3D scene whose target has a known map and cells\n",
                   argv[1]);
      return 2;
    }
    detail::CellDistanceOptions options;
    options.threads = argc > 2 ? std::atoi(argv[2]) : 0;
    options.tolerance = argc > 3 ? std::atof(argv[3]) : 0.0;
    if (options.tolerance > 0) options.j_near_ratio = 2.0, options.j_angle_points = 8;
    // The body deformed by the known map: X + u_T (u_T node-major).
    const Eigen::MatrixXd u =
        Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>>(
            target.map_displacement->data(), mesh.num_nodes(), 3);
    const detail::HexCells body = hex_cells(mesh, mesh.nodes + u);
    const detail::HexCells cells = hex_cells(*target.cells, target.cells->nodes);
    std::printf("scene %s: body %ld hexahedra, target %ld hexahedra (%s)\n", argv[1],
                static_cast<long>(body.cells.rows()), static_cast<long>(cells.cells.rows()),
                target.description.c_str());
    double t0 = now();
    const detail::CellRho matched = detail::cell_rho(body, cells, options);
    const double t_matched = now() - t0;
    t0 = now();
    const detail::CellRho self = detail::cell_rho(cells, cells, options);
    const double t_self = now() - t0;
    std::printf("matched floor %.6f (%.1f s), self floor %.6f (%.1f s), ratio %.4f\n", matched.rho,
                t_matched, self.rho, t_self, matched.rho / self.rho);
  } catch (const Error& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 2;
  }
  return 0;
}
