// bench_state: measurements of the FE state solver (issue 4). Prints CSV-like lines.
//
//   bench_state solvers [scale]    factorisation/solve times of every linear solver on the
//                                  bending mesh (cells × scale in each direction)
//   bench_state newton SCENE [linear-solver]
//                                  cold start, warm start after +5 % m, adjoint cost, split
//                                  of the time per Newton iteration; run it with
//                                  OMP_NUM_THREADS=1 and =2 to compare threads
//                                  (SOFTHD_BENCH_REPORT=1: the warm solve's iteration
//                                  table, with PCG iterations and factorisations)
//   bench_state hessian SCENE      one reduced Hessian-vector product's state side
//                                  (sensitivity + hessian_product, full and Gauss–Newton)
//                                  against one adjoint gradient at the state of `newton`
//                                  (minimum of 5 each, and the factorisations they made)
//   bench_state assembly SCENE     assembly times, 1 and 2 threads (minimum of 7)
//   bench_state qp-cost SCENE...   one thread: energy + residual + tangent assembly (with
//                                  the merge into K) and the element kernels alone, per
//                                  element and per quadrature point (minimum of 7, wall
//                                  and CPU), and each scene's per-point time over the first's
//   (SCENE: a name in data/scenes, or a path ending in .json)
//   bench_state refine             bending plate, m = -1e4 X3/0.1: tip displacement for Q2
//                                  and Q1 at refinements
//   bench_state hard [cells_x]     m = -5e4 on the upper half of the plate thickness
//                                  (element controls): more than a full turn

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <string>
#include <utility>
#include <vector>

#include "softhd/control/scene.hpp"
#include "softhd/fe/adjoint.hpp"
#include "softhd/fe/newton.hpp"
#include "softhd/fe/output.hpp"
#include "softhd/fe/second_order.hpp"
#include "softhd/fe/state_solver.hpp"
#include "softhd/parallel.hpp"

#ifdef _OPENMP
#include <omp.h>
#endif

using namespace softhd::fe;
using softhd::load_scene;
using softhd::Scene;
using Clock = std::chrono::steady_clock;

namespace {

double since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

int threads() {
#ifdef _OPENMP
  return omp_get_max_threads();
#else
  return 1;
#endif
}

// A scene of data/scenes by name, or a scene file by path (anything ending in .json).
Scene scene_file(const std::string& name) {
  const bool path = name.size() > 5 && name.compare(name.size() - 5, 5, ".json") == 0;
  return load_scene(path ? name
                         : std::string(SOFTHD_SOURCE_DIR) + "/data/scenes/" + name + ".json");
}

// m = -1e4 X3 / 0.1 at the vertices (the quarter-turn-order bend).
Eigen::VectorXd linear_bend(const ControlSpace& c, const Mesh& mesh) {
  const Eigen::MatrixXd P = c.positions(mesh);
  return -1e4 * P.col(2) / 0.1;
}

int solvers(double scale) {
  // The BLAS as NewtonSolver runs it: one OpenBLAS thread. With OpenBLAS's default of
  // one thread per core, a factorisation under load took 1.2-5.2 s instead of 0.26-0.31 s
  // (its threads busy-wait for the cores the other processes hold).
  softhd::limit_blas_threads();
  Scene s = scene_file("bending");
  s.body.cells = (s.body.cells.cast<double>() * scale).cast<int>();
  const Assembler A = s.body.make_assembler();
  const ControlSpace c(A.mesh(), A.geometry(), ControlKind::kVertex);
  State st = rest_state(A);
  SparseMatrix K = A.tangent_pattern();
  Eigen::VectorXd R;
  // A deformed state (one Newton step of the linear bend) so that K is a real tangent.
  A.evaluate(st.u, c.to_quadrature(linear_bend(c, A.mesh())), nullptr, &R, &K);
  // Minimum over 3 repetitions; CPU time (std::clock) as well, since the factorisations
  // are single-threaded and wall time suffers from other processes on a shared machine.
  std::printf("mesh,nodes,dofs,nnz_lower,solver,analyze_s,factorize_s,solve_s,factorize_cpu_s\n");
  for (LinearSolverType t :
       {LinearSolverType::kEigenLLT, LinearSolverType::kEigenLDLT, LinearSolverType::kCholmod}) {
    auto ls = make_linear_solver(t);
    auto t0 = Clock::now();
    ls->analyze(K);
    const double ta = since(t0);
    double tf = 1e300, ts = 1e300, tc = 1e300;
    for (int rep = 0; rep < 3; ++rep) {
      t0 = Clock::now();
      const std::clock_t c0 = std::clock();
      ls->factorize(K);
      tc = std::min(tc, static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC);
      tf = std::min(tf, since(t0));
      t0 = Clock::now();
      const Eigen::VectorXd x = ls->solve(R);
      ts = std::min(ts, since(t0));
    }
    std::printf("%dx%dx%d,%ld,%ld,%ld,%s,%.4f,%.4f,%.4f,%.4f\n", s.body.cells[0], s.body.cells[1],
                s.body.cells[2], static_cast<long>(A.mesh().num_nodes()),
                static_cast<long>(A.dofs().num_free), static_cast<long>(K.nonZeros()),
                to_string(t).c_str(), ta, tf, ts, tc);
  }
  return 0;
}

void print_summary(const char* label, const NewtonSummary& s) {
  const double n = std::max(1, s.newton_iterations);
  std::printf(
      "%s,threads=%d,status=%s,iterations=%d,load_steps=%d,failed=%d,factorizations=%d,"
      "total_s=%.3f,assembly_per_it_s=%.4f,factorization_per_it_s=%.4f,solve_per_it_s=%.4f\n",
      label, threads(), to_string(s.status).c_str(), s.newton_iterations, s.load_steps,
      s.failed_load_steps, s.factorizations, s.seconds_total, s.seconds_assembly / n,
      s.seconds_factorization / n, s.seconds_solve / n);
}

int newton(const std::string& name, const std::string& solver) {
  const Scene s = scene_file(name);
  const Assembler A = s.body.make_assembler();
  const ControlSpace c(A.mesh(), A.geometry(), s.body.control_kind);
  NewtonOptions o;
  if (!solver.empty()) o.tangent.linear_solver = parse_linear_solver(solver);
  NewtonSolver newton(A, o);
  // bending: the linear-through-thickness bend; torsion: 2 % of the lower bound on the
  // top half, which bends and (through the oblique material direction) twists the beam.
  Eigen::VectorXd m;
  if (name == "bending") {
    m = linear_bend(c, A.mesh());
  } else {
    const Eigen::MatrixXd P = c.positions(A.mesh());
    m = (P.col(2).array() > 0.5 * s.body.upper[2]).cast<double>() * 0.02 * s.body.control_lower;
  }
  std::printf("scene=%s,dofs=%ld,solver=%s\n", name.c_str(), static_cast<long>(A.dofs().num_free),
              to_string(o.tangent.linear_solver).c_str());
  State st = rest_state(A);
  const NewtonSummary cold = newton.solve(c.to_quadrature(m), &st);
  print_summary("cold", cold);
  const Eigen::VectorXd tip =
      probe_displacement(A, st.u, s.body.upper.cwiseProduct(Eigen::Vector3d(1, 0.5, 0.5)));
  std::printf("tip_u,%.6f,%.6f,%.6f\n", tip[0], tip[1], tip[2]);
  // Adjoint for J = |u_tip|^2 at the tip nodes: one solve + the gradient integral.
  auto t0 = Clock::now();
  Eigen::VectorXd g = Eigen::VectorXd::Zero(A.dofs().num_dofs);
  for (int n : A.mesh().face("x1")) g.segment(3 * n, 3) = 2.0 * st.u.segment(3 * n, 3);
  const Eigen::VectorXd lambda = solve_adjoint(A, newton, g);
  const Eigen::VectorXd grad = control_gradient(A, c, st.u, lambda);
  const double t_adj = since(t0);
  std::printf("adjoint_s=%.4f,fraction_of_cold_solve=%.4f,|grad|=%.4e\n", t_adj,
              t_adj / cold.seconds_total, grad.norm());
  const NewtonSummary warm = newton.solve(c.to_quadrature(1.05 * m), &st);
  print_summary("warm_plus5pct", warm);
  if (std::getenv("SOFTHD_BENCH_REPORT")) std::fprintf(stderr, "%s", warm.FullReport().c_str());
  std::printf("adjoint_fraction_of_warm_solve=%.4f\n", t_adj / warm.seconds_total);
  return cold.converged() && warm.converged() ? 0 : 1;
}

// The control of `newton` for a scene: the linear bend, or the torsion scene's top half.
Eigen::VectorXd bench_control(const std::string& name, const Scene& s, const ControlSpace& c,
                              const Mesh& mesh) {
  if (name == "bending") return linear_bend(c, mesh);
  const Eigen::MatrixXd P = c.positions(mesh);
  return (P.col(2).array() > 0.5 * s.body.upper[2]).cast<double>() * 0.02 * s.body.control_lower;
}

// The minimum wall time of `reps` calls of f.
template <class F>
double min_time(int reps, F&& f) {
  double best = 1e300;
  for (int r = 0; r < reps; ++r) {
    const auto t0 = Clock::now();
    f();
    best = std::min(best, since(t0));
  }
  return best;
}

int hessian(const std::string& name) {
  const Scene s = scene_file(name);
  StateSolverOptions options;
  const auto solver = make_state_solver(s.body, options);
  auto& S = dynamic_cast<StateSolver&>(*solver);
  const Assembler& A = S.assembler();
  const Eigen::VectorXd m = bench_control(name, s, S.control(), A.mesh());
  const NewtonSummary cold = S.solve(m);
  print_summary("cold", cold);
  if (!cold.converged()) return 1;
  // J = Σ_tip |u|²: g = 2 u, F_uu w = 2 w at the tip nodes.
  Eigen::VectorXd tip = Eigen::VectorXd::Zero(A.dofs().num_dofs);
  for (int n : A.mesh().face("x1")) tip.segment(3 * n, 3).setConstant(2.0);
  const Eigen::VectorXd g = tip.cwiseProduct(S.displacement());
  auto t0 = Clock::now();
  S.gradient(g);
  std::printf("first_gradient_s=%.4f,factorizations=%d\n", since(t0), S.adjoint_factorizations());
  const double t_grad = min_time(5, [&] { S.gradient(g); });
  const Eigen::VectorXd v = 0.1 * Eigen::VectorXd::Ones(m.size()) * m.cwiseAbs().maxCoeff();
  for (softhd::HessianPart part : {softhd::HessianPart::full, softhd::HessianPart::gauss_newton}) {
    int factorizations = 0;
    const double t_prod = min_time(5, [&] {
      const Eigen::VectorXd w = S.sensitivity(v);
      factorizations += S.adjoint_factorizations();
      S.hessian_product(v, w, tip.cwiseProduct(w), part);
      factorizations += S.adjoint_factorizations();
    });
    std::printf("%s: gradient_s=%.4f,product_s=%.4f,product/gradient=%.2f,factorizations=%d\n",
                part == softhd::HessianPart::full ? "full" : "gauss_newton", t_grad, t_prod,
                t_prod / t_grad, factorizations);
  }
  // The element loops of a product alone (the rest is the two PCG solves).
  const Eigen::VectorXd& u = S.current_state().u;
  const Eigen::VectorXd w = S.sensitivity(v);
  const ControlSpace& c = S.control();
  std::printf(
      "loops_s: control_force=%.4f,curvature=%.4f,mixed_um=%.4f,mixed_mu=%.4f,"
      "control_gradient=%.4f\n",
      min_time(5, [&] { control_force(A, c, u, v); }),
      min_time(5, [&] { adjoint_curvature(A, u, w, w); }),
      min_time(5, [&] { adjoint_mixed_um(A, c, w, v); }),
      min_time(5, [&] { adjoint_mixed_mu(A, c, w, w); }),
      min_time(5, [&] { control_gradient(A, c, u, w); }));
  return 0;
}

double tip_z(int order, int nx, int ny, int nz, int* iterations) {
  Scene s = scene_file("bending");
  s.body.order = order;
  s.body.cells << nx, ny, nz;
  const Assembler A = s.body.make_assembler();
  const ControlSpace c(A.mesh(), A.geometry(), ControlKind::kVertex);
  NewtonSolver newton(A);
  State st = rest_state(A);
  const NewtonSummary sum = newton.solve(c.to_quadrature(linear_bend(c, A.mesh())), &st);
  *iterations = sum.converged() ? sum.newton_iterations : -1;
  return probe_displacement(A, st.u, Eigen::Vector3d(10.0, 1.0, 0.05))[2];
}

// Assembly alone, minimum over 7 repetitions, for 1 and 2 threads (the Newton timings on
// a shared machine mix in waiting for other processes).
// Counts the element tangents it is handed (keeps the work from being optimised away).
class CountingSink final : public ElementMatrixSink {
 public:
  void add(Eigen::Index, Eigen::Index count, const double* Ke) override {
    elements += count;
    checksum += Ke[0];
  }
  Eigen::Index elements = 0;
  double checksum = 0.0;
};

int assembly(const std::string& name) {
  const Scene s = scene_file(name);
  const Assembler A = s.body.make_assembler();
  // The PETSc backend's lean assembler (no pattern, dN/dX recomputed per point).
  const Assembler L(A.mesh(), s.body.materials[0], s.body.fiber_field.values.col(0),
                    s.body.constraints, AssemblerStorage::kLean);
  const ControlSpace c(A.mesh(), A.geometry(), s.body.control_kind);
  const Eigen::MatrixXd m = c.to_quadrature(Eigen::VectorXd::Constant(c.size(), -1e3));
  const Eigen::VectorXd u = Eigen::VectorXd::Zero(A.dofs().num_dofs);
  SparseMatrix K = A.tangent_pattern();
  Eigen::VectorXd R;
  double Pi;
  CountingSink sink;
  // element_tangents_*: energy, residual and element tangents handed to a sink that does
  // nothing with them, by the full assembler (stored dN/dX) and by the lean one.
  std::printf(
      "scene,threads,energy_s,energy_residual_tangent_s,element_tangents_full_s,"
      "element_tangents_lean_s\n");
  for (int t : {1, 2}) {
#ifdef _OPENMP
    omp_set_num_threads(t);
#endif
    double te = 1e300, tk = 1e300, tf = 1e300, tl = 1e300;
    for (int rep = 0; rep < 7; ++rep) {
      auto t0 = Clock::now();
      A.evaluate(u, m, &Pi, nullptr, nullptr);
      te = std::min(te, since(t0));
      t0 = Clock::now();
      A.evaluate(u, m, &Pi, &R, &K);
      tk = std::min(tk, since(t0));
      t0 = Clock::now();
      A.evaluate_elements(u, m, &Pi, &R, &sink);
      tf = std::min(tf, since(t0));
      t0 = Clock::now();
      L.evaluate_elements(u, m, &Pi, &R, &sink);
      tl = std::min(tl, since(t0));
    }
    std::printf("%s,%d,%.4f,%.4f,%.4f,%.4f\n", name.c_str(), t, te, tk, tf, tl);
  }
  if (sink.elements != 28 * A.mesh().num_elements()) std::fprintf(stderr, "bench: sink count\n");
  return 0;
}

// Minimum over 7 repetitions of f's wall and CPU seconds.
template <class F>
std::pair<double, double> min_time(F&& f) {
  double wall = 1e300, cpu = 1e300;
  for (int rep = 0; rep < 7; ++rep) {
    const auto t0 = Clock::now();
    const std::clock_t c0 = std::clock();
    f();
    cpu = std::min(cpu, static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC);
    wall = std::min(wall, since(t0));
  }
  return {wall, cpu};
}

// Assembly cost per element and per quadrature point, one thread (issue 30: the P2
// tetrahedron against the Q2 hexahedron). u = 0 and m = -1e-3 a: the kernels have no
// data-dependent branches, so the state does not change the cost.
int qp_cost(const std::vector<std::string>& names) {
#ifdef _OPENMP
  omp_set_num_threads(1);
#endif
  std::printf(
      "scene,cell_nodes,quadrature_points,elements,dofs,assembly_s,assembly_cpu_s,kernels_s,"
      "kernels_cpu_s,cpu_us_per_element,cpu_us_per_point,kernel_cpu_us_per_point,"
      "per_point_over_first,kernel_per_point_over_first\n");
  double first = 0.0, first_kernel = 0.0;
  for (const std::string& name : names) {
    const Scene s = scene_file(name);
    const Assembler A = s.body.make_assembler();
    const ControlSpace c(A.mesh(), A.geometry(), s.body.control_kind);
    const double a = s.body.materials[0]->stiffness_scale();
    const Eigen::MatrixXd m = c.to_quadrature(Eigen::VectorXd::Constant(c.size(), -1e-3 * a));
    const Eigen::VectorXd u = Eigen::VectorXd::Zero(A.dofs().num_dofs);
    SparseMatrix K = A.tangent_pattern();
    Eigen::VectorXd R;
    double Pi = 0.0;
    CountingSink sink;
    const auto full = min_time([&] { A.evaluate(u, m, &Pi, &R, &K); });
    const auto kernels = min_time([&] { A.evaluate_elements(u, m, &Pi, &R, &sink); });
    // Per element and point from the CPU time: one thread, so it is the work done, without
    // the waits for other processes that the wall time of a shared machine mixes in.
    const double E = static_cast<double>(A.mesh().num_elements());
    const int nq = A.geometry().points_per_element();
    const double per_point = full.second / (E * nq), kernel_per_point = kernels.second / (E * nq);
    if (first == 0.0) first = per_point, first_kernel = kernel_per_point;
    std::printf("%s,%d,%d,%ld,%ld,%.5f,%.5f,%.5f,%.5f,%.3f,%.4f,%.4f,%.3f,%.3f\n", s.name.c_str(),
                A.mesh().nodes_per_element(), nq, static_cast<long>(E),
                static_cast<long>(A.dofs().num_dofs), full.first, full.second, kernels.first,
                kernels.second, 1e6 * full.second / E, 1e6 * per_point, 1e6 * kernel_per_point,
                per_point / first, kernel_per_point / first_kernel);
  }
  return 0;
}

int refine() {
  std::printf("order,cells,tip_u3,newton_iterations,seconds\n");
  const int base[3] = {10, 1, 1};
  for (int order : {2, 1})
    for (int r : {1, 2, 4, 8}) {
      if (order == 2 && r == 8) continue;
      const auto t0 = Clock::now();
      int its = 0;
      const int nx = base[0] * r * (order == 1 ? 2 : 1), ny = base[1] * r,
                nz = base[2] * r * (order == 1 ? 2 : 1);
      const double w = tip_z(order, nx, ny, nz, &its);
      std::printf("Q%d,%dx%dx%d,%.6f,%d,%.2f\n", order, nx, ny, nz, w, its, since(t0));
      std::fflush(stdout);
    }
  return 0;
}

int hard(int nx) {
  Scene s = scene_file("bending");
  s.body.cells << nx, std::max(1, nx / 10), 2;
  s.body.control_kind = ControlKind::kElement;
  const Assembler A = s.body.make_assembler();
  const ControlSpace c(A.mesh(), A.geometry(), ControlKind::kElement);
  const Eigen::MatrixXd P = c.positions(A.mesh());
  const Eigen::VectorXd m = (P.col(2).array() > 0.05).cast<double>() * -5e4;
  NewtonOptions o;
  o.max_load_steps = 1000;
  NewtonSolver newton(A, o);
  State st = rest_state(A);
  const NewtonSummary sum = newton.solve(c.to_quadrature(m), &st);
  print_summary("hard_full_turn", sum);
  const Eigen::VectorXd tip = probe_displacement(A, st.u, Eigen::Vector3d(10.0, 1.0, 0.05));
  // Turning angle of the mid-plane line X2 = 1, X3 = 0.05: unwrapped angles of 200 chords.
  double turn = 0.0, previous = 0.0;
  Eigen::VectorXd x_prev;
  for (int i = 0; i <= 200; ++i) {
    const Eigen::Vector3d X(10.0 * i / 200, 1.0, 0.05);
    const Eigen::VectorXd x = X + probe_displacement(A, st.u, X);
    if (i > 0) {
      double angle = std::atan2(x[2] - x_prev[2], x[0] - x_prev[0]);
      while (angle - previous > M_PI) angle -= 2 * M_PI;
      while (angle - previous < -M_PI) angle += 2 * M_PI;
      turn += angle - previous;
      previous = angle;
    }
    x_prev = x;
  }
  std::printf("cells=%dx%dx%d,tip_u,%.5f,%.5f,%.5f,min_J=%.4f,turn_rad=%.4f\n", s.body.cells[0],
              s.body.cells[1], s.body.cells[2], tip[0], tip[1], tip[2], A.min_jacobian(st.u), turn);
  return sum.converged() ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string mode = argc > 1 ? argv[1] : "";
  if (mode == "solvers") return solvers(argc > 2 ? std::atof(argv[2]) : 1.0);
  if (mode == "newton" && argc > 2) return newton(argv[2], argc > 3 ? argv[3] : "");
  if (mode == "refine") return refine();
  if (mode == "assembly" && argc > 2) return assembly(argv[2]);
  if (mode == "hessian" && argc > 2) return hessian(argv[2]);
  if (mode == "qp-cost" && argc > 2)
    return qp_cost(std::vector<std::string>(argv + 2, argv + argc));
  if (mode == "hard") return hard(argc > 2 ? std::atoi(argv[2]) : 50);
  std::fprintf(stderr,
               "usage: bench_state solvers [scale] | newton bending|torsion [solver] | "
               "assembly SCENE | hessian SCENE | qp-cost SCENE... | refine | hard [cells_x]\n");
  return 2;
}
