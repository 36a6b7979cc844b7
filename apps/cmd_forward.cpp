// softhd forward: solve the hyperelastic state of a scene for a given control.

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "commands.hpp"
#include "failure.hpp"
#include "softhd/control/scene.hpp"
#include "softhd/control/targets.hpp"
#include "softhd/error.hpp"
#include "softhd/fe/cloud.hpp"
#include "softhd/fe/forward.hpp"
#include "softhd/fe/grid_sequencing.hpp"
#include "softhd/fe/locator.hpp"
#include "softhd/fe/newton.hpp"
#include "softhd/fe/output.hpp"
#include "softhd/fe/state_backend.hpp"
#include "softhd/fe/state_equation.hpp"
#include "softhd/io/cloud_io.hpp"
#include "softhd/parallel.hpp"
#include "softhd/work_share.hpp"

namespace {

using namespace softhd::fe;
using softhd::load_scene;
using softhd::Scene;

constexpr const char* kUsage =
    "usage: softhd forward SCENE [--control FILE | --control-uniform V] [--probe X1,X2[,X3]]...\n"
    "                      [--out DIR] [--write-cloud FILE] [--json] [--linear-solver NAME]\n"
    "                      [--coarse-levels K] [--step-tol T] [--load-increment F]\n"
    "                      [--intermediate-tol T] [--factorize-every-step]\n"
    "                      [--threads N] [--verbose] [--state-backend NAME]\n"
    "       softhd forward SCENE --write-control-nodes FILE [--control-uniform V]\n"
    "\n"
    "Solves the equilibrium of the scene's body for the active tension m and writes\n"
    "DIR/forward.vtu (deformed mesh with displacement, m and J; default DIR: out).\n"
    "  --control FILE         rows 'X1 X2 [X3] m', one per control node (vertex or element\n"
    "                         centre), matched by coordinates\n"
    "  --control-uniform V    m = V everywhere (default: the scene's control.initial)\n"
    "  --probe X1,X2[,X3]     report u at this reference point (FE interpolation); repeatable\n"
    "  --write-cloud FILE     also write the deformed nodes with their deformed volumes\n"
    "                         V_i = int N_i J dX as a point cloud (.ply binary, else text), in\n"
    "                         node order: a target for softhd optimise\n"
    "  --coarse-levels K      grid sequencing: first solve on coarser levels (K, coarsest\n"
    "                         first) and start each finer Newton solve from the coarser state\n"
    "                         interpolated onto its nodes; 0 starts from rest. A box halves\n"
    "                         its cells along every even axis per level; a mesh file of order\n"
    "                         2 has one level, P1/Q1 on its vertices (p-sequencing). Default\n"
    "                         auto: halve while an axis is even and the coarse mesh keeps >= 32\n"
    "                         elements, a file mesh of order 2 its P1/Q1 level; a coarse solve\n"
    "                         that fails makes the start the rest state\n"
    "  --json                 print a JSON summary (probes, energy, volume, iterations, ...)\n"
    "  --linear-solver NAME   eigen-llt, eigen-ldlt or cholmod (default cholmod)\n"
    "  --step-tol T           converged also needs the last Newton correction\n"
    "                         |du|_inf <= T |u|_inf (default 1e-10; 0: residual test only)\n"
    "  --load-increment F     first load step, a fraction of m (default 1; doubled after\n"
    "                         quick steps, halved after failed ones)\n"
    "  --intermediate-tol T   relative residual accepting a load step before the last\n"
    "                         (default 1e-9, as the last one)\n"
    "  --factorize-every-step classical Newton: factorise every tangent instead of\n"
    "                         reusing a factorisation as a PCG preconditioner\n"
    "  --threads N            threads of the assembly (default 0: OMP_NUM_THREADS or all cores)\n"
    "  --max-memory GIB       refuse meshes whose estimated memory exceeds this (default 8;\n"
    "                         with a PETSc backend, per rank)\n"
    "  --state-backend NAME   cholmod (serial Newton, default), petsc-mumps (distributed Newton,\n"
    "                         MUMPS LDL^T) or petsc-gamg (distributed Newton, CG + GAMG); the\n"
    "                         PETSc ones need a build with SOFTHD_WITH_MPI=ON and run on the\n"
    "                         ranks of mpiexec (or serially; coarse levels are solved serially\n"
    "                         on every rank) and take no --write-cloud, --linear-solver or\n"
    "                         --factorize-every-step. PETSc options (e.g.\n"
    "                         -softhd_state_ksp_monitor) go in the environment variable\n"
    "                         PETSC_OPTIONS\n"
    "  --write-control-nodes FILE  write the control nodes with their current values and stop\n"
    "\n"
    "exit status: 0 done; 1 numerical failure (the state solve did not converge); 2 bad\n"
    "input or refused (one line on stderr names the file, key or flag).\n";

struct Args {
  std::string scene, control_file, out_dir = "out", write_nodes, linear_solver, write_cloud;
  StateBackend backend = StateBackend::kCholmod;
  bool has_uniform = false, json = false, verbose = false;
  int coarse_levels = -1;  // automatic
  int threads = 0;
  double step_tol = 1e-10;
  double load_increment = 1.0;
  double intermediate_tol = 1e-9;
  bool factorize_every_step = false;
  double uniform = 0.0;
  double memory_limit = softhd::fe::kDefaultMemoryLimit;
  std::vector<Eigen::VectorXd> probes;
};

double parse_number(const std::string& text, const std::string& option) {
  try {
    size_t used = 0;
    const double v = std::stod(text, &used);
    if (used == text.size()) return v;
  } catch (const std::exception&) {
  }
  throw softhd::InvalidArgument(option + " expects a number, got '" + text + "'");
}

Eigen::VectorXd parse_point(const std::string& text) {
  std::vector<double> v;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) v.push_back(parse_number(item, "--probe"));
  if (v.size() < 2 || v.size() > 3)
    throw softhd::InvalidArgument("--probe expects X1,X2 or X1,X2,X3, got '" + text + "'");
  return Eigen::Map<Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size()));
}

// Returns false if --help was asked for.
bool parse(int argc, char** argv, Args* a) {
  for (int i = 1; i < argc; ++i) {
    const std::string s = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw softhd::InvalidArgument(s + " needs a value");
      return argv[++i];
    };
    if (s == "--help" || s == "-h") return false;
    if (s == "--control") {
      a->control_file = value();
    } else if (s == "--control-uniform") {
      a->uniform = parse_number(value(), s);
      a->has_uniform = true;
    } else if (s == "--probe") {
      a->probes.push_back(parse_point(value()));
    } else if (s == "--out") {
      a->out_dir = value();
    } else if (s == "--json") {
      a->json = true;
    } else if (s == "--verbose") {
      a->verbose = true;
    } else if (s == "--state-backend") {
      a->backend = parse_state_backend(value());
      if (a->backend != StateBackend::kCholmod && !petsc_backend_available())
        throw softhd::InvalidArgument("--state-backend " + to_string(a->backend) +
                                      " needs softhd built with -DSOFTHD_WITH_MPI=ON");
    } else if (s == "--linear-solver") {
      a->linear_solver = value();
      try {
        parse_linear_solver(a->linear_solver);
      } catch (const softhd::InvalidArgument& e) {
        throw softhd::InvalidArgument("--linear-solver: " + std::string(e.what()));
      }
    } else if (s == "--step-tol") {
      a->step_tol = parse_number(value(), s);
      if (!(a->step_tol >= 0.0 && a->step_tol < 1.0))
        throw softhd::InvalidArgument("--step-tol must be in [0, 1)");
    } else if (s == "--load-increment") {
      a->load_increment = parse_number(value(), s);
      if (!(a->load_increment > 0.0 && a->load_increment <= 1.0))
        throw softhd::InvalidArgument("--load-increment must be in (0, 1]");
    } else if (s == "--intermediate-tol") {
      a->intermediate_tol = parse_number(value(), s);
      if (!(a->intermediate_tol > 0.0 && a->intermediate_tol < 1.0))
        throw softhd::InvalidArgument("--intermediate-tol must be in (0, 1)");
    } else if (s == "--factorize-every-step") {
      a->factorize_every_step = true;
    } else if (s == "--threads") {
      const double t = parse_number(value(), s);
      if (!(t >= 0 && t <= softhd::kMaxThreads && t == static_cast<int>(t)))
        throw softhd::InvalidArgument("--threads expects an integer from 0 to " +
                                      std::to_string(softhd::kMaxThreads));
      a->threads = static_cast<int>(t);
    } else if (s == "--coarse-levels") {
      const std::string v = value();
      // -1 is the internal code for auto, not a value a user may give.
      const double k = v == "auto" ? -1.0 : parse_number(v, s);
      if (!(v == "auto" || (k >= 0 && k <= 8 && k == static_cast<int>(k))))
        throw softhd::InvalidArgument("--coarse-levels expects auto or an integer from 0 to 8");
      a->coarse_levels = static_cast<int>(k);
    } else if (s == "--max-memory") {
      const double g = parse_number(value(), s);
      if (!(g > 0.0 && g <= 1e6))
        throw softhd::InvalidArgument("--max-memory expects GiB in (0, 1e6]");
      a->memory_limit = g * (1u << 30);
    } else if (s == "--write-cloud") {
      a->write_cloud = value();
    } else if (s == "--write-control-nodes") {
      a->write_nodes = value();
    } else if (!s.empty() && s[0] == '-') {
      throw softhd::InvalidArgument("unknown option " + s + " (see softhd forward --help)");
    } else if (a->scene.empty()) {
      a->scene = s;
    } else {
      throw softhd::InvalidArgument("unexpected argument '" + s + "'");
    }
  }
  if (a->scene.empty()) throw softhd::InvalidArgument("no scene file given (see --help)");
  if (!a->control_file.empty() && a->has_uniform)
    throw softhd::InvalidArgument("--control and --control-uniform exclude each other");
  return true;
}

/// The control values (one per control position) from the arguments (file rows matched by
/// coordinates), checked against the scene's bounds.
Eigen::VectorXd control_values(const Scene& scene, const Mesh& mesh,
                               const Eigen::MatrixXd& positions, const Args& args) {
  if (!args.control_file.empty()) return read_control_file(args.control_file, positions);
  return softhd::fe::constant_control(mesh, scene.body.control_kind, scene.body.control_regions,
                                      args.has_uniform ? args.uniform : scene.body.control_initial);
}

// The JSON record of each coarse level of a grid-sequenced start.
nlohmann::json coarse_levels_json(const GridSequencingReport& grid) {
  nlohmann::json levels = nlohmann::json::array();
  for (const GridLevelReport& level : grid.levels) {
    levels.push_back(
        {{"cells", std::vector<int>(level.cells.data(), level.cells.data() + level.cells.size())},
         {"mesh", level.mesh},
         {"cell", to_string(level.cell)},
         {"nodes", level.nodes},
         {"newton_iterations", level.newton.newton_iterations},
         {"factorizations", level.newton.factorizations},
         {"seconds", level.newton.seconds_total}});
  }
  return levels;
}

/// The state solver's settings from the arguments.
StateSolverOptions solver_options(const Args& args) {
  if (args.backend != StateBackend::kCholmod &&
      (!args.linear_solver.empty() || args.factorize_every_step))
    throw softhd::InvalidArgument(
        "--linear-solver and --factorize-every-step need --state-backend cholmod");
  StateSolverOptions so;
  so.backend = args.backend;
  NewtonOptions& options = so.newton;
  options.verbose = args.verbose;
  options.displacement_tolerance = args.step_tol;
  options.initial_load_increment = args.load_increment;
  options.min_load_increment = std::min(options.min_load_increment, args.load_increment);
  options.intermediate_tolerance = args.intermediate_tol;
  options.tangent.reuse_factorization = !args.factorize_every_step;
  if (!args.linear_solver.empty())
    options.tangent.linear_solver = parse_linear_solver(args.linear_solver);
  return so;
}

/// What a forward solve leaves for the output (whole mesh, on every rank).
struct Solved {
  GridSequencingReport grid;
  NewtonSummary summary;
  State state;
  Eigen::MatrixXd J;
  double energy = 0.0, volume = 0.0, seconds_solve = 0.0;
  Eigen::Index dofs = 0;
};

Solved solve(const Scene& scene, const Eigen::VectorXd& m, const Args& args) {
  const std::unique_ptr<StateEquation> solver = make_state_solver(scene.body, solver_options(args));
  GridSequencingOptions grid_options;
  grid_options.levels = args.coarse_levels;
  Solved r;
  r.grid = solver->grid_sequenced_start(scene.body, m, grid_options);
  if (softhd::world_rank() == 0) std::cerr << r.grid.BriefReport();
  r.summary = solver->solve(m);
  r.seconds_solve = r.summary.seconds_total;
  for (const GridLevelReport& level : r.grid.levels) r.seconds_solve += level.newton.seconds_total;
  r.state = solver->state();
  r.J = solver->jacobians();
  r.energy = solver->energy();
  r.volume = solver->deformed_volume();
  r.dofs = solver->free_dofs();
  return r;
}

void print_json(const Scene& scene, const Args& args, const Mesh& mesh, const Solved& r,
                const std::string& vtu, double seconds) {
  const NewtonSummary& summary = r.summary;
  nlohmann::json j;
  j["scene"] = scene.name;
  j["state_backend"] = to_string(args.backend);
  j["ranks"] = softhd::world_size();
  j["status"] = to_string(summary.status);
  j["converged"] = summary.converged();
  j["load_reached"] = summary.final_load;
  nlohmann::json probes = nlohmann::json::array();
  for (const Eigen::VectorXd& X : args.probes) {
    const Eigen::VectorXd u = probe_displacement(mesh, r.state.u, X);
    probes.push_back({{"X", std::vector<double>(X.data(), X.data() + X.size())},
                      {"u", std::vector<double>(u.data(), u.data() + u.size())}});
  }
  j["probes"] = probes;
  j["energy"] = r.energy;
  j["volume"] = r.volume;
  j["min_J"] = r.J.minCoeff();
  j["quadrature_points_per_element"] = r.J.cols();
  j["newton_iterations"] = summary.newton_iterations;
  j["factorizations"] = summary.factorizations;
  j["krylov_iterations"] = summary.krylov_iterations;
  j["load_steps"] = summary.load_steps;
  j["dofs"] = r.dofs;
  // Solve time: the coarse levels' Newton solves and the fine one (no file I/O).
  j["coarse_levels"] = coarse_levels_json(r.grid);
  j["seconds_solve"] = r.seconds_solve;
  j["seconds"] = seconds;
  j["vtu"] = vtu;
  std::cout << j.dump(2) << "\n";
}

// Every rank reads the scene and solves (with a PETSc backend, its slab); rank 0 writes the
// files and prints.
int forward(const Args& args) {
  const auto t0 = std::chrono::steady_clock::now();
  const bool writer = softhd::world_rank() == 0;
  // The memory limit is per rank: a PETSc backend holds 1/K of the state on each.
  const double ranks = args.backend == StateBackend::kCholmod ? 1 : softhd::world_size();
  const Scene scene = load_scene(args.scene, args.memory_limit * ranks);
  const Mesh mesh = scene.body.make_mesh();
  const Eigen::MatrixXd positions = control_positions(mesh, scene.body.control_kind);
  const Eigen::VectorXd m = control_values(scene, mesh, positions, args);
  if (!args.write_nodes.empty()) {
    if (writer) write_control_file(args.write_nodes, positions, m);
    return 0;
  }
  softhd::fe::check_control_bounds(scene.body, mesh, m);
  const softhd::fe::PointLocator locator(mesh);
  for (const Eigen::VectorXd& X : args.probes) {
    Eigen::VectorXd xi;
    if (X.size() != scene.body.dim() || locator.locate(X, &xi) < 0) {
      std::ostringstream os;
      os << "probe (" << X.transpose() << ") is not a point of the " << scene.body.dim()
         << "D body";
      throw softhd::InvalidArgument(os.str());
    }
  }
  softhd::set_threads(args.threads);
  const Solved r = solve(scene, m, args);
  const NewtonSummary& summary = r.summary;
  if (!writer) return summary.converged() ? 0 : 1;
  std::filesystem::create_directories(args.out_dir);
  const std::string vtu = (std::filesystem::path(args.out_dir) / "forward.vtu").string();
  write_vtu(vtu, mesh, r.state.u, r.state.m_qp, r.J);
  const bool cloud = !args.write_cloud.empty() && summary.converged();
  if (cloud) {  // the deformed volumes need the whole mesh's quadrature: one assembler here
    softhd::write_cloud(args.write_cloud,
                        deformed_cloud(scene.body.make_assembler(), r.state.u, CloudPoints::kNodes,
                                       CloudVolumes::kDeformed));
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (args.json) {
    print_json(scene, args, mesh, r, vtu, seconds);
  } else {
    std::cout << summary.BriefReport() << "\nwrote " << vtu << "\n";
    if (cloud) std::cout << "wrote " << args.write_cloud << "\n";
    for (const Eigen::VectorXd& X : args.probes) {
      std::cout << "u(" << X.transpose()
                << ") = " << probe_displacement(mesh, r.state.u, X).transpose() << "\n";
    }
  }
  if (!summary.converged()) {
    std::cerr << "softhd forward: the state solve did not converge (the VTU holds the last "
                 "converged load step)\n"
              << summary.FullReport();
    return 1;
  }
  return 0;
}

}  // namespace

int run_forward(int argc, char** argv) {
  Args args;
  try {
    if (!parse(argc, argv, &args)) {
      if (softhd::world_rank() == 0) std::cout << kUsage;
      return 0;
    }
    return forward(args);
  } catch (const softhd::NumericalError& e) {
    return softhd::cli::report_failure("forward", 1, std::string("error: ") + e.what());
  } catch (const softhd::Error& e) {
    return softhd::cli::report_failure("forward", 2, std::string("error: ") + e.what());
  } catch (const std::filesystem::filesystem_error& e) {
    return softhd::cli::report_failure("forward", 2, std::string("error: ") + e.what());
  }
}
