// One forward solve of a scene (the CLI's and the Python module's).

#include "softhd/fe/forward.hpp"

#include <sstream>

#include "softhd/error.hpp"

namespace softhd::fe {

void ForwardOptions::validate() const {
  newton.validate();
  grid.validate();
}

void check_control_bounds(const Scene& scene, const ControlSpace& control, const Mesh& mesh,
                          const Eigen::VectorXd& m) {
  if (m.size() != control.size())
    throw InvalidArgument("the control has " + std::to_string(m.size()) +
                          " values but the scene has " + std::to_string(control.size()) +
                          " controls");
  for (Eigen::Index k = 0; k < m.size(); ++k) {
    if (!(m[k] >= scene.control_lower && m[k] <= scene.control_upper)) {
      std::ostringstream os;
      os << "control value " << m[k] << " at node " << k << " (" << control.positions(mesh).row(k)
         << ") is outside the scene's bounds [" << scene.control_lower << ", "
         << scene.control_upper << "]";
      throw InvalidArgument(os.str());
    }
  }
}

ForwardResult solve_forward(const Scene& scene, const Assembler& assembler,
                            const ControlSpace& control, const Eigen::VectorXd& m,
                            const ForwardOptions& options) {
  options.validate();
  check_control_bounds(scene, control, assembler.mesh(), m);
  NewtonOptions newton_options = options.newton;  // a zero absolute tolerance: the floor
  if (newton_options.absolute_tolerance == 0.0)
    newton_options.absolute_tolerance = scene.residual_floor();
  NewtonSolver newton(assembler, newton_options);
  const Eigen::MatrixXd m_qp = control.to_quadrature(m);
  ForwardResult r;
  r.state = grid_sequenced_start(scene, assembler, m, newton_options, options.grid, &r.grid);
  r.summary = newton.solve(m_qp, &r.state);
  assembler.evaluate(r.state.u, r.state.m_qp, &r.energy, nullptr, nullptr);
  r.volume = assembler.deformed_volume(r.state.u);
  r.min_J = assembler.jacobians(r.state.u).minCoeff();
  r.seconds_solve = r.summary.seconds_total;
  for (const GridLevelReport& level : r.grid.levels) r.seconds_solve += level.newton.seconds_total;
  return r;
}

}  // namespace softhd::fe
