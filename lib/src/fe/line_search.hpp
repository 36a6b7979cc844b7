#pragma once
// The energy line search of Newton's method (internal to newton.cpp): Armijo backtracking
// on Π that never accepts det F <= 0, with a nonmonotone (watchdog) step.

#include <Eigen/Core>
#include <functional>

#include "softhd/fe/newton.hpp"

namespace softhd::fe {

class EnergyLineSearch {
 public:
  /// energy(u, &Π) returns false (inadmissible) if det F <= 0 somewhere;
  /// residual_norm(u) = |R(u)|₂.
  EnergyLineSearch(const NewtonOptions& options,
                   std::function<bool(const Eigen::VectorXd&, double*)> energy,
                   std::function<double(const Eigen::VectorXd&)> residual_norm)
      : options_(options), energy_(std::move(energy)), residual_norm_(std::move(residual_norm)) {}

  /// Moves *u along du: Π at *u is Pi, slope = R·du (< 0 for descent), rnorm = |R(*u)|.
  /// Returns the accepted step length (1 for a full or tentative step), or 0 if none was
  /// found; *u is then unchanged (or back at the watchdog's saved point).
  double step(const Eigen::VectorXd& du, double Pi, double slope, double rnorm, Eigen::VectorXd* u);
  /// True if the last step was taken tentatively (the watchdog is waiting).
  bool tentative() const { return watch_.active; }
  /// Drops a pending tentative step's bookkeeping (a new load step starts).
  void reset() { watch_.active = false; }

 private:
  /// Armijo backtracking from u0 along du from step s.
  double backtrack(const Eigen::VectorXd& u0, double Pi0, double slope, const Eigen::VectorXd& du,
                   double s, double rnorm, Eigen::VectorXd* u) const;

  const NewtonOptions& options_;
  std::function<bool(const Eigen::VectorXd&, double*)> energy_;
  std::function<double(const Eigen::VectorXd&)> residual_norm_;
  // Watchdog: a full step that raises the energy but keeps det F > 0 is taken tentatively;
  // if the next full step does not end below the Armijo line of the saved point, both are
  // undone and the saved step backtracks. Thin bodies need it: the full Newton step bends
  // them correctly but leaves second-order membrane strains the next iteration removes.
  struct Watch {
    bool active = false;
    Eigen::VectorXd u, du;
    double Pi = 0.0, slope = 0.0, rnorm = 0.0;
  } watch_;
};

}  // namespace softhd::fe
