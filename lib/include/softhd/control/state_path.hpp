#pragma once
/// \file state_path.hpp
/// The states the shape objective solves for, one control after another (docs/formulation.md
/// §4.7): the state equation m ↦ u(m) (any backend) started from the kept converged state whose
/// control is nearest, or, after a large step, from the two-level start (a coarse body solved
/// at the warm start's control and at m, their difference prolongated); the converged states
/// kept for warm starts (what a checkpoint saves); and the adjoint solve with the converged
/// tangent. Second-order solves (incremental state and adjoint) belong here too.

#include <Eigen/Core>
#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <vector>

#include "softhd/fe/assembly.hpp"
#include "softhd/fe/control.hpp"
#include "softhd/fe/newton.hpp"
#include "softhd/fe/state_equation.hpp"

namespace softhd {

/// A converged state kept for warm starts, with its control (empty for the rest state).
struct WarmStart {
  Eigen::VectorXd m;  ///< the control (empty for the rest state)
  fe::State state;    ///< its converged state
};

/// One state solve: Newton's summary of the last solve, and the Newton iterations and
/// factorisations of all solves made for it (a failed two-level start included).
struct StateSolve {
  fe::NewtonSummary summary;  ///< the last solve's
  int newton_iterations = 0;  ///< of every fine solve made
  int factorizations = 0;     ///< of every fine solve made
};

/// The state path of one body and control space. Not thread-safe.
class StatePath {
 public:
  /// The assembler and control space must outlive the path; `solver` solves their body.
  /// Keeps at most `warm_start_states` (≥ 1) converged states; with a coarse level the
  /// two-level start is used when the coarse solve to the new control needs at least
  /// `coarse_correction_iterations` Newton iterations.
  StatePath(const fe::Assembler& assembler, const fe::ControlSpace& control,
            std::unique_ptr<fe::StateEquation> solver, const fe::NewtonOptions& newton,
            int warm_start_states, int coarse_correction_iterations);
  ~StatePath();

  /// The equilibrium for m in *state (converged or not), started as the file's comment says.
  StateSolve solve(const Eigen::VectorXd& m, fe::State* state);
  /// The state part of dJ/dm for g = ∂J/∂u at the last converged solve (fe::StateEquation::
  /// gradient); adds the adjoint's factorisations to *factorizations.
  Eigen::VectorXd adjoint(const Eigen::VectorXd& g, int* factorizations);
  /// The solve at m from `converged`, a state already converged for m (0 Newton iterations,
  /// or 1 at most): puts the solver back at an earlier point (e.g. the Hessian's, after a
  /// rejected trial moved it) without adding a warm start.
  StateSolve resolve(const Eigen::VectorXd& m, const fe::State& converged, fe::State* state);
  ///@{
  /// The state's side of the reduced Hessian-vector product at the last converged solve and
  /// the adjoint made there: fe::StateEquation::sensitivity and
  /// fe::StateEquation::hessian_product.
  Eigen::VectorXd sensitivity(const Eigen::VectorXd& v);
  Eigen::VectorXd hessian_product(const Eigen::VectorXd& v, const Eigen::VectorXd& w,
                                  const Eigen::VectorXd& q, HessianPart part);
  ///@}
  /// Changes at every solve, reset and restore: a caller that keeps what goes with the
  /// solver's current state (the Hessian point's adjoint) tells whether it still holds.
  std::uint64_t generation() const { return generation_; }

  /// The warm-start states, most recent first (the rest state last until it is pushed out).
  const std::deque<WarmStart>& warm_starts() const { return cache_; }
  /// The last converged state (the rest state before any solve).
  const fe::State& last_state() const { return cache_.front().state; }
  /// Puts a converged state for the control m first among the warm starts (e.g. the best
  /// one, so that solving m again starts, and stays, exactly there).
  void remember(const Eigen::VectorXd& m, const fe::State& state);
  /// Replaces the warm-start states (e.g. from a checkpoint), so that the next solve is
  /// bitwise the one an uninterrupted run would make. Throws InvalidArgument if the list is
  /// empty, longer than warm_start_states, or a size does not fit the problem.
  void restore(const std::vector<WarmStart>& states);

  /// Two-level starts: `coarse` is the same body on a coarser mesh (e.g. a MeshHierarchy
  /// level); it must outlive the path.
  void use_coarse_level(const fe::Assembler& coarse);
  /// The coarse body of use_coarse_level, or null.
  const fe::Assembler* coarse_level() const { return coarse_; }
  /// Forgets what the solver keeps between solves (factorisations, path tangent) and the
  /// coarse level's states: later solves then depend on earlier ones only through the warm
  /// starts, which a checkpoint can save. Costs a factorisation at the next solve.
  void reset();

 private:
  const WarmStart& nearest(const Eigen::VectorXd& m) const;
  fe::NewtonSummary solve_from(const fe::State& start, const Eigen::VectorXd& m, fe::State* state);
  bool coarse_corrected(const Eigen::VectorXd& m, const WarmStart& warm, fe::State* start,
                        int* iterations);
  bool kept_coarse_state(const Eigen::VectorXd& m, fe::State* state) const;
  Eigen::MatrixXd coarse_control(const Eigen::VectorXd& m) const;

  const fe::Assembler& assembler_;
  const fe::ControlSpace& control_;
  std::unique_ptr<fe::StateEquation> solver_;
  fe::NewtonOptions newton_;
  int warm_start_states_;
  int coarse_correction_iterations_;
  std::deque<WarmStart> cache_;  // most recent first
  const fe::Assembler* coarse_ = nullptr;
  std::optional<fe::NewtonSolver> coarse_newton_;
  bool coarse_active_ = true;           // false after a small step, until a hard fine solve
  std::deque<WarmStart> coarse_cache_;  // coarse equilibria by control, most recent first
  std::uint64_t generation_ = 0;        // see generation()
};

}  // namespace softhd
