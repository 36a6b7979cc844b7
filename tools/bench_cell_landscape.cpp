// The landscape of ρ̃ near a reachable target, collocated against cell-integrated
// (docs/formulation.md §2.8, "The landscape with the cell quadrature"): the bending plate
// (data/scenes/bending.json) on CELLS (default 13 × 3 × 1, Q2), the target the equilibrium of
// the known control m* = −2.6e4 X3/0.1 solved on the 2× finer mesh, as the nodes with deformed
// volumes (collocation, as `softhd forward --write-cloud`) and as cells (each Q2 cell split into
// 8 trilinear sub-cells through its 27 nodes).
//
//   bench_cell_landscape [--threads T] [--h H1,H2] [--scales S1,S2] [--rays T1,T2,...]
//                        [--components K] [--check C] [--cells N1,N2,N3] [--target fine|body]
//                        [--refine R]
//
// For each scale s of m* (default 1 and 0.5): ρ̃'s gradient with respect to the controls by
// central differences of the value at steps H (in units of the bound range, default 1e-3 and
// 3e-4; each solve warm-started from the nearest kept state), for the cell quadrature and for
// collocation (method exact), against the adjoint gradient of collocation; the projected
// gradient norms ‖P(z − ∇_z ρ̃) − z‖ in z = m/s_b (s_b = max(|lower|, |upper|), docs/formulation.md
// §4.5). The second step only on every C-th component (default 7), to check the first. Then both
// values along the ray t m* (T; "--rays ''": none), the target's cell self floor, and one value's
// cost of each. K ≥ 0: the differences on the first K components only (0: the adjoint's only).
// --target body: the body's own equilibrium at m* on the finer mesh's nodes and cells (its FE
// interpolant), a target the body reaches exactly at m*: the quadratures' part alone. --refine R:
// the target's mesh R× the body's cells (default 2; 1 with --target body: the body's own cells).
#include <Eigen/Core>
#include <chrono>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include "hausdorff/cell_distance.hpp"
#include "softhd/control/scene.hpp"
#include "softhd/control/shape_objective.hpp"
#include "softhd/control/targets.hpp"
#include "softhd/error.hpp"
#include "softhd/fe/cloud.hpp"
#include "softhd/fe/forward.hpp"
#include "softhd/hausdorff.hpp"
#include "softhd/parallel.hpp"

using namespace softhd;
using detail::HexCells;

namespace {

double now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

std::vector<double> numbers(const std::string& text) {
  std::vector<double> v;
  std::stringstream s(text);
  std::string item;
  while (std::getline(s, item, ','))
    if (!item.empty()) v.push_back(std::stod(item));
  return v;
}

// The trilinear sub-cells of a hexahedral Lagrange mesh of order p deformed by u: each cell's
// (p+1)³ nodes (tensor order a = i + (p+1)(j + (p+1)k)) split into p³ hexahedra through them.
HexCells deformed_cells(const fe::Assembler& assembler, const Eigen::VectorXd& u) {
  const fe::Mesh& mesh = assembler.mesh();
  if (mesh.cell != fe::CellType::kHex8 && mesh.cell != fe::CellType::kHex27)
    throw InvalidArgument("bench_cell_landscape: hexahedral meshes only");
  const int p = mesh.order, n = p + 1;
  HexCells h;
  h.nodes = fe::deformed_cloud(assembler, u, fe::CloudPoints::kNodes, fe::CloudVolumes::kReference)
                .points();
  h.cells.resize(mesh.num_elements() * p * p * p, 8);
  const int corner[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                            {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  Eigen::Index row = 0;
  for (Eigen::Index e = 0; e < mesh.num_elements(); ++e)
    for (int k = 0; k < p; ++k)
      for (int j = 0; j < p; ++j)
        for (int i = 0; i < p; ++i, ++row)
          for (int c = 0; c < 8; ++c) {
            const int a = (i + corner[c][0]) + n * ((j + corner[c][1]) + n * (k + corner[c][2]));
            h.cells(row, c) = mesh.elements(e, a);
          }
  return h;
}

// ‖P(z − g_z) − z‖₂ in z = m/s (s the bound scale), g_z = s g, P onto [lower/s, upper/s].
double projected_norm(const Eigen::VectorXd& m, const Eigen::VectorXd& g, double lower,
                      double upper) {
  const double s = std::max(std::abs(lower), std::abs(upper));
  const Eigen::VectorXd z = m / s, gz = s * g;
  return ((z - gz).cwiseMax(lower / s).cwiseMin(upper / s) - z).norm();
}

struct Landscape {
  fe::Body body;
  std::unique_ptr<fe::Assembler> assembler;
  std::unique_ptr<fe::ControlSpace> control;
  std::unique_ptr<ShapeObjective> objective;
  HexCells target_cells;
  detail::CellDistanceOptions cell;
  double seconds_cell = 0.0, seconds_colloc = 0.0;

  // Both ρ̃ at m (the state solved by the objective; cell ρ̃ of its deformed sub-cells).
  void values(const Eigen::VectorXd& m, double* colloc, double* cells) {
    const double t0 = now();
    const ShapeEvaluation e = objective->evaluate(m, false);
    if (e.status != EvaluationStatus::ok) throw StateSolveError("state solve failed: " + e.failure);
    const double t1 = now();
    *colloc = e.rho;
    *cells = detail::cell_rho(deformed_cells(*assembler, objective->state_path().last_state().u),
                              target_cells, cell)
                 .rho;
    seconds_colloc += t1 - t0;
    seconds_cell += now() - t1;
  }
};

// Central differences of both values at m, step h (units of m), components i < K with
// i % every == 0 (the others 0).
void fd_gradients(Landscape& L, const Eigen::VectorXd& m, double h, int K, int every,
                  Eigen::VectorXd* gc, Eigen::VectorXd* gx) {
  gc->setZero(m.size());
  gx->setZero(m.size());
  for (int i = 0; i < K; i += every) {
    double cp, xp, cm, xm;
    Eigen::VectorXd mi = m;
    mi[i] = m[i] + h;
    L.values(mi, &cp, &xp);
    mi[i] = m[i] - h;
    L.values(mi, &cm, &xm);
    (*gc)[i] = (cp - cm) / (2 * h);  // ∂ρ̃/∂m_i ≈ (ρ̃(m + h e_i) − ρ̃(m − h e_i)) / 2h
    (*gx)[i] = (xp - xm) / (2 * h);
  }
}

double rel(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return (a - b).norm() / std::max(b.norm(), 1e-300);
}

struct Args {
  int threads = 1, components = -1, check = 7, refine = 2;
  std::string target = "fine";
  std::vector<double> steps{1e-3, 3e-4}, scales{1.0, 0.5},
      rays{0.5, 0.75, 0.9, 0.95, 1.0, 1.05, 1.1, 1.25}, cells{13, 3, 1};
};

Args parse_args(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string k = argv[i];
    if (i + 1 >= argc) throw InvalidArgument("bench_cell_landscape: " + k + " needs a value");
    const std::string v = argv[++i];
    if (k == "--threads")
      a.threads = std::stoi(v);
    else if (k == "--h")
      a.steps = numbers(v);
    else if (k == "--scales")
      a.scales = numbers(v);
    else if (k == "--rays")
      a.rays = numbers(v);
    else if (k == "--components")
      a.components = std::stoi(v);
    else if (k == "--check")
      a.check = std::max(1, std::stoi(v));
    else if (k == "--refine")
      a.refine = std::max(1, std::stoi(v));
    else if (k == "--target")
      a.target = v;
    else if (k == "--cells")
      a.cells = numbers(v);
    else
      throw InvalidArgument("bench_cell_landscape: unknown argument " + k);
  }
  if (a.steps.size() != 2 || a.cells.size() != 3)
    throw InvalidArgument("bench_cell_landscape: --h needs 2 values, --cells 3");
  if (a.target != "fine" && a.target != "body")
    throw InvalidArgument("bench_cell_landscape: --target: expected fine or body, got " + a.target);
  return a;
}

constexpr double kMTop = -2.6e4, kThickness = 0.1;  // m* = kMTop X3 / kThickness

// The target's displacement on `fa` (R× the body's cells): m* solved there from rest with grid
// sequencing (fine), or the body's own equilibrium at m* carried to its nodes by the body's FE
// map (body).
Eigen::VectorXd target_displacement(const Args& a, const fe::Body& fine, const fe::Assembler& fa,
                                    const Landscape& L, const Eigen::VectorXd& m_star) {
  if (a.target == "fine") {
    const fe::ControlSpace fc = fine.make_control_space(fa);
    const Eigen::VectorXd m_fine = kMTop * fc.positions(fa.mesh()).col(2) / kThickness;
    const fe::ForwardResult fr = fe::solve_forward(fine, fa, fc, m_fine);
    if (!fr.summary.converged()) throw StateSolveError("the fine solve did not converge");
    return fr.state.u;
  }
  const fe::ForwardResult fr = fe::solve_forward(L.body, *L.assembler, *L.control, m_star);
  if (!fr.summary.converged()) throw StateSolveError("the body's solve did not converge");
  return NodalMap(L.assembler->mesh(),
                  fe::deformed_cloud(*L.assembler, fr.state.u, fe::CloudPoints::kNodes,
                                     fe::CloudVolumes::kReference))
      .displacement(fa.mesh());
}

// How far the body's own equilibrium at m* is from the target's map at the body's nodes.
void report_gap(Landscape& L, const fe::Mesh& target_mesh, const PointCloud& target,
                const Eigen::VectorXd& m_star) {
  const ShapeEvaluation e = L.objective->evaluate(m_star, false);
  if (e.status != EvaluationStatus::ok) throw StateSolveError("state solve failed: " + e.failure);
  const Eigen::VectorXd d = L.objective->state_path().last_state().u -
                            NodalMap(target_mesh, target).displacement(L.assembler->mesh());
  const Eigen::Index nn = L.assembler->mesh().num_nodes();
  const Eigen::VectorXd dn =
      Eigen::Map<const Eigen::MatrixXd>(d.data(), 3, nn).colwise().norm().transpose();
  std::printf("body at m* against the target's map at its nodes: RMS %.4g, max %.4g\n",
              std::sqrt(dn.squaredNorm() / nn), dn.maxCoeff());
}

// At m: collocation's adjoint gradient; with K > 0 both gradients by differences (step 1 on
// components < K, step 2 on every check-th of them), their agreement and norms.
void report_gradients(Landscape& L, const Args& a, const Eigen::VectorXd& m, double s) {
  const double lower = L.body.control_lower, upper = L.body.control_upper;
  const double sb = std::max(std::abs(lower), std::abs(upper)), range = upper - lower;
  const ShapeEvaluation e = L.objective->evaluate(m, true);
  if (e.status != EvaluationStatus::ok) throw StateSolveError("state solve failed: " + e.failure);
  std::printf(
      "m = %g m*: colloc rho %.9g, adjoint: projected gradient norm %.4g, |grad_z| %.4g "
      "(s_b = %g)\n",
      s, e.rho, projected_norm(m, e.gradient, lower, upper), sb * e.gradient.norm(), sb);
  std::fflush(stdout);
  const int n = static_cast<int>(m.size());
  const int K = a.components < 0 || a.components > n ? n : a.components;
  if (K == 0) return;
  Eigen::VectorXd gc[2], gx[2];
  fd_gradients(L, m, a.steps[0] * range, K, 1, &gc[0], &gx[0]);
  fd_gradients(L, m, a.steps[1] * range, K, a.check, &gc[1], &gx[1]);
  Eigen::VectorXd adj = e.gradient, sub[2] = {gx[0], gc[0]}, adj_sub = adj;
  adj.tail(n - K).setZero();
  for (int i = 0; i < n; ++i)
    if (i >= K || i % a.check) sub[0][i] = sub[1][i] = adj_sub[i] = 0.0;
  std::printf(
      "  FD step %g x range on %d components, %g on every %d-th: |g1 - g2|/|g2| cells "
      "%.2e, colloc %.2e; colloc FD vs adjoint %.2e (h1, %d components) %.2e (h2)\n",
      a.steps[0], K, a.steps[1], a.check, rel(sub[0], gx[1]), rel(sub[1], gc[1]), rel(gc[0], adj),
      K, rel(gc[1], adj_sub));
  std::printf(
      "  on the %d components: projected gradient norm colloc adjoint %.4g, FD %.4g | "
      "cells FD %.4g; |grad_z| colloc %.4g, cells %.4g\n",
      K, projected_norm(m, adj, lower, upper), projected_norm(m, gc[0], lower, upper),
      projected_norm(m, gx[0], lower, upper), sb * adj.norm(), sb * gx[0].norm());
  std::printf("  cells FD gradient (h1):");
  for (int i = 0; i < K; ++i) std::printf(" %.6g", gx[0][i]);
  std::printf("\n  colloc adjoint gradient:");
  for (int i = 0; i < n; ++i) std::printf(" %.6g", e.gradient[i]);
  std::printf("\n");
  std::fflush(stdout);
}

// Both values along the ray t m*, the target's cell self floor, and one value's cost of each at
// m* (collocation exact and tree at 1e-2, cells), side by side.
void report_ray_and_cost(Landscape& L, const Args& a, const PointCloud& target,
                         const Eigen::VectorXd& m_star) {
  std::printf("ray t m*: t, colloc rho, cells rho\n");
  double c, x;
  for (double t : a.rays) {
    L.values(t * m_star, &c, &x);
    std::printf("  %5.3f %.9g %.9g\n", t, c, x);
    std::fflush(stdout);
  }
  const double t0 = now();
  const double self = detail::cell_rho(L.target_cells, L.target_cells, L.cell).rho;
  std::printf("target cell self floor %.9g (%.2f s)\n", self, now() - t0);
  L.values(m_star, &c, &x);
  const Eigen::VectorXd& u = L.objective->state_path().last_state().u;
  const HexCells body = deformed_cells(*L.assembler, u);
  const PointCloud moving =
      fe::deformed_cloud(*L.assembler, u, fe::CloudPoints::kNodes, fe::CloudVolumes::kReference);
  HausdorffOptions tree = L.objective->options().hausdorff;
  tree.method = Method::tree;
  tree.tolerance = 1e-2;
  const HausdorffTarget exact_t(target, L.objective->options().hausdorff), tree_t(target, tree);
  const double a0 = now();
  (void)exact_t.evaluate(moving, HausdorffRequest{});
  const double a1 = now();
  (void)tree_t.evaluate(moving, HausdorffRequest{});
  const double a2 = now();
  (void)detail::cell_rho(body, L.target_cells, L.cell);
  const double a3 = now();
  std::printf("one value at m*: colloc exact %.4f s, colloc tree 1e-2 %.4f s, cells %.3f s\n",
              a1 - a0, a2 - a1, a3 - a2);
}

}  // namespace

int main(int argc, char** argv) try {
  const Args a = parse_args(argc, argv);
  set_threads(a.threads);
  limit_blas_threads();
  const Scene scene = load_scene(std::string(SOFTHD_SOURCE_DIR) + "/data/scenes/bending.json");
  Landscape L;
  L.body = scene.body;
  fe::Body fine = scene.body;
  for (int k = 0; k < 3; ++k) {
    L.body.cells[k] = static_cast<int>(a.cells[k]);
    fine.cells[k] = a.refine * L.body.cells[k];
  }
  L.assembler = std::make_unique<fe::Assembler>(L.body.make_assembler());
  L.control = std::make_unique<fe::ControlSpace>(L.body.make_control_space(*L.assembler));
  const Eigen::VectorXd m_star =
      kMTop * L.control->positions(L.assembler->mesh()).col(2) / kThickness;
  const fe::Assembler fa = fine.make_assembler();
  const Eigen::VectorXd u_target = target_displacement(a, fine, fa, L, m_star);
  const PointCloud target =
      fe::deformed_cloud(fa, u_target, fe::CloudPoints::kNodes, fe::CloudVolumes::kDeformed);
  ShapeObjectiveOptions so;
  so.hausdorff.method = Method::exact;
  so.hausdorff.threads = a.threads;
  so.newton.displacement_tolerance = 1e-12;
  so.newton.relative_tolerance = 1e-11;
  L.objective = std::make_unique<ShapeObjective>(*L.assembler, *L.control,
                                                 HausdorffTarget(target, so.hausdorff), so);
  L.target_cells = deformed_cells(fa, u_target);
  L.cell.threads = a.threads;
  std::printf(
      "body %dx%dx%d Q%d (%ld controls), target %dx%dx%d (%ld points, %ld sub-cells), "
      "body %ld sub-cells, threads %d\n",
      L.body.cells[0], L.body.cells[1], L.body.cells[2], L.assembler->mesh().order,
      static_cast<long>(m_star.size()), fine.cells[0], fine.cells[1], fine.cells[2],
      static_cast<long>(target.size()), static_cast<long>(L.target_cells.cells.rows()),
      static_cast<long>(L.assembler->mesh().num_elements() * L.assembler->mesh().order *
                        L.assembler->mesh().order * L.assembler->mesh().order),
      a.threads);
  report_gap(L, fa.mesh(), target, m_star);
  for (double s : a.scales) report_gradients(L, a, s * m_star, s);
  if (!a.rays.empty()) report_ray_and_cost(L, a, target, m_star);
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "bench_cell_landscape: %s\n", e.what());
  return 1;
}
