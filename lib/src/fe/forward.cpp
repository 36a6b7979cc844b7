// One forward solve of a scene (moved here from apps/cmd_forward.cpp so that the CLI and the
// Python module solve the same way).

#include "softhd/fe/forward.hpp"

#include <sstream>

#include "softhd/control/targets.hpp"
#include "softhd/error.hpp"

namespace softhd::fe {

void ForwardOptions::validate() const {
  std::string error;
  if (!newton.IsValid(&error)) throw InvalidArgument("newton: " + error);
  if (coarse_levels < 0 || coarse_levels > 8)
    throw InvalidArgument("coarse_levels must be an integer from 0 to 8, got " +
                          std::to_string(coarse_levels));
}

Scene coarsened(const Scene& scene) {
  Scene coarse = scene;
  for (Eigen::Index k = 0; k < coarse.cells.size(); ++k) {
    if (coarse.cells[k] % 2 != 0)
      throw InvalidArgument("coarse_levels: " + std::to_string(coarse.cells[k]) +
                            " cells along axis " + std::to_string(k + 1) + " cannot be halved");
    coarse.cells[k] /= 2;
  }
  return coarse;
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

namespace {

/// The starting state for `assembler` (the scene's mesh) and m_qp: the rest state, or with
/// levels > 0 the equilibrium on the mesh with half the cells (itself started with
/// levels − 1) interpolated onto this mesh's nodes by the coarse shape functions.
State start_state(const Scene& scene, const Assembler& assembler, const Eigen::MatrixXd& m_qp,
                  const LevelControl& control_of, int levels, const ForwardOptions& options) {
  State state = rest_state(assembler);
  if (levels == 0) return state;
  const Scene coarse = coarsened(scene);
  const Assembler ca = coarse.make_assembler();
  const ControlSpace cc(ca.mesh(), ca.geometry(), coarse.control_kind);
  const Eigen::MatrixXd mq = cc.to_quadrature(control_of(coarse, cc));
  State cs = start_state(coarse, ca, mq, control_of, levels - 1, options);
  NewtonSolver newton(ca, options.newton);
  const NewtonSummary summary = newton.solve(mq, &cs);
  if (options.on_coarse_level) {
    std::ostringstream cells;
    cells << coarse.cells.transpose();
    options.on_coarse_level("coarse level (cells " + cells.str() + "): " + summary.BriefReport());
  }
  if (!summary.converged())
    throw Error("coarse_levels: the state on the coarser mesh did not converge");
  // Prolongation: u(X) = Σ_a N_a(ξ) u_a of the coarse element containing each node.
  const Mesh& cm = ca.mesh();
  Eigen::MatrixXd y = cm.nodes;
  for (Eigen::Index n = 0; n < cm.num_nodes(); ++n)
    for (int c = 0; c < cm.dim; ++c) y(n, c) += cs.u[n * cm.dim + c];
  const NodalMap P(cm, PointCloud(y, Eigen::VectorXd::Ones(cm.num_nodes())));
  state.u = P.displacement(assembler.mesh());
  state.m_qp = m_qp;  // Newton starts at full load from the interpolated state
  return state;
}

}  // namespace

ForwardResult solve_forward(const Scene& scene, const Assembler& assembler,
                            const ControlSpace& control, const LevelControl& control_of,
                            const ForwardOptions& options) {
  options.validate();
  const Eigen::VectorXd m = control_of(scene, control);
  check_control_bounds(scene, control, assembler.mesh(), m);
  NewtonSolver newton(assembler, options.newton);
  const Eigen::MatrixXd m_qp = control.to_quadrature(m);
  ForwardResult r;
  r.state = start_state(scene, assembler, m_qp, control_of, options.coarse_levels, options);
  r.summary = newton.solve(m_qp, &r.state);
  assembler.evaluate(r.state.u, r.state.m_qp, &r.energy, nullptr, nullptr);
  r.volume = assembler.deformed_volume(r.state.u);
  r.min_J = assembler.jacobians(r.state.u).minCoeff();
  return r;
}

}  // namespace softhd::fe
