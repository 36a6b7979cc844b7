// One forward solve of a body (the CLI's and the Python module's).

#include "softhd/fe/forward.hpp"

#include <sstream>

#include "softhd/error.hpp"

namespace softhd::fe {

void ForwardOptions::validate() const {
  newton.validate();
  grid.validate();
}

void check_control_bounds(const Body& body, const Mesh& mesh, const Eigen::VectorXd& m) {
  const std::vector<char> acts = acting_controls(mesh, body.control_kind, body.control_regions);
  if (m.size() != static_cast<Eigen::Index>(acts.size()))
    throw InvalidArgument("the control has " + std::to_string(m.size()) +
                          " values but the scene has " + std::to_string(acts.size()) + " controls");
  for (Eigen::Index k = 0; k < m.size(); ++k) {
    // [lower, upper] where the control acts, [0, 0] outside control.region
    const double lower = acts[k] ? body.control_lower : 0.0;
    const double upper = acts[k] ? body.control_upper : 0.0;
    if (!(m[k] >= lower && m[k] <= upper)) {
      std::ostringstream os;
      os << "control value " << m[k] << " at node " << k << " ("
         << control_positions(mesh, body.control_kind).row(k) << ") is outside the scene's bounds ["
         << lower << ", " << upper << "]" << (acts[k] ? "" : " (outside control.region)");
      throw InvalidArgument(os.str());
    }
  }
}

void check_control_bounds(const Body& body, const ControlSpace& control, const Mesh& mesh,
                          const Eigen::VectorXd& m) {
  if (control.kind() != body.control_kind || control.regions() != body.control_regions)
    throw InvalidArgument("check_control_bounds: the control space is not the body's");
  check_control_bounds(body, mesh, m);
}

ForwardResult solve_forward(const Body& body, const Assembler& assembler,
                            const ControlSpace& control, const Eigen::VectorXd& m,
                            const ForwardOptions& options) {
  options.validate();
  check_control_bounds(body, control, assembler.mesh(), m);
  NewtonOptions newton_options = options.newton;  // a zero absolute tolerance: the floor
  if (newton_options.absolute_tolerance == 0.0)
    newton_options.absolute_tolerance = body.residual_floor();
  NewtonSolver newton(assembler, newton_options);
  const Eigen::MatrixXd m_qp = control.to_quadrature(m);
  ForwardResult r;
  r.state = grid_sequenced_start(body, assembler, m, newton_options, options.grid, &r.grid);
  r.summary = newton.solve(m_qp, &r.state);
  assembler.evaluate(r.state.u, r.state.m_qp, &r.energy, nullptr, nullptr);
  r.volume = assembler.deformed_volume(r.state.u);
  r.min_J = assembler.jacobians(r.state.u).minCoeff();
  r.seconds_solve = r.summary.seconds_total;
  for (const GridLevelReport& level : r.grid.levels) r.seconds_solve += level.newton.seconds_total;
  return r;
}

}  // namespace softhd::fe
