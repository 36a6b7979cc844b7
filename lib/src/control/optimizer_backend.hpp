#pragma once
/// \file optimizer_backend.hpp
/// The two implementations behind minimise() (internal): NLopt (bounded_optimizer.cpp) and
/// ROL's trust-region Newton–CG (rol_newton.cpp, the only file that includes Trilinos).
/// minimise() picks one by the algorithm; nothing else branches on which.

#include <functional>

#include "softhd/control/bounded_optimizer.hpp"

namespace softhd::detail {

using IterationObserver = std::function<void(const IterationRecord&, const Eigen::VectorXd&)>;

/// One call of minimise(), checked by check_problem.
struct BoundedProblem {
  const BoundedObjective& objective;
  const BoundedHessVec& hess_vec;  ///< may be empty
  const Eigen::VectorXd& x0;
  const Eigen::VectorXd& lower;
  const Eigen::VectorXd& upper;
  const BoundedOptimizerOptions& options;
  const IterationObserver& on_iteration;  ///< may be empty
};

/// An optimiser for a checked problem.
class OptimizerBackend {
 public:
  virtual ~OptimizerBackend() = default;
  /// minimise()'s contract for this backend's algorithms.
  virtual BoundedOptimizerSummary minimise(const BoundedProblem& problem) const = 0;
};

const OptimizerBackend& nlopt_backend();  ///< mma, ccsaq, lbfgs, slsqp
const OptimizerBackend& rol_backend();    ///< newton

/// Why a backend's own stopping tests ended a run; none: the algorithm ended it by itself.
enum class Stop {
  none,
  iterations,
  evaluations,
  relative_change,
  gradient,
  target,
  time,
  requested,
  radius,  ///< the trust radius fell below its minimum (ROL)
  hessian  ///< a Hessian-vector product failed (ROL)
};

/// Sets s->status and s->termination (one line) for a stop of ours and returns true; returns
/// false, s unchanged, for Stop::none.
bool set_stop(Stop stop, BoundedOptimizerSummary* s);

/// Throws InvalidArgument for options, bounds or a start the optimiser cannot take.
void check_problem(const Eigen::VectorXd& x0, const Eigen::VectorXd& lower,
                   const Eigen::VectorXd& upper, const BoundedOptimizerOptions& options);

}  // namespace softhd::detail
