#pragma once
// The distributed discrete system of the PETSc state backend (internal): one rank's part's
// assembler (built without a serial sparsity pattern: element tangents go straight into the
// distributed matrix), the global free-dof numbering, the distributed tangent (MATAIJ), and
// the KSP that solves with it. Vectors cross this interface as Eigen vectors of the rank's owned
// rows (in global row order); reductions over ranks are done here.

#include <petscksp.h>

#include <Eigen/Core>
#include <memory>
#include <vector>

#include "partition.hpp"
#include "softhd/fe/assembly.hpp"
#include "softhd/fe/body.hpp"
#include "softhd/fe/state_backend.hpp"

namespace softhd::fe::petsc_detail {

/// Throws NumericalError naming the call if a PETSc call failed.
void check(PetscErrorCode code, const char* call);
#define SOFTHD_PETSC(call) ::softhd::fe::petsc_detail::check((call), #call)

/// What one linear solve did.
struct LinearSolveReport {
  bool ok = false;
  double shift = 0.0;    ///< μ of K + μ I (0 if none)
  int attempts = 0;      ///< factorisations (MUMPS) or preconditioner setups (GAMG)
  int krylov = 0;        ///< CG iterations over all attempts (0 for MUMPS)
  bool stalled = false;  ///< CG ran out of iterations (no shift is tried then)
  double seconds = 0.0;  ///< wall time
};

class DistributedSystem {
 public:
  DistributedSystem(const Body& body, StateBackend backend, int max_krylov_iterations);
  ~DistributedSystem();
  DistributedSystem(const DistributedSystem&) = delete;
  DistributedSystem& operator=(const DistributedSystem&) = delete;

  const Partition& part() const { return part_; }
  const Assembler& assembler() const { return *assembler_; }
  const FreeNumbering& numbering() const { return part_.numbering; }
  Eigen::Index owned() const {
    return static_cast<Eigen::Index>(part_.numbering.owned_local.size());
  }
  int block_size() const { return block_size_; }
  /// True for the iterative backend (CG + GAMG).
  bool iterative() const { return backend_ == StateBackend::kPetscGamg; }

  /// Π, R (owned rows) and/or the tangent (kept in the matrix) at the owned displacement
  /// u and the part's control m_qp; null outputs are skipped. Returns false (on every rank)
  /// if det F <= 0 at a quadrature point of any rank; *energy is then +inf.
  bool evaluate(const Eigen::VectorXd& u, const Eigen::MatrixXd& m_qp, double* energy,
                Eigen::VectorXd* residual, bool tangent);
  /// x with ‖K x − b‖ <= rtol ‖b‖ (GAMG; MUMPS solves directly), K the last assembled
  /// tangent, shifted to K + μ I if it is not positive definite and allow_shift is set
  /// (μ as in LinearSolver::factorize_shifted; K itself is left unshifted afterwards).
  LinearSolveReport solve(const Eigen::VectorXd& b, double rtol, bool allow_shift,
                          Eigen::VectorXd* x);

  /// The part's full displacement (its num_dofs, fixed entries zero) of owned values u.
  Eigen::VectorXd local_vector(const Eigen::VectorXd& u) const;
  ///@{
  /// Reductions over ranks.
  double dot(const Eigen::VectorXd& a, const Eigen::VectorXd& b) const;
  double norm(const Eigen::VectorXd& a) const { return std::sqrt(dot(a, a)); }
  double max_abs(const Eigen::VectorXd& a) const;
  double sum(double local) const;
  double min(double local) const;
  ///@}
  /// Starts the next shift search at μ = 0, as a new system would.
  void forget_shift() { last_shift_ = 0.0; }

 private:
  void create_matrix();
  /// Sums the per-local-node values `local` (local_rows_ order) into global_ over the
  /// ranks (reverse scatter with addition); the owned entries are then in global_.
  void add_to_global(const double* local);
  void create_solver();
  /// One attempt at K x = b (K possibly shifted); true if it succeeded.
  bool attempt(Vec b, Vec x, double rtol, LinearSolveReport* report);

  Partition part_;
  std::unique_ptr<Assembler> assembler_;
  StateBackend backend_;
  int max_krylov_iterations_;
  int block_size_ = 1;
  std::vector<PetscInt> local_rows_;  // global row of each local free dof
  Mat K_ = nullptr;
  Vec global_ = nullptr, global2_ = nullptr, local_ = nullptr;
  VecScatter to_local_ = nullptr;
  KSP ksp_ = nullptr;
  double last_shift_ = 0.0;
  bool matrix_assembled_ = false;
  bool mumps_configured_ = false;
};

}  // namespace softhd::fe::petsc_detail
