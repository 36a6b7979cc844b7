#include "softhd/fe/grid_sequencing.hpp"

#include <memory>
#include <sstream>

#include "softhd/error.hpp"
#include "softhd/fe/interpolation.hpp"

namespace softhd::fe {

namespace {

// The box with half the cells along every even axis; with Halving::rounded, a box with no
// even axis has every axis of at least 4 cells halved rounding up, n -> (n + 1) / 2 (a coarser
// box whose grid is not nested in the finer one: the levels exchange fields by interpolation
// at points, prolongate and control_at, which need no nesting).
Scene halved(const Scene& scene, Halving halving) {
  Scene coarse = scene;
  bool halved = false;
  for (Eigen::Index k = 0; k < coarse.cells.size(); ++k) {
    if (coarse.cells[k] % 2 == 0) {
      coarse.cells[k] /= 2;
      halved = true;
    }
  }
  if (!halved && halving == Halving::rounded) {
    for (Eigen::Index k = 0; k < coarse.cells.size(); ++k) {
      if (coarse.cells[k] >= 4) {
        coarse.cells[k] = (coarse.cells[k] + 1) / 2;
        halved = true;
      }
    }
  }
  if (!halved) {
    std::ostringstream os;
    os << "grid sequencing: no cell count of (" << scene.cells.transpose() << ") can be halved";
    if (halving == Halving::rounded) os << " (none is even or at least 4)";
    throw InvalidArgument(os.str());
  }
  return coarse;
}

// A file mesh of order 2 as P1/Q1 on its vertices: the mesh's vertex nodes, fibres per node
// restricted to them (per element and uniform ones as they are), the linear cell's default
// quadrature; materials by region and constraints by name carry over.
Scene order_dropped(const Scene& scene) {
  if (scene.order != 2)
    throw InvalidArgument("grid sequencing: the mesh from " + scene.mesh_file +
                          " is of order 1 at this level (a first-order file, or an order-2 "
                          "file's vertices): a file mesh has no grid to halve, so its one "
                          "coarser level is an order-2 mesh's vertices (P1/Q1 on its cells)");
  const Mesh& fine = *scene.file_mesh;
  Scene coarse = scene;
  coarse.file_mesh = std::make_shared<const Mesh>(linear_mesh(fine));
  coarse.order = 1;
  coarse.gmsh_options.order = 1;
  coarse.quadrature_degree = 0;
  if (scene.fiber_field.kind == FiberField::Kind::kNode) {
    Eigen::Matrix3Xd a(3, fine.num_vertices());
    for (Eigen::Index k = 0; k < a.cols(); ++k)
      a.col(k) = scene.fiber_field.values.col(fine.vertex_nodes[k]);
    coarse.fiber_field.values = a;
  }
  return coarse;
}

}  // namespace

void GridSequencingOptions::validate() const {
  if (levels < -1) throw InvalidArgument("grid sequencing: levels must be >= -1");
  if (min_elements < 1) throw InvalidArgument("grid sequencing: min_elements must be >= 1");
}

std::string GridSequencingReport::BriefReport() const {
  std::ostringstream os;
  for (const GridLevelReport& level : levels)
    os << "coarse level (" << level.mesh << "): " << level.newton.BriefReport() << "\n";
  if (fell_back_to_rest) os << "coarse level did not converge: the fine solve starts from rest\n";
  return os.str();
}

std::string describe_level(const Scene& scene) {
  std::ostringstream os;
  if (scene.is_box()) {
    os << "cells " << scene.cells.transpose();
    return os.str();
  }
  const Mesh& mesh = *scene.file_mesh;
  const ReferenceElement& ref = reference_element(mesh.cell);
  if (scene.gmsh_options.order == 1)  // the vertices only (order_dropped, or "order": 1)
    os << (ref.simplex ? "P1" : "Q1") << " on the vertices: ";
  os << to_string(mesh.cell) << ", " << mesh.num_nodes() << " nodes";
  return os.str();
}

Scene coarsened(const Scene& scene, Halving halving) {
  // The one choice of the coarse level: halving needs a structured grid, which only a box
  // has; a file mesh drops its order on the same cells instead.
  return scene.is_box() ? halved(scene, halving) : order_dropped(scene);
}

int coarser_levels(const Scene& scene, Halving halving, int min_elements) {
  // A file mesh: its P1/Q1 level (order_dropped: as many elements), which has no coarser one;
  // answered without building it.
  if (!scene.is_box())
    return scene.order == 2 && scene.file_mesh->num_elements() >= min_elements ? 1 : 0;
  int levels = 0;
  Scene s = scene;
  while (true) {
    Scene c;
    try {
      c = halved(s, halving);  // a box's cells only: throws where no axis can be halved
    } catch (const InvalidArgument&) {
      return levels;
    }
    if (c.cells.prod() < min_elements) return levels;
    ++levels;
    s = std::move(c);
  }
}

int grid_levels(const Scene& scene, const GridSequencingOptions& options) {
  options.validate();
  if (options.levels >= 0) {
    Scene s = scene;
    for (int l = 0; l < options.levels; ++l) {
      try {
        s = coarsened(s);
      } catch (const InvalidArgument& e) {  // say how many levels there are, and why
        throw InvalidArgument("grid sequencing: " + std::to_string(options.levels) +
                              " coarser levels asked for, but the body has " + std::to_string(l) +
                              " (" + e.what() + ")");
      }
    }
    return options.levels;
  }
  // A file mesh of order 2: its P1/Q1 level (as many elements as the mesh), measured faster
  // than the start from rest on the finger (studies/bench_p_sequencing.py); a box halved along
  // its even axes while the coarser mesh keeps min_elements.
  return coarser_levels(scene, Halving::nested, options.min_elements);
}

Eigen::MatrixXd quadrature_positions(const Mesh& mesh, const ReferenceGeometry& geometry) {
  const int nq = geometry.points_per_element(), nen = geometry.nodes_per_element();
  const Eigen::MatrixXd& N = geometry.shape_values();  // nq by nen
  Eigen::MatrixXd X(mesh.num_elements() * nq, mesh.dim), Xe(nen, mesh.dim);
  for (Eigen::Index e = 0; e < mesh.num_elements(); ++e) {
    for (int a = 0; a < nen; ++a) Xe.row(a) = mesh.nodes.row(mesh.elements(e, a));
    X.middleRows(e * nq, nq) = N * Xe;  // X_q = Σ_a N_a(ξ_q) X_a
  }
  return X;
}

Eigen::MatrixXd control_on_quadrature(const Assembler& assembler, const Mesh& mesh,
                                      ControlKind kind, const Eigen::VectorXd& m,
                                      const std::vector<int>& regions) {
  // The same cells and vertices (and regions): m(ξ_q) = Σ_k M_k(ξ_q) m_k in each element of
  // the control's regions, no point search.
  if (same_cells(assembler.mesh(), mesh))
    return ControlSpace(assembler.mesh(), assembler.geometry(), kind, regions).to_quadrature(m);
  const Eigen::VectorXd v = control_at(
      mesh, kind, m, quadrature_positions(assembler.mesh(), assembler.geometry()), regions);
  const int nq = assembler.geometry().points_per_element();
  return Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
      v.data(), assembler.mesh().num_elements(), nq);
}

Eigen::VectorXd prolongate(const Mesh& coarse, const Eigen::VectorXd& u_coarse, const Mesh& fine) {
  if (coarse.dim != fine.dim || u_coarse.size() != coarse.num_nodes() * coarse.dim)
    throw InvalidArgument("prolongate: the coarse field does not match its mesh");
  const int d = fine.dim;
  const Eigen::MatrixXd U = u_coarse.reshaped(d, coarse.num_nodes()).transpose();
  // The same cells: u(ξ_a) = Σ_b N_b(ξ_a) u_b element by element (p-sequencing).
  if (same_cells(coarse, fine)) return transfer_nodal(coarse, U, fine).transpose().reshaped();
  // u(X_n) = Σ_a N_a(ξ) u_a in the coarse element containing the fine node X_n
  std::vector<int> outside;
  const Eigen::MatrixXd u =
      interpolate_nodal(coarse, PointLocator(coarse), U, fine.nodes, &outside);
  if (!outside.empty())
    throw InvalidArgument("prolongate: fine node " + std::to_string(outside[0]) + " is outside");
  return u.transpose().reshaped();
}

bool solve_grid_level(const Scene& scene, const Mesh& fine, ControlKind kind,
                      const Eigen::VectorXd& m, int levels, const NewtonOptions& newton,
                      GridSequencingReport* report, Mesh* mesh, State* state) {
  const Assembler assembler = scene.make_assembler();
  const Eigen::MatrixXd m_qp =
      control_on_quadrature(assembler, fine, kind, m, scene.control_regions);
  *state = rest_state(assembler);
  if (levels > 0) {
    Mesh coarse_mesh;
    State coarse;
    if (!solve_grid_level(coarsened(scene), fine, kind, m, levels - 1, newton, report, &coarse_mesh,
                          &coarse))
      return false;
    state->u = prolongate(coarse_mesh, coarse.u, assembler.mesh());
  }
  NewtonSolver solver(assembler, newton);
  const NewtonSummary summary = solver.solve(m_qp, state);
  report->levels.push_back({scene.cells, summary, describe_level(scene), assembler.mesh().cell,
                            assembler.mesh().num_nodes()});
  *mesh = assembler.mesh();
  return summary.converged();
}

State grid_sequenced_start(const Scene& scene, const Assembler& fine, const Eigen::VectorXd& m,
                           const NewtonOptions& newton, const GridSequencingOptions& options,
                           GridSequencingReport* report) {
  GridSequencingReport local;
  if (!report) report = &local;
  *report = GridSequencingReport{};
  const int levels = grid_levels(scene, options);
  const ControlSpace control = scene.make_control_space(fine);
  if (m.size() != control.size())
    throw InvalidArgument("grid sequencing: m must have one value per control");
  State state = rest_state(fine);
  state.m_qp = control.to_quadrature(m);  // the fine solve starts at full load
  if (levels == 0) return rest_state(fine);
  Mesh coarse_mesh;
  State coarse;
  if (!solve_grid_level(coarsened(scene), fine.mesh(), scene.control_kind, m, levels - 1, newton,
                        report, &coarse_mesh, &coarse)) {
    report->fell_back_to_rest = true;
    return rest_state(fine);
  }
  state.u = prolongate(coarse_mesh, coarse.u, fine.mesh());
  return state;
}

}  // namespace softhd::fe
