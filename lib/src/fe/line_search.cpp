#include "line_search.hpp"

#include <cmath>

namespace softhd::fe {

double EnergyLineSearch::backtrack(const Eigen::VectorXd& u0, double Pi0, double slope,
                                   const Eigen::VectorXd& du, double s, double rnorm,
                                   Eigen::VectorXd* u) const {
  // Π(u0 + s du) <= Π(u0) + c s slope, s shrinking; det F <= 0 is never accepted.
  for (int ls = 0; ls < options_.max_line_search_steps; ++ls, s *= options_.backtrack) {
    const Eigen::VectorXd trial = u0 + s * du;
    double Pi_trial;
    if (!energy_(trial, &Pi_trial)) continue;
    bool accept = Pi_trial <= Pi0 + options_.armijo * s * slope;
    // Energy differences at round-off: accept if the residual decreases.
    if (!accept && std::abs(Pi_trial - Pi0) <= 1e-13 * std::abs(Pi0))
      accept = residual_norm_(trial) < rnorm;
    if (accept) {
      *u = trial;
      return s;
    }
  }
  return 0.0;
}

double EnergyLineSearch::step(const Eigen::VectorXd& du, double Pi, double slope, double rnorm,
                              Eigen::VectorXd* u) {
  const Eigen::VectorXd full = *u + du;
  double Pi_full;
  const bool admissible = energy_(full, &Pi_full);
  if (watch_.active) {
    // The previous step was tentative: keep both if this full step ends below the saved
    // point's Armijo line, else backtrack the saved step from the saved point.
    watch_.active = false;
    if (admissible && Pi_full <= watch_.Pi + options_.armijo * watch_.slope) {
      *u = full;
      return 1.0;
    }
    const double s = backtrack(watch_.u, watch_.Pi, watch_.slope, watch_.du, options_.backtrack,
                               watch_.rnorm, u);
    if (s == 0.0) *u = watch_.u;
    return s;
  }
  if (admissible && Pi_full <= Pi + options_.armijo * slope) {
    *u = full;
    return 1.0;
  }
  if (admissible && options_.watchdog) {
    watch_ = {true, *u, du, Pi, slope, rnorm};
    *u = full;
    return 1.0;
  }
  return backtrack(*u, Pi, slope, du, 1.0, rnorm, u);
}

}  // namespace softhd::fe
