#include "softhd/control/shape_tracking.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "softhd/error.hpp"

namespace softhd {

std::pair<double, double> shape_error(const fe::Mesh& mesh, const Eigen::VectorXd& u,
                                      const Eigen::VectorXd& u_T) {
  const int d = mesh.dim;
  if (u.size() != mesh.num_nodes() * d || u_T.size() != u.size())
    throw InvalidArgument("shape_error: displacements must have num_nodes * dim entries");
  double mx = 0.0, sum = 0.0;
  for (Eigen::Index n = 0; n < mesh.num_nodes(); ++n) {
    const double e = (u.segment(n * d, d) - u_T.segment(n * d, d)).norm();  // |x_i − T(X_i)|
    mx = std::max(mx, e);
    sum += e * e;
  }
  return {mx, std::sqrt(sum / static_cast<double>(mesh.num_nodes()))};
}

std::optional<TrackingIteration> first_below(const std::vector<TrackingIteration>& history,
                                             double k) {
  for (const TrackingIteration& it : history)
    if (it.rho_over_floor <= k) return it;
  return std::nullopt;
}

ShapeTrackingSummary track_shape(ShapeObjective& objective, const Eigen::VectorXd& lower,
                                 const Eigen::VectorXd& upper, const Eigen::VectorXd& m0_in,
                                 const std::optional<Eigen::VectorXd>& map_displacement,
                                 const ShapeTrackingOptions& options,
                                 const ShapeTrackingCallbacks& callbacks) {
  using Clock = std::chrono::steady_clock;
  const auto t_start = Clock::now();
  const fe::Mesh& mesh = objective.assembler().mesh();
  if (map_displacement && map_displacement->size() != mesh.num_nodes() * mesh.dim)
    throw InvalidArgument("track_shape: the known map has the wrong number of entries");
  if (m0_in.size() != lower.size() || lower.size() != upper.size())
    throw InvalidArgument("track_shape: m0, lower and upper differ in size");
  const Eigen::VectorXd m0 = m0_in.cwiseMax(lower).cwiseMin(upper);

  ShapeTrackingSummary s;
  // Floors (docs/formulation.md §2.2, §5.3): the target against itself, and the body deformed
  // exactly by the known map at this discretisation.
  const HausdorffTarget& Y = objective.target();
  const double m_points = static_cast<double>(Y.cloud().size());
  const bool self_floor = m_points * m_points <= options.self_floor_max_pairs;
  // With a known map the matched floor judges progress, and the self floor (M² pairs, often
  // the most expensive evaluation of the run) is only reported: computed after the run.
  if (self_floor && !map_displacement) s.floor_self = Y.evaluate(Y.cloud()).rho;
  if (map_displacement) s.floor_matched = Y.evaluate(objective.particles(*map_displacement)).rho;
  const std::optional<double> floor = s.floor();

  const ShapeEvaluation start = objective.evaluate(m0, false);
  if (!start.ok) throw Error("the state solve at the starting control failed: " + start.failure);
  s.rho_start = start.rho;
  if (callbacks.on_start) callbacks.on_start(s);

  // The objective for the optimiser, remembering the last evaluation for the records.
  ShapeEvaluation last;
  const BoundedObjective f = [&](const Eigen::VectorXd& m, double& value, Eigen::VectorXd* g) {
    last = objective.evaluate(m, g != nullptr);
    s.seconds_state += last.seconds_state;
    s.seconds_distance += last.seconds_distance;
    s.seconds_adjoint += last.seconds_adjoint;
    s.newton_iterations += last.newton_iterations;
    s.factorizations += last.factorizations;
    if (!last.ok) {
      if (callbacks.on_failure) callbacks.on_failure(last.failure);
      return false;
    }
    value = last.J;
    if (g) *g = last.gradient;
    return true;
  };
  fe::State best_state = objective.last_state();  // the state of the best control so far
  const auto on_iteration = [&](const IterationRecord& rec, const Eigen::VectorXd& m) {
    best_state = objective.last_state();
    TrackingIteration it;
    it.iteration = options.iteration_offset + rec.iteration;
    it.evaluation = options.evaluation_offset + rec.evaluation;
    it.J = last.J;
    it.rho = last.rho;
    it.A = last.A;
    it.B = last.B;
    it.rho_over_floor = floor ? last.rho / *floor : std::numeric_limits<double>::quiet_NaN();
    it.projected_gradient_norm = rec.projected_gradient_norm;
    it.newton_iterations = last.newton_iterations;
    it.factorizations = last.factorizations;
    it.seconds_state = last.seconds_state;
    it.seconds_distance = last.seconds_distance;
    it.seconds_adjoint = last.seconds_adjoint;
    it.seconds =
        options.seconds_offset + std::chrono::duration<double>(Clock::now() - t_start).count();
    s.history.push_back(it);
    if (callbacks.on_iteration) callbacks.on_iteration(it, m);
  };
  const BoundedOptimizerSummary r = minimise(f, m0, lower, upper, options.optimizer, on_iteration);

  // The final state: the best control's, evaluated again from its own state (Newton stops
  // at once there, so the final ρ̃ is the one the optimiser saw).
  objective.remember_state(r.x, best_state);
  const ShapeEvaluation final_eval = objective.evaluate(r.x, false);
  if (!final_eval.ok)
    throw Error("the state solve at the best control failed: " + final_eval.failure);
  if (self_floor && map_displacement) s.floor_self = Y.evaluate(Y.cloud()).rho;
  s.control = r.x;
  s.displacement = objective.last_state().u;
  s.rho_final = final_eval.rho;
  s.J_final = final_eval.J;
  s.iterations = options.iteration_offset + r.iterations;
  s.evaluations = options.evaluation_offset + r.evaluations;
  s.failed_evaluations = r.failed_evaluations;
  s.termination = r.termination;
  s.converged = r.converged;
  if (map_displacement) {
    const auto [mx, rms] = shape_error(mesh, s.displacement, *map_displacement);
    s.shape_error_max = mx;
    s.shape_error_rms = rms;
  }
  const double run = std::chrono::duration<double>(Clock::now() - t_start).count();
  s.seconds = options.seconds_offset + run;
  s.seconds_optimizer =
      std::max(0.0, run - s.seconds_state - s.seconds_distance - s.seconds_adjoint);
  return s;
}

}  // namespace softhd
