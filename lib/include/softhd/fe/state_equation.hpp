#pragma once
/// \file state_equation.hpp
/// The state equation R(u; m) = 0 as the control layer and the CLI see it, whatever engine
/// solves it (docs/formulation.md §4, docs/scaling.md §4): a control vector m in, the
/// equilibrium displacement out, warm-started from a state the caller sets or from the last
/// solve, and the adjoint gradient for any ∂J/∂u at the converged state.
///
/// Two implementations, made by make_state_solver() from a StateBackend:
///  - StateSolver (fe/state_solver.hpp): the serial Newton with CHOLMOD factorisations;
///  - PetscStateSolver (fe/petsc_state.hpp, SOFTHD_WITH_MPI builds): the distributed Newton
///    on PETSc, every member collective over PETSC_COMM_WORLD.
/// Vectors crossing this interface are always whole-mesh ones (global node and element
/// order) and equal on every rank, so code above it never depends on the partition.

#include <Eigen/Core>
#include <functional>
#include <memory>

#include "softhd/fe/assembly.hpp"
#include "softhd/fe/body.hpp"
#include "softhd/fe/control.hpp"
#include "softhd/fe/grid_sequencing.hpp"
#include "softhd/fe/newton.hpp"
#include "softhd/fe/state_backend.hpp"
#include "softhd/hessian_part.hpp"

namespace softhd::fe {

/// The state equation m ↦ u(m) of one body, with warm starts and the adjoint gradient.
/// With a PETSc backend every member is collective (all ranks call it, same arguments).
class StateEquation {
 public:
  virtual ~StateEquation();
  StateEquation() = default;
  StateEquation(const StateEquation&) = delete;
  StateEquation& operator=(const StateEquation&) = delete;

  /// The engine.
  virtual StateBackend backend() const = 0;
  /// Free dofs of the whole mesh.
  virtual Eigen::Index free_dofs() const = 0;

  /// Equilibrium for the control m (one value per control of the body), Newton started
  /// from the current state (the last solve's, or the one set_state gave). On failure the
  /// state stays at the last converged load step and the summary says why.
  virtual NewtonSummary solve(const Eigen::VectorXd& m) = 0;
  /// True if the last solve converged (gradient() is then available).
  virtual bool converged() const = 0;
  /// The current displacement of the whole mesh (num_nodes · dim, fixed entries zero).
  virtual Eigen::VectorXd displacement() const = 0;
  /// The current state: displacement and control at the quadrature points, whole mesh.
  virtual State state() const = 0;
  /// Makes `state` (whole mesh, the shapes state() returns) the start of the next solve.
  /// Throws InvalidArgument for the wrong shapes.
  virtual void set_state(const State& state) = 0;
  /// Grid sequencing (fe/grid_sequencing.hpp) for the control m of `body` (the one the
  /// solver was made for): the current state becomes the prolongated coarse equilibrium
  /// with m at full load (the rest state if no level is asked for or a coarse solve fails).
  virtual GridSequencingReport grid_sequenced_start(const Body& body, const Eigen::VectorXd& m,
                                                    const GridSequencingOptions& options) = 0;
  /// Forgets what the solver keeps between solves besides the state (factorisations, the
  /// path tangent), as a newly made solver; the next solve starts from the current state.
  virtual void reset() = 0;

  /// The state part of dJ/dm (one value per control) for g = ∂J/∂u (num_nodes · dim):
  /// K λ = g with the converged tangent, then ∫ M_k (F a₀)·(∇λ a₀) dX. Throws
  /// InvalidArgument if the last solve did not converge.
  virtual Eigen::VectorXd gradient(const Eigen::VectorXd& g) = 0;
  /// Numeric factorisations (or preconditioner set-ups) made by the last gradient().
  virtual int adjoint_factorizations() const = 0;

  ///@{
  /// The state's side of the reduced Hessian-vector product of J(m) = F(u(m), m)
  /// (docs/formulation.md §4.4.1), at the converged state of the last solve and the adjoint λ
  /// of the gradient() made there, reusing the tangent's kept factorisation (no new one).
  /// Both throw InvalidArgument if the last solve did not converge, if no gradient() followed
  /// it, or for vectors of the wrong size.
  ///
  /// w = (du/dm) v for a control direction v (one value per control): K w = −(∂R/∂m) v
  /// (num_nodes · dim, fixed entries zero).
  virtual Eigen::VectorXd sensitivity(const Eigen::VectorXd& v) = 0;
  /// s (one value per control) such that H v = ∂²F/∂m² v + ∂²F/∂m∂u w + s, given v, w =
  /// sensitivity(v) and q = ∂²F/∂u² w + ∂²F/∂u∂m v (num_nodes · dim): the incremental adjoint
  /// μ from K μ = q − [the λ-weighted state's ∂²/∂u² w and ∂²/∂u∂m v], then s = the (∂R/∂m)ᵀ μ
  /// term − [the λ-weighted state's ∂²/∂m∂u w], with gradient()'s sign convention.
  /// HessianPart::gauss_newton drops the bracketed terms (then H v = Sᵀ F_uu S v with
  /// S = du/dm when F has no m–u cross term).
  virtual Eigen::VectorXd hessian_product(const Eigen::VectorXd& v, const Eigen::VectorXd& w,
                                          const Eigen::VectorXd& q, HessianPart part) = 0;
  ///@}

  ///@{
  /// Π(u; m), ∫ J dX and min J at the current state, over the whole mesh.
  virtual double energy() const = 0;
  virtual double deformed_volume() const = 0;
  virtual double min_jacobian() const = 0;
  ///@}
  /// det F at the quadrature points of the current state (elements by points, whole mesh).
  virtual Eigen::MatrixXd jacobians() const = 0;
};

/// Settings of make_state_solver(); defaults per field.
struct StateSolverOptions {
  StateBackend backend = StateBackend::kCholmod;  ///< the engine
  /// Newton settings (the PETSc backends ignore tangent.*: their KSP replaces it).
  NewtonOptions newton;
  /// petsc-gamg: CG iterations allowed per solve before K is treated as indefinite.
  int max_krylov_iterations = 2000;

  /// Throws InvalidArgument naming the first invalid field.
  void validate() const;
};

/// The state solver of `options.backend` for `body` (which must outlive it).
/// The serial one uses `assembler` and `control` (the body's, whole mesh) if given — they
/// must then outlive it — and else makes its own; the PETSc ones build their part of
/// the body themselves and ignore them. Throws InvalidArgument for invalid options, and for a
/// PETSc backend in a build without SOFTHD_WITH_MPI or before PETSc is initialised. A zero
/// options.newton.absolute_tolerance is replaced by body.residual_floor(), so
/// that a zero or tiny control converges at once instead of chasing round-off.
std::unique_ptr<StateEquation> make_state_solver(const Body& body,
                                                 const StateSolverOptions& options,
                                                 const Assembler* assembler = nullptr,
                                                 const ControlSpace* control = nullptr);

/// Makes state solvers for given Newton settings (ShapeObjective fills in its tolerance).
using StateSolverFactory = std::function<std::unique_ptr<StateEquation>(const NewtonOptions&)>;

/// make_state_solver(body, {backend, newton}, assembler, control) for each Newton setting;
/// body, assembler and control must outlive every solver made.
StateSolverFactory state_solver_factory(const Body& body, StateBackend backend,
                                        const Assembler* assembler = nullptr,
                                        const ControlSpace* control = nullptr);

}  // namespace softhd::fe
