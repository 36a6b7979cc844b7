#include "softhd/fe/grid_sequencing.hpp"

#include <sstream>
#include <string>
#include <utility>

#include "softhd/error.hpp"
#include "softhd/fe/interpolation.hpp"

namespace softhd::fe {

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

MeshHierarchy grid_hierarchy(const Body& body, const GridSequencingOptions& options) {
  options.validate();
  if (options.levels >= 0) {
    try {
      return MeshHierarchy(body, Halving::nested, options.levels);
    } catch (const InvalidArgument& e) {
      throw InvalidArgument(std::string("grid sequencing: ") + e.what());
    }
  }
  // A file mesh of order 2: its P1/Q1 level (as many elements as the mesh), measured faster
  // than the start from rest on the finger (studies/bench_p_sequencing.py); a box halved along
  // its even axes while the coarser mesh keeps min_elements.
  return MeshHierarchy(body, Halving::nested,
                       coarser_levels(body, Halving::nested, options.min_elements));
}

int grid_levels(const Body& body, const GridSequencingOptions& options) {
  options.validate();
  if (options.levels < 0) return coarser_levels(body, Halving::nested, options.min_elements);
  return grid_hierarchy(body, options).size() - 1;
}

bool solve_coarse_levels(const MeshHierarchy& levels, const Mesh& control_mesh, ControlKind kind,
                         const Eigen::VectorXd& m, const NewtonOptions& newton,
                         GridSequencingReport* report, Mesh* mesh, State* state) {
  Mesh below;  // the level under the one being solved, and its equilibrium
  State below_state;
  for (int k = levels.size() - 1; k >= 1; --k) {  // coarsest first
    const Body& body = levels.level(k);
    const Assembler assembler = body.make_assembler();
    State s = rest_state(assembler);
    if (k < levels.size() - 1) s.u = prolongate(below, below_state.u, assembler.mesh());
    NewtonSolver solver(assembler, newton);
    const NewtonSummary summary = solver.solve(
        control_on_quadrature(assembler, control_mesh, kind, m, body.control_regions), &s);
    report->levels.push_back({body.cells, summary, describe_level(body), assembler.mesh().cell,
                              assembler.mesh().num_nodes()});
    if (!summary.converged()) return false;
    below = assembler.mesh();
    below_state = std::move(s);
  }
  *mesh = std::move(below);
  *state = std::move(below_state);
  return true;
}

State grid_sequenced_start(const Body& body, const Assembler& fine, const Eigen::VectorXd& m,
                           const NewtonOptions& newton, const GridSequencingOptions& options,
                           GridSequencingReport* report) {
  GridSequencingReport local;
  if (!report) report = &local;
  *report = GridSequencingReport{};
  const MeshHierarchy levels = grid_hierarchy(body, options);
  const ControlSpace control = body.make_control_space(fine);
  if (m.size() != control.size())
    throw InvalidArgument("grid sequencing: m must have one value per control");
  State state = rest_state(fine);
  state.m_qp = control.to_quadrature(m);  // the fine solve starts at full load
  if (levels.size() == 1) return rest_state(fine);
  Mesh coarse_mesh;
  State coarse;
  if (!solve_coarse_levels(levels, fine.mesh(), body.control_kind, m, newton, report, &coarse_mesh,
                           &coarse)) {
    report->fell_back_to_rest = true;
    return rest_state(fine);
  }
  state.u = prolongate(coarse_mesh, coarse.u, fine.mesh());
  return state;
}

}  // namespace softhd::fe
