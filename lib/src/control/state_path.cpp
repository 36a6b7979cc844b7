// The state path of the shape objective: warm starts, two-level starts and the adjoint
// (docs/formulation.md §4.4, §4.7).

#include "softhd/control/state_path.hpp"

#include <cmath>
#include <string>

#include "softhd/error.hpp"
#include "softhd/fe/grid_sequencing.hpp"

namespace softhd {

StatePath::StatePath(const fe::Assembler& assembler, const fe::ControlSpace& control,
                     std::unique_ptr<fe::StateEquation> solver, const fe::NewtonOptions& newton,
                     int warm_start_states, int coarse_correction_iterations)
    : assembler_(assembler),
      control_(control),
      solver_(std::move(solver)),
      newton_(newton),
      warm_start_states_(warm_start_states),
      coarse_correction_iterations_(coarse_correction_iterations) {
  SOFTHD_ASSERT(solver_ != nullptr, "the state solver factory made none");
  cache_.push_back({Eigen::VectorXd(), fe::rest_state(assembler)});
}
StatePath::~StatePath() = default;

void StatePath::remember(const Eigen::VectorXd& m, const fe::State& state) {
  cache_.push_front({m, state});
  while (static_cast<int>(cache_.size()) > warm_start_states_) cache_.pop_back();
}

void StatePath::restore(const std::vector<WarmStart>& states) {
  if (states.empty() || static_cast<int>(states.size()) > warm_start_states_)
    throw InvalidArgument("warm starts: expected 1 to " + std::to_string(warm_start_states_) +
                          " states, got " + std::to_string(states.size()));
  const fe::State& rest = cache_.back().state;  // the shapes every state has
  for (const WarmStart& w : states) {
    if ((w.m.size() != 0 && w.m.size() != control_.size()) || w.state.u.size() != rest.u.size() ||
        w.state.m_qp.rows() != rest.m_qp.rows() || w.state.m_qp.cols() != rest.m_qp.cols() ||
        !w.state.u.allFinite() || !w.state.m_qp.allFinite() || !w.m.allFinite())
      throw InvalidArgument("warm starts: a state does not fit this problem");
  }
  cache_.assign(states.begin(), states.end());
  ++generation_;
}

void StatePath::use_coarse_level(const fe::Assembler& coarse) {
  coarse_ = &coarse;
  coarse_newton_.emplace(coarse, newton_);
}

void StatePath::reset() {
  ++generation_;
  solver_->reset();
  if (coarse_) coarse_newton_.emplace(*coarse_, newton_);
  coarse_active_ = true;
  coarse_cache_.clear();  // like the solver's, not in a checkpoint
}

Eigen::VectorXd StatePath::adjoint(const Eigen::VectorXd& g, int* factorizations) {
  Eigen::VectorXd out = solver_->gradient(g);
  *factorizations += solver_->adjoint_factorizations();
  return out;
}

StateSolve StatePath::resolve(const Eigen::VectorXd& m, const fe::State& converged,
                              fe::State* state) {
  StateSolve out;
  out.summary = solve_from(converged, m, state);
  out.newton_iterations = out.summary.newton_iterations;
  out.factorizations = out.summary.factorizations;
  return out;
}

Eigen::VectorXd StatePath::sensitivity(const Eigen::VectorXd& v) { return solver_->sensitivity(v); }

Eigen::VectorXd StatePath::hessian_product(const Eigen::VectorXd& v, const Eigen::VectorXd& w,
                                           const Eigen::VectorXd& q, HessianPart part) {
  return solver_->hessian_product(v, w, q, part);
}

Eigen::MatrixXd StatePath::coarse_control(const Eigen::VectorXd& m) const {
  return fe::control_on_quadrature(*coarse_, assembler_.mesh(), control_.kind(), m,
                                   control_.regions());
}

/// The fine start u + P(u_c(m) − u_c(m_old)): the coarse equilibria at the warm start's
/// control m_old (kept from an earlier solve, else solved from the restricted warm state)
/// and at m, their difference prolongated. Returns false if a coarse solve fails;
/// `iterations` counts the coarse iterations to m.
bool StatePath::coarse_corrected(const Eigen::VectorXd& m, const WarmStart& warm, fe::State* start,
                                 int* iterations) {
  const Eigen::VectorXd m_old = warm.m.size() ? warm.m : Eigen::VectorXd::Zero(m.size());
  fe::State c;
  if (!kept_coarse_state(m_old, &c)) {
    c = {fe::prolongate(assembler_.mesh(), warm.state.u, coarse_->mesh()), coarse_control(m_old)};
    if (!coarse_newton_->solve(c.m_qp, &c).converged()) return false;
  }
  const Eigen::VectorXd u_old = c.u;
  const fe::NewtonSummary to_m = coarse_newton_->solve(coarse_control(m), &c);
  *iterations = to_m.newton_iterations;
  if (!to_m.converged()) return false;
  coarse_cache_.push_front({m, c});
  while (static_cast<int>(coarse_cache_.size()) > warm_start_states_) coarse_cache_.pop_back();
  start->u = warm.state.u + fe::prolongate(coarse_->mesh(), c.u - u_old, assembler_.mesh());
  start->m_qp = control_.to_quadrature(m);
  return true;
}

/// The coarse equilibrium kept for exactly the control m, if any.
bool StatePath::kept_coarse_state(const Eigen::VectorXd& m, fe::State* state) const {
  for (const WarmStart& w : coarse_cache_) {
    if (w.m.size() == m.size() && w.m == m) {
      *state = w.state;
      return true;
    }
  }
  return false;
}

/// The kept state whose control is nearest to m (the rest state counts as m = 0).
const WarmStart& StatePath::nearest(const Eigen::VectorXd& m) const {
  size_t best = 0;
  double best_d = INFINITY;
  for (size_t k = 0; k < cache_.size(); ++k) {
    const double d = cache_[k].m.size() ? (cache_[k].m - m).norm() : m.norm();
    if (d < best_d) {
      best_d = d;
      best = k;
    }
  }
  return cache_[best];
}

/// The fine solve to m from `start`; its end state (converged or not) in *state.
fe::NewtonSummary StatePath::solve_from(const fe::State& start, const Eigen::VectorXd& m,
                                        fe::State* state) {
  ++generation_;
  solver_->set_state(start);
  const fe::NewtonSummary s = solver_->solve(m);
  *state = solver_->state();
  return s;
}

StateSolve StatePath::solve(const Eigen::VectorXd& m, fe::State* state) {
  const WarmStart& warm = nearest(m);
  StateSolve out;
  const auto counted = [&out](const fe::NewtonSummary& s) {
    out.newton_iterations += s.newton_iterations;
    out.factorizations += s.factorizations;
    out.summary = s;
    return s;
  };
  if (coarse_ && coarse_active_) {
    int iterations = 0;
    fe::State start;
    const bool ok = coarse_corrected(m, warm, &start, &iterations);
    if (ok && iterations >= coarse_correction_iterations_) {
      const fe::NewtonSummary s = counted(solve_from(start, m, state));
      if (s.converged()) return out;
    } else if (ok && iterations > 0) {
      coarse_active_ = false;  // small steps now: the coarse solves would only cost
    }
  }
  const fe::NewtonSummary s = counted(solve_from(warm.state, m, state));
  // A hard fine solve: large steps again, so the coarse level is tried again.
  if (coarse_ && s.newton_iterations >= 2 * coarse_correction_iterations_) coarse_active_ = true;
  return out;
}

}  // namespace softhd
