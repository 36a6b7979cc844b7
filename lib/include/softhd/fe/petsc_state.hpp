#pragma once
/// \file petsc_state.hpp
/// The state equation on PETSc, distributed over the ranks of PETSC_COMM_WORLD (built only
/// with SOFTHD_WITH_MPI=ON; docs/scaling.md §4-§8).
///
/// Partition (any body: a box or a Gmsh file's mesh): the elements are cut among the ranks by
/// recursive coordinate bisection of their centroids (on a box, between cell planes: slabs
/// on 2 ranks); each rank builds the assembler of its elements only (mesh, quadrature data,
/// materials and fibres of its regions) and assembles them into a distributed MATAIJ matrix
/// (block size dim when every node is free or wholly fixed). A node shared by several ranks
/// belongs to the lowest; rows are numbered rank by rank, each rank's nodes in coordinate
/// order along the first cut's axis, so that each rank owns one contiguous range.
///
/// Newton: the serial method of fe/newton.hpp (docs/formulation.md §3.6) on distributed
/// vectors: the same energy line search (the same EnergyLineSearch code, on each rank's
/// owned entries, with the energy summed over ranks), the same load stepping, path
/// predictor, forcing terms and convergence test (|R|₂ <= rtol R_ref + atol, and the step
/// test |Δu|_∞ <= displacement_tolerance |u|_∞). Linear solves by PETSc KSP:
///  - petsc-mumps: KSPPREONLY + PCCHOLESKY with MUMPS (symmetric LDLᵀ with pivoting); the
///    inertia of the factor says whether K is positive definite;
///  - petsc-gamg: CG on the true residual, preconditioned by GAMG with the rigid-body
///    near-null space; K is taken as not positive definite when CG reports negative
///    curvature (KSP_DIVERGED_INDEFINITE_MAT/PC) or does not converge.
/// A tangent that is not positive definite is shifted, K + μ I, with the shift sequence of
/// LinearSolver::factorize_shifted (no Newton–CG truncation, no reuse of a factorisation as
/// a preconditioner: each direction is a fresh solve). The adjoint solves with the tangent
/// at the converged state through the same KSP.
///
/// Contract: PETSc (and with it MPI) must be initialised by the program (PetscInitialize)
/// before a PetscStateSolver is made and finalised after the last one is destroyed; the
/// library never calls MPI_Init or PetscInitialize. Every member function is collective:
/// all ranks call it with the same arguments. PETSc options prefixed -softhd_state_ (e.g.
/// -softhd_state_ksp_monitor) reach the KSP.

#include <Eigen/Core>
#include <memory>

#include "softhd/fe/body.hpp"
#include "softhd/fe/grid_sequencing.hpp"
#include "softhd/fe/newton.hpp"
#include "softhd/fe/state_backend.hpp"
#include "softhd/fe/state_equation.hpp"

namespace softhd::fe {

/// Settings of PetscStateSolver; defaults per field.
struct PetscStateOptions {
  /// Newton settings (tangent.* are not used: the KSP below replaces the tangent solver).
  NewtonOptions newton;
  /// kPetscMumps or kPetscGamg.
  StateBackend backend = StateBackend::kPetscMumps;
  /// CG iterations allowed per solve (petsc-gamg) before K is treated as indefinite.
  int max_krylov_iterations = 2000;

  /// Throws InvalidArgument naming the first invalid field.
  void validate() const;
};

/// Sizes of the distributed problem as seen by one rank.
struct PetscStateLayout {
  int rank = 0;                     ///< this rank
  int size = 1;                     ///< the number of ranks
  int cut_axis = 0;                 ///< the first cut's axis (0 on one rank)
  Eigen::Index local_elements = 0;  ///< elements of this rank's part
  Eigen::Index owned_rows = 0;      ///< free dofs owned by this rank
  Eigen::Index global_rows = 0;     ///< free dofs of the whole mesh
  int block_size = 1;               ///< block size of the matrix
};

/// The state equation m ↦ u(m) of one body on PETSc, warm-started from the last solve, with
/// the adjoint gradient (the PETSc implementation of StateEquation, usually made by
/// make_state_solver). Collective on PETSC_COMM_WORLD.
class PetscStateSolver final : public StateEquation {
 public:
  /// Throws InvalidArgument for invalid options, a backend other than the PETSc ones, a mesh
  /// with fewer elements than ranks, or if PETSc is not initialised.
  explicit PetscStateSolver(const Body& body, PetscStateOptions options = {});
  ~PetscStateSolver() override;

  /// kPetscMumps or kPetscGamg.
  StateBackend backend() const override;
  /// Free dofs of the whole mesh.
  Eigen::Index free_dofs() const override;

  /// Equilibrium for the control m (the body's control space, all values on every rank),
  /// from the last converged state (rest at first). On failure the state stays at the last
  /// converged load step and the summary says why. Same summary fields as the serial
  /// Newton (factorizations: MUMPS factorisations or GAMG setups; krylov_iterations: CG).
  NewtonSummary solve(const Eigen::VectorXd& m) override;
  /// True if the last solve converged.
  bool converged() const override;
  /// Grid sequencing as in solve_forward (fe/grid_sequencing.hpp): the coarser levels of
  /// `body` (the one given at construction) are solved by the serial Newton on every rank
  /// (they are small), and their equilibrium, prolongated onto this rank's nodes, becomes
  /// the start of the next solve, with the control m at full load. With no level asked for,
  /// or if a coarse solve fails (reported), the start is the rest state.
  GridSequencingReport grid_sequenced_start(const Body& body, const Eigen::VectorXd& m,
                                            const GridSequencingOptions& options) override;
  /// The current state over the whole mesh, on every rank (gathered).
  State state() const override;
  /// Makes the whole-mesh `state` (the same on every rank) the start of the next solve:
  /// each rank takes its owned rows and its part's control.
  void set_state(const State& state) override;
  /// Forgets the path tangent and the last shift (the matrix and KSP objects are kept).
  void reset() override;

  /// The displacement of the whole mesh (num_nodes · dim, global dof order, fixed entries
  /// zero), on every rank.
  Eigen::VectorXd displacement() const override;
  /// The state part of dJ/dm (control-space size, on every rank) for g = ∂J/∂u given on
  /// every rank (num_nodes · dim): K λ = g with the converged tangent, then ∫ M_k (F a₀)·(∇λ
  /// a₀) dX. Throws InvalidArgument if the last solve did not converge, NumericalError if
  /// the solve fails.
  Eigen::VectorXd gradient(const Eigen::VectorXd& g) override;
  /// MUMPS factorisations or GAMG set-ups of the last gradient().
  int adjoint_factorizations() const override;
  /// w = (du/dm) v (StateEquation::sensitivity).
  Eigen::VectorXd sensitivity(const Eigen::VectorXd& v) override;
  /// The state's side of the reduced Hessian-vector product (StateEquation::hessian_product).
  Eigen::VectorXd hessian_product(const Eigen::VectorXd& v, const Eigen::VectorXd& w,
                                  const Eigen::VectorXd& q, HessianPart part) override;

  ///@{
  /// Π(u; m), ∫ J dX and min J at the current state, over the whole mesh.
  double energy() const override;
  double deformed_volume() const override;
  double min_jacobian() const override;
  ///@}
  /// The current control at the quadrature points, or det F there: E by nq over the whole
  /// mesh in global element order, on every rank.
  Eigen::MatrixXd control_at_quadrature() const;
  /// See control_at_quadrature.
  Eigen::MatrixXd jacobians() const override;

  /// Sizes of the partition.
  PetscStateLayout layout() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace softhd::fe
