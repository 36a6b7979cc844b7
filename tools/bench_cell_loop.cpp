// The cell-integrated ρ̃ of the bending loop alone, for profiles (docs/formulation.md §2.8, "The
// cost in the bending loop"): data/scenes/bending.json at the bent control m = −2.6e4 X₃/0.1 (the
// state solved once), the body's 4 000 hexahedra against the arc target's cells, the cell form
// at the loop's options (the tree at τ = 1e-2, J's near ratio 2 and 8 angle points):
//
//   bench_cell_loop THREADS NX NY NZ [REPS [value|gradient|both [STATE [CORNER]]]]
//
// the target's grid NX × NY × NZ (the scene's: 200 20 8; the body's resolution: 100 10 4);
// per repeat the seconds of the value and of the value with its gradient, ρ̃, A⁴ and B⁴ to 17
// digits and the near cells and points of both directed means. The state solve is not timed;
// STATE: a file the displacement is read from if it exists, else written to after the solve
// (profiles of the distance alone); CORNER: CellDistanceOptions::corner_factor (default its
// default).
#include <Eigen/Core>
#include <chrono>
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "control/cell_form.hpp"
#include "softhd/control/scene.hpp"
#include "softhd/control/scene_target.hpp"
#include "softhd/control/shape_objective.hpp"
#include "softhd/error.hpp"

using namespace softhd;

namespace {

double now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

void report(const char* what, double seconds, const detail::CellRho& r) {
  std::printf(
      "%-9s %8.3f s  rho %.17g  A4 %.17g  B4 %.17g  near %ld + %ld cells, %ld + %ld points, "
      "corner %ld + %ld cells\n",
      what, seconds, r.rho, r.a.mean, r.b.mean, r.a.near_cells, r.b.near_cells, r.a.near_points,
      r.b.near_points, r.a.corner_cells, r.b.corner_cells);
  std::fflush(stdout);
}

int run(int argc, char** argv) {
  if (argc < 5) {
    std::fprintf(stderr, "usage: bench_cell_loop THREADS NX NY NZ [REPS [value|gradient|both]]\n");
    return 2;
  }
  const int threads = std::stoi(argv[1]);
  const int reps = argc > 5 ? std::stoi(argv[5]) : 1;
  const std::string what = argc > 6 ? argv[6] : "both";
  if (what != "value" && what != "gradient" && what != "both")
    throw InvalidArgument("the last argument: value, gradient or both");
  Scene scene = load_scene(std::string(SOFTHD_SOURCE_DIR) + "/data/scenes/bending.json");
  nlohmann::json t = nlohmann::json::parse(scene.target_json);
  t["cells"] = {std::stoi(argv[2]), std::stoi(argv[3]), std::stoi(argv[4])};
  scene.target_json = t.dump();
  fe::Assembler assembler = scene.body.make_assembler();
  const fe::ControlSpace space(assembler.mesh(), assembler.geometry(), scene.body.control_kind);
  const SceneTarget target = scene_target(scene, assembler.mesh());
  if (!target.cells) throw InternalError("bench_cell_loop: the bending target has no cells");
  ShapeObjectiveOptions o;
  o.hausdorff.method = Method::tree;
  o.hausdorff.tolerance = 1e-2;
  o.hausdorff.threads = threads;
  const std::string state = argc > 7 ? argv[7] : "";
  Eigen::VectorXd u(3 * assembler.mesh().num_nodes());
  std::FILE* in = state.empty() ? nullptr : std::fopen(state.c_str(), "rb");
  if (in) {
    const std::size_t got = std::fread(u.data(), sizeof(double), u.size(), in);
    std::fclose(in);
    if (got != static_cast<std::size_t>(u.size()))
      throw FileError("bench_cell_loop: short " + state);
  } else {
    ShapeObjective colloc(assembler, space, HausdorffTarget(target.cloud, o.hausdorff), o);
    const Eigen::MatrixXd p = space.positions(assembler.mesh());
    const Eigen::VectorXd m = -2.6e4 * p.col(2) / 0.1;
    if (colloc.evaluate(m, false).status != EvaluationStatus::ok)
      throw NumericalError("bench_cell_loop: the state solve failed");
    u = colloc.state_path().last_state().u;
    if (!state.empty()) {
      std::FILE* out = std::fopen(state.c_str(), "wb");
      if (!out) throw FileError("bench_cell_loop: cannot write " + state);
      std::fwrite(u.data(), sizeof(double), u.size(), out);
      std::fclose(out);
    }
  }
  detail::CellDistanceOptions co;  // the objective's (shape_objective.cpp, cell_options)
  co.threads = threads;
  co.tolerance = 1e-2;
  co.j_near_ratio = 2.0, co.j_angle_points = 8;
  if (argc > 8) co.corner_factor = std::stod(argv[8]);
  const detail::CellForm form(assembler.mesh(), *target.cells, co);
  for (int r = 0; r < reps; ++r) {
    if (what != "gradient") {
      const double t0 = now();
      const detail::CellRho v = form.evaluate(u);
      report("value", now() - t0, v);
    }
    if (what != "value") {
      Eigen::VectorXd g;
      const double t0 = now();
      const detail::CellRho v = form.evaluate(u, &g);
      report("gradient", now() - t0, v);
      std::printf("          |grad| %.17g\n", g.norm());
    }
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const InvalidArgument& e) {
    std::fprintf(stderr, "bench_cell_loop: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_cell_loop: %s\n", e.what());
    return 1;
  }
}
