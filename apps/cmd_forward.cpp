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
#include "softhd/control/targets.hpp"
#include "softhd/error.hpp"
#include "softhd/fe/cloud.hpp"
#include "softhd/fe/forward.hpp"
#include "softhd/fe/grid_sequencing.hpp"
#include "softhd/fe/newton.hpp"
#include "softhd/fe/output.hpp"
#include "softhd/fe/scene.hpp"
#include "softhd/fe/state_backend.hpp"
#if defined(SOFTHD_WITH_MPI) && SOFTHD_WITH_MPI
#include <mpi.h>

#include "softhd/fe/petsc_state.hpp"
#endif
#include "softhd/io/cloud_io.hpp"
#include "softhd/parallel.hpp"

namespace {

using namespace softhd::fe;

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
    "  --coarse-levels K      grid sequencing: first solve on the mesh with half the cells\n"
    "                         along every even axis (K times, coarsest first) and start each\n"
    "                         finer Newton solve from the coarser state interpolated onto its\n"
    "                         nodes; 0 starts from rest (default auto: halve while an axis is\n"
    "                         even and the coarse mesh keeps >= 32 elements; a coarse solve\n"
    "                         that fails makes the start the rest state)\n"
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
    "  --write-control-nodes FILE  write the control nodes with their current values and stop\n";

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
      if (!(t >= 0 && t <= 1024 && t == static_cast<int>(t)))
        throw softhd::InvalidArgument("--threads expects an integer from 0 to 1024");
      a->threads = static_cast<int>(t);
    } else if (s == "--coarse-levels") {
      const std::string v = value();
      const double k = v == "auto" ? -1.0 : parse_number(v, s);
      if (!(k >= -1 && k <= 8 && k == static_cast<int>(k)))
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

/// The control values on `control` from the arguments (file rows matched by coordinates).
Eigen::VectorXd control_values(const Scene& scene, const ControlSpace& control, const Mesh& mesh,
                               const Args& args) {
  Eigen::VectorXd m = Eigen::VectorXd::Constant(
      control.size(), args.has_uniform ? args.uniform : scene.control_initial);
  if (!args.control_file.empty()) m = read_control_file(args.control_file, control.positions(mesh));
  return m;
}

int forward_petsc(const Args& args);

// The JSON record of each coarse level of a grid-sequenced start.
nlohmann::json coarse_levels_json(const GridSequencingReport& grid) {
  nlohmann::json levels = nlohmann::json::array();
  for (const GridLevelReport& level : grid.levels) {
    levels.push_back(
        {{"cells", std::vector<int>(level.cells.data(), level.cells.data() + level.cells.size())},
         {"newton_iterations", level.newton.newton_iterations},
         {"factorizations", level.newton.factorizations},
         {"seconds", level.newton.seconds_total}});
  }
  return levels;
}

int forward(const Args& args) {
  if (args.backend != StateBackend::kCholmod) return forward_petsc(args);
  const auto t0 = std::chrono::steady_clock::now();
  const Scene scene = load_scene(args.scene, args.memory_limit);
  const Assembler assembler = scene.make_assembler();
  const ControlSpace control(assembler.mesh(), assembler.geometry(), scene.control_kind);
  const Eigen::MatrixXd positions = control.positions(assembler.mesh());
  const Eigen::VectorXd m = control_values(scene, control, assembler.mesh(), args);
  if (!args.write_nodes.empty()) {
    write_control_file(args.write_nodes, positions, m);
    return 0;
  }
  check_control_bounds(scene, control, assembler.mesh(), m);
  for (const Eigen::VectorXd& X : args.probes) {
    Eigen::VectorXd xi;
    if (X.size() != scene.dim() || locate(assembler.mesh(), X, &xi) < 0) {
      std::ostringstream os;
      os << "probe (" << X.transpose() << ") is not a point of the " << scene.dim() << "D body";
      throw softhd::InvalidArgument(os.str());
    }
  }
  softhd::set_threads(args.threads);
  ForwardOptions fo;
  NewtonOptions& options = fo.newton;
  options.verbose = args.verbose;
  options.displacement_tolerance = args.step_tol;
  options.initial_load_increment = args.load_increment;
  options.min_load_increment = std::min(options.min_load_increment, args.load_increment);
  options.intermediate_tolerance = args.intermediate_tol;
  options.tangent.reuse_factorization = !args.factorize_every_step;
  if (!args.linear_solver.empty())
    options.tangent.linear_solver = parse_linear_solver(args.linear_solver);
  fo.grid.levels = args.coarse_levels;
  const ForwardResult fr = solve_forward(scene, assembler, control, m, fo);
  std::cerr << fr.grid.BriefReport();
  const State& state = fr.state;
  const NewtonSummary& summary = fr.summary;
  const Eigen::MatrixXd J = assembler.jacobians(state.u);
  std::filesystem::create_directories(args.out_dir);
  const std::string vtu = (std::filesystem::path(args.out_dir) / "forward.vtu").string();
  write_vtu(vtu, assembler.mesh(), state.u, state.m_qp, J);
  if (!args.write_cloud.empty() && summary.converged()) {
    const softhd::PointCloud cloud =
        deformed_cloud(assembler, state.u, CloudPoints::kNodes, CloudVolumes::kDeformed);
    softhd::write_cloud(args.write_cloud, cloud);
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (args.json) {
    nlohmann::json j;
    j["scene"] = scene.name;
    j["status"] = to_string(summary.status);
    j["converged"] = summary.converged();
    j["load_reached"] = summary.final_load;
    nlohmann::json probes = nlohmann::json::array();
    for (const Eigen::VectorXd& X : args.probes) {
      const Eigen::VectorXd u = probe_displacement(assembler, state.u, X);
      probes.push_back({{"X", std::vector<double>(X.data(), X.data() + X.size())},
                        {"u", std::vector<double>(u.data(), u.data() + u.size())}});
    }
    j["probes"] = probes;
    j["energy"] = fr.energy;
    j["volume"] = fr.volume;
    j["min_J"] = fr.min_J;
    j["newton_iterations"] = summary.newton_iterations;
    j["factorizations"] = summary.factorizations;
    j["krylov_iterations"] = summary.krylov_iterations;
    j["load_steps"] = summary.load_steps;
    j["dofs"] = assembler.dofs().num_free;
    // Solve time: the coarse levels' Newton solves and the fine one (no file I/O).
    j["coarse_levels"] = coarse_levels_json(fr.grid);
    j["seconds_solve"] = fr.seconds_solve;
    j["seconds"] = seconds;
    j["vtu"] = vtu;
    std::cout << j.dump(2) << "\n";
  } else {
    std::cout << summary.BriefReport() << "\nwrote " << vtu << "\n";
    if (!args.write_cloud.empty() && summary.converged())
      std::cout << "wrote " << args.write_cloud << "\n";
    for (const Eigen::VectorXd& X : args.probes) {
      std::cout << "u(" << X.transpose()
                << ") = " << probe_displacement(assembler, state.u, X).transpose() << "\n";
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

#if defined(SOFTHD_WITH_MPI) && SOFTHD_WITH_MPI
/// Reference positions of the controls (vertices or element centres) from the mesh alone.
Eigen::MatrixXd control_positions(const Mesh& mesh, ControlKind kind) {
  if (kind == ControlKind::kVertex) {
    Eigen::MatrixXd p(mesh.num_vertices(), mesh.dim);
    for (Eigen::Index v = 0; v < p.rows(); ++v) p.row(v) = mesh.nodes.row(mesh.vertex_nodes[v]);
    return p;
  }
  Eigen::MatrixXd p = Eigen::MatrixXd::Zero(mesh.num_elements(), mesh.dim);
  const Eigen::Index nv = mesh.element_vertices.cols();
  for (Eigen::Index e = 0; e < p.rows(); ++e)
    for (Eigen::Index a = 0; a < nv; ++a)
      p.row(e) += mesh.nodes.row(mesh.vertex_nodes[mesh.element_vertices(e, a)]) / nv;
  return p;
}

// softhd forward with a PETSc backend: every rank reads the scene and builds its slab; rank 0
// writes the VTU and prints the report.
int forward_petsc(const Args& args) {
  const auto t0 = std::chrono::steady_clock::now();
  if (!args.write_cloud.empty() || !args.linear_solver.empty() || args.factorize_every_step)
    throw softhd::InvalidArgument(
        "--write-cloud, --linear-solver and --factorize-every-step need --state-backend cholmod");
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  const Scene scene = load_scene(args.scene, args.memory_limit * size);
  const Mesh mesh = scene.make_mesh();
  const Eigen::MatrixXd positions = control_positions(mesh, scene.control_kind);
  Eigen::VectorXd m = Eigen::VectorXd::Constant(
      positions.rows(), args.has_uniform ? args.uniform : scene.control_initial);
  if (!args.control_file.empty()) m = read_control_file(args.control_file, positions);
  if (!args.write_nodes.empty()) {
    if (rank == 0) write_control_file(args.write_nodes, positions, m);
    return 0;
  }
  for (Eigen::Index k = 0; k < m.size(); ++k)
    if (!(m[k] >= scene.control_lower && m[k] <= scene.control_upper))
      throw softhd::InvalidArgument("control value " + std::to_string(m[k]) + " at control " +
                                    std::to_string(k) + " is outside the scene's bounds");
  for (const Eigen::VectorXd& X : args.probes) {
    Eigen::VectorXd xi;
    if (X.size() != scene.dim() || locate(mesh, X, &xi) < 0)
      throw softhd::InvalidArgument("a probe is not a point of the body");
  }
  softhd::set_threads(args.threads);
  PetscStateOptions options;
  options.backend = args.backend;
  options.newton.verbose = args.verbose;
  options.newton.displacement_tolerance = args.step_tol;
  options.newton.initial_load_increment = args.load_increment;
  options.newton.min_load_increment =
      std::min(options.newton.min_load_increment, args.load_increment);
  options.newton.intermediate_tolerance = args.intermediate_tol;
  PetscStateSolver solver(scene, options);
  GridSequencingOptions grid_options;
  grid_options.levels = args.coarse_levels;
  const GridSequencingReport grid = solver.grid_sequenced_start(scene, m, grid_options);
  if (rank == 0) std::cerr << grid.BriefReport();
  const NewtonSummary summary = solver.solve(m);
  double seconds_solve = summary.seconds_total;
  for (const GridLevelReport& level : grid.levels) seconds_solve += level.newton.seconds_total;
  const Eigen::VectorXd u = solver.displacement();
  const Eigen::MatrixXd J = solver.jacobians(), m_qp = solver.control_at_quadrature();
  const double energy = solver.energy(), volume = solver.deformed_volume();
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (rank != 0) return summary.converged() ? 0 : 1;
  std::filesystem::create_directories(args.out_dir);
  const std::string vtu = (std::filesystem::path(args.out_dir) / "forward.vtu").string();
  write_vtu(vtu, mesh, u, m_qp, J);
  if (args.json) {
    nlohmann::json j;
    j["scene"] = scene.name;
    j["state_backend"] = to_string(args.backend);
    j["ranks"] = size;
    j["status"] = to_string(summary.status);
    j["converged"] = summary.converged();
    j["load_reached"] = summary.final_load;
    nlohmann::json probes = nlohmann::json::array();
    for (const Eigen::VectorXd& X : args.probes) {
      const Eigen::VectorXd v = probe_displacement(mesh, u, X);
      probes.push_back({{"X", std::vector<double>(X.data(), X.data() + X.size())},
                        {"u", std::vector<double>(v.data(), v.data() + v.size())}});
    }
    j["probes"] = probes;
    j["energy"] = energy;
    j["volume"] = volume;
    j["min_J"] = J.minCoeff();
    j["newton_iterations"] = summary.newton_iterations;
    j["factorizations"] = summary.factorizations;
    j["krylov_iterations"] = summary.krylov_iterations;
    j["load_steps"] = summary.load_steps;
    j["dofs"] = solver.layout().global_rows;
    j["coarse_levels"] = coarse_levels_json(grid);
    j["seconds_solve"] = seconds_solve;
    j["seconds"] = seconds;
    j["vtu"] = vtu;
    std::cout << j.dump(2) << "\n";
  } else {
    std::cout << summary.BriefReport() << "\nwrote " << vtu << "\n";
    for (const Eigen::VectorXd& X : args.probes)
      std::cout << "u(" << X.transpose() << ") = " << probe_displacement(mesh, u, X).transpose()
                << "\n";
  }
  if (!summary.converged()) {
    std::cerr << "softhd forward: the state solve did not converge\n" << summary.FullReport();
    return 1;
  }
  return 0;
}
#else
int forward_petsc(const Args&) {
  throw softhd::InvalidArgument(
      "the PETSc state backends need softhd built with SOFTHD_WITH_MPI=ON");
}
#endif

}  // namespace

int run_forward(int argc, char** argv) {
  Args args;
  try {
    if (!parse(argc, argv, &args)) {
      std::cout << kUsage;
      return 0;
    }
    return forward(args);
  } catch (const softhd::Error& e) {
    std::cerr << "softhd forward: " << e.what() << "\n";
    return 2;
  } catch (const std::filesystem::filesystem_error& e) {
    std::cerr << "softhd forward: " << e.what() << "\n";
    return 2;
  }
}
