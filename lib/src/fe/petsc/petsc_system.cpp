#include "petsc_system.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>

#include "softhd/error.hpp"

namespace softhd::fe::petsc_detail {

void check(PetscErrorCode code, const char* call) {
  if (code != 0)
    throw NumericalError("PETSc state: " + std::string(call) + " failed (PETSc error " +
                         std::to_string(static_cast<int>(code)) + ")");
}

namespace {

MPI_Comm comm() { return PETSC_COMM_WORLD; }

int comm_rank() {
  int r = 0;
  MPI_Comm_rank(comm(), &r);
  return r;
}

int comm_size() {
  int s = 1;
  MPI_Comm_size(comm(), &s);
  return s;
}

Partition checked_partition(const Body& body) {
  PetscBool initialised = PETSC_FALSE;
  PetscInitialized(&initialised);
  if (!initialised)
    throw InvalidArgument("PETSc state: PETSc is not initialised (call PetscInitialize first)");
  return make_partition(body, comm_rank(), comm_size());
}

}  // namespace

DistributedSystem::DistributedSystem(const Body& body, StateBackend backend,
                                     int max_krylov_iterations)
    : part_(checked_partition(body)),
      assembler_(std::make_unique<Assembler>(part_.mesh, body.materials, part_.fibers,
                                             body.constraints, AssemblerStorage::kLean,
                                             body.quadrature_degree)),
      backend_(backend),
      max_krylov_iterations_(max_krylov_iterations),
      local_rows_(part_.numbering.local_to_global.begin(), part_.numbering.local_to_global.end()) {
  SOFTHD_ASSERT(assembler_->dofs().num_free == static_cast<Eigen::Index>(local_rows_.size()),
                "PETSc state: the assembler's free dofs differ from the partition's");
  int whole = numbering().whole_nodes ? 1 : 0, all_whole = 0;
  MPI_Allreduce(&whole, &all_whole, 1, MPI_INT, MPI_MIN, comm());
  block_size_ = all_whole ? body.dim() : 1;
  const auto n = static_cast<PetscInt>(owned());
  const auto N = static_cast<PetscInt>(numbering().num_global);
  SOFTHD_PETSC(VecCreate(comm(), &global_));
  SOFTHD_PETSC(VecSetSizes(global_, n, N));
  SOFTHD_PETSC(VecSetBlockSize(global_, block_size_));
  SOFTHD_PETSC(VecSetType(global_, VECSTANDARD));
  SOFTHD_PETSC(VecDuplicate(global_, &global2_));
  const auto nl = static_cast<PetscInt>(local_rows_.size());
  SOFTHD_PETSC(VecCreateSeq(PETSC_COMM_SELF, nl, &local_));
  IS is = nullptr;
  SOFTHD_PETSC(ISCreateGeneral(PETSC_COMM_SELF, nl, local_rows_.data(), PETSC_COPY_VALUES, &is));
  SOFTHD_PETSC(VecScatterCreate(global_, is, local_, nullptr, &to_local_));
  SOFTHD_PETSC(ISDestroy(&is));
  create_matrix();
  create_solver();
}

DistributedSystem::~DistributedSystem() {
  KSPDestroy(&ksp_);
  MatDestroy(&K_);
  VecScatterDestroy(&to_local_);
  VecDestroy(&local_);
  VecDestroy(&global2_);
  VecDestroy(&global_);
}

void DistributedSystem::add_to_global(const double* local) {
  PetscInt n = 0;
  SOFTHD_PETSC(VecGetLocalSize(local_, &n));
  PetscScalar* a = nullptr;
  SOFTHD_PETSC(VecGetArray(local_, &a));
  std::copy(local, local + n, a);
  SOFTHD_PETSC(VecRestoreArray(local_, &a));
  SOFTHD_PETSC(VecZeroEntries(global_));
  SOFTHD_PETSC(VecScatterBegin(to_local_, local_, global_, ADD_VALUES, SCATTER_REVERSE));
  SOFTHD_PETSC(VecScatterEnd(to_local_, local_, global_, ADD_VALUES, SCATTER_REVERSE));
}

void DistributedSystem::create_matrix() {
  // Exact nonzero counts per owned row, from the whole mesh (make_partition).
  const auto n = static_cast<PetscInt>(owned());
  const auto N = static_cast<PetscInt>(numbering().num_global);
  const std::vector<PetscInt> dnz(numbering().diagonal_nonzeros.begin(),
                                  numbering().diagonal_nonzeros.end());
  const std::vector<PetscInt> onz(numbering().off_diagonal_nonzeros.begin(),
                                  numbering().off_diagonal_nonzeros.end());
  SOFTHD_PETSC(MatCreate(comm(), &K_));
  SOFTHD_PETSC(MatSetSizes(K_, n, n, N, N));
  SOFTHD_PETSC(MatSetBlockSize(K_, block_size_));
  SOFTHD_PETSC(MatSetType(K_, MATAIJ));
  SOFTHD_PETSC(MatSeqAIJSetPreallocation(K_, 0, dnz.data()));
  SOFTHD_PETSC(MatMPIAIJSetPreallocation(K_, 0, dnz.data(), 0, onz.data()));
  SOFTHD_PETSC(MatSetOption(K_, MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_TRUE));
  SOFTHD_PETSC(MatSetOption(K_, MAT_SYMMETRIC, PETSC_TRUE));
  SOFTHD_PETSC(MatSetOption(K_, MAT_SYMMETRY_ETERNAL, PETSC_TRUE));
}

namespace {

// The rigid-body modes on the owned rows: MatNullSpaceCreateRigidBody on the node
// coordinates when every node is wholly free or fixed (block size dim), else built here
// (translations and rotations restricted to the free dofs) and orthonormalised.
MatNullSpace rigid_body_modes(const DistributedSystem& s, Vec layout) {
  const int dim = s.part().mesh.dim;
  const DofMap& dofs = s.assembler().dofs();
  const std::vector<int>& owned = s.numbering().owned_local;
  auto coordinate = [&](size_t i, int* comp) {
    const Eigen::Index dof = dofs.free_dofs[owned[i]];
    *comp = static_cast<int>(dof % dim);
    return s.part().mesh.nodes.row(dof / dim);
  };
  MatNullSpace space = nullptr;
  if (s.block_size() == dim) {
    Vec coords = nullptr;
    SOFTHD_PETSC(VecDuplicate(layout, &coords));
    PetscScalar* c = nullptr;
    SOFTHD_PETSC(VecGetArray(coords, &c));
    int comp = 0;
    for (size_t i = 0; i < owned.size(); ++i) c[i] = coordinate(i, &comp)[comp];
    SOFTHD_PETSC(VecRestoreArray(coords, &c));
    SOFTHD_PETSC(MatNullSpaceCreateRigidBody(coords, &space));
    SOFTHD_PETSC(VecDestroy(&coords));
    return space;
  }
  const int nmodes = dim == 3 ? 6 : 3;
  std::vector<Vec> modes(nmodes);
  for (int k = 0; k < nmodes; ++k) {
    SOFTHD_PETSC(VecDuplicate(layout, &modes[k]));
    PetscScalar* v = nullptr;
    SOFTHD_PETSC(VecGetArray(modes[k], &v));
    for (size_t i = 0; i < owned.size(); ++i) {
      int c = 0;
      const Eigen::VectorXd X = coordinate(i, &c);
      // Translations 0..dim-1, then rotations about z (and in 3D about x and y).
      const int r = k - dim;
      const int p = r == 0 ? 0 : r == 1 ? 1 : 2, q = r == 0 ? 1 : r == 1 ? 2 : 0;
      v[i] = k < dim ? (c == k ? 1.0 : 0.0) : c == p ? -X[q] : c == q ? X[p] : 0.0;
    }
    SOFTHD_PETSC(VecRestoreArray(modes[k], &v));
    for (int l = 0; l < k; ++l) {  // modified Gram–Schmidt
      PetscScalar dot = 0.0;
      SOFTHD_PETSC(VecDot(modes[k], modes[l], &dot));
      SOFTHD_PETSC(VecAXPY(modes[k], -dot, modes[l]));
    }
    SOFTHD_PETSC(VecNormalize(modes[k], nullptr));
  }
  SOFTHD_PETSC(MatNullSpaceCreate(comm(), PETSC_FALSE, nmodes, modes.data(), &space));
  for (Vec& v : modes) SOFTHD_PETSC(VecDestroy(&v));
  return space;
}

}  // namespace

void DistributedSystem::create_solver() {
  SOFTHD_PETSC(KSPCreate(comm(), &ksp_));
  SOFTHD_PETSC(KSPSetOperators(ksp_, K_, K_));
  SOFTHD_PETSC(KSPSetOptionsPrefix(ksp_, "softhd_state_"));
  PC pc = nullptr;
  SOFTHD_PETSC(KSPGetPC(ksp_, &pc));
  if (backend_ == StateBackend::kPetscMumps) {
    SOFTHD_PETSC(KSPSetType(ksp_, KSPPREONLY));
    SOFTHD_PETSC(PCSetType(pc, PCCHOLESKY));
    SOFTHD_PETSC(PCFactorSetMatSolverType(pc, MATSOLVERMUMPS));
  } else {
    SOFTHD_PETSC(KSPSetType(ksp_, KSPCG));
    SOFTHD_PETSC(KSPSetNormType(ksp_, KSP_NORM_UNPRECONDITIONED));
    SOFTHD_PETSC(PCSetType(pc, PCGAMG));
    MatNullSpace space = rigid_body_modes(*this, global_);
    SOFTHD_PETSC(MatSetNearNullSpace(K_, space));
    SOFTHD_PETSC(MatNullSpaceDestroy(&space));
  }
  SOFTHD_PETSC(KSPSetFromOptions(ksp_));
}

Eigen::VectorXd DistributedSystem::local_vector(const Eigen::VectorXd& u) const {
  PetscScalar* g = nullptr;
  SOFTHD_PETSC(VecGetArray(global_, &g));
  std::copy(u.data(), u.data() + u.size(), g);
  SOFTHD_PETSC(VecRestoreArray(global_, &g));
  SOFTHD_PETSC(VecScatterBegin(to_local_, global_, local_, INSERT_VALUES, SCATTER_FORWARD));
  SOFTHD_PETSC(VecScatterEnd(to_local_, global_, local_, INSERT_VALUES, SCATTER_FORWARD));
  const PetscScalar* l = nullptr;
  SOFTHD_PETSC(VecGetArrayRead(local_, &l));
  const Eigen::VectorXd out = assembler_->dofs().expand(
      Eigen::Map<const Eigen::VectorXd>(l, static_cast<Eigen::Index>(local_rows_.size())));
  SOFTHD_PETSC(VecRestoreArrayRead(local_, &l));
  return out;
}

double DistributedSystem::sum(double local) const {
  double out = 0.0;
  MPI_Allreduce(&local, &out, 1, MPI_DOUBLE, MPI_SUM, comm());
  return out;
}

double DistributedSystem::min(double local) const {
  double out = 0.0;
  MPI_Allreduce(&local, &out, 1, MPI_DOUBLE, MPI_MIN, comm());
  return out;
}

double DistributedSystem::dot(const Eigen::VectorXd& a, const Eigen::VectorXd& b) const {
  return sum(a.dot(b));
}

double DistributedSystem::max_abs(const Eigen::VectorXd& a) const {
  return -min(a.size() ? -a.lpNorm<Eigen::Infinity>() : 0.0);
}

namespace {

// Adds element tangents into the distributed matrix, each element's full nd by nd block
// (fixed dofs get row and column -1, which PETSc ignores). Entries of rows owned by another
// rank are stashed by PETSc and sent at MatAssemblyBegin.
class MatrixSink final : public ElementMatrixSink {
 public:
  MatrixSink(Mat K, const Assembler& assembler, const std::vector<PetscInt>& rows)
      : K_(K),
        mesh_(assembler.mesh()),
        dofs_(assembler.dofs()),
        rows_(rows),
        index_(static_cast<size_t>(mesh_.nodes_per_element()) * mesh_.dim) {}

  void add(Eigen::Index first, Eigen::Index count, const double* Ke) override {
    const int dim = mesh_.dim, nen = mesh_.nodes_per_element(), nd = nen * dim;
    for (Eigen::Index i = 0; i < count; ++i) {
      for (int a = 0; a < nen; ++a)
        for (int k = 0; k < dim; ++k) {
          const int f = dofs_.free_index[mesh_.elements(first + i, a) * dim + k];
          index_[a * dim + k] = f >= 0 ? rows_[f] : -1;
        }
      SOFTHD_PETSC(MatSetValues(K_, nd, index_.data(), nd, index_.data(),
                                Ke + i * nd * static_cast<Eigen::Index>(nd), ADD_VALUES));
    }
  }

 private:
  Mat K_;
  const Mesh& mesh_;
  const DofMap& dofs_;
  const std::vector<PetscInt>& rows_;
  std::vector<PetscInt> index_;
};

}  // namespace

bool DistributedSystem::evaluate(const Eigen::VectorXd& u, const Eigen::MatrixXd& m_qp,
                                 double* energy, Eigen::VectorXd* residual, bool tangent) {
  const Eigen::VectorXd ul = local_vector(u);
  double e = 0.0;
  Eigen::VectorXd r;
  MatrixSink sink(K_, *assembler_, local_rows_);
  if (tangent && matrix_assembled_) SOFTHD_PETSC(MatZeroEntries(K_));
  const bool ok = assembler_->evaluate_elements(ul, m_qp, &e, residual ? &r : nullptr,
                                                tangent ? &sink : nullptr);
  if (tangent) {  // collective: every rank assembles, whatever its elements did
    SOFTHD_PETSC(MatAssemblyBegin(K_, MAT_FINAL_ASSEMBLY));
    SOFTHD_PETSC(MatAssemblyEnd(K_, MAT_FINAL_ASSEMBLY));
    matrix_assembled_ = true;
  }
  if (min(ok ? 1.0 : 0.0) == 0.0) {  // det F <= 0 on some rank
    if (energy) *energy = std::numeric_limits<double>::infinity();
    return false;
  }
  if (energy) *energy = sum(e);
  if (residual) {
    add_to_global(r.data());
    const PetscScalar* g = nullptr;
    SOFTHD_PETSC(VecGetArrayRead(global_, &g));
    *residual = Eigen::Map<const Eigen::VectorXd>(g, owned());
    SOFTHD_PETSC(VecRestoreArrayRead(global_, &g));
  }
  return true;
}

bool DistributedSystem::attempt(Vec b, Vec x, double rtol, LinearSolveReport* report) {
  ++report->attempts;
  KSPConvergedReason reason = KSP_CONVERGED_ITERATING;
  // The matrix changed (assembled or shifted): KSPSetUp alone would keep the old
  // preconditioner once set up without a KSPSolve in between.
  SOFTHD_PETSC(KSPSetOperators(ksp_, K_, K_));
  if (backend_ == StateBackend::kPetscMumps) {
    PC pc = nullptr;
    SOFTHD_PETSC(KSPGetPC(ksp_, &pc));
    if (!mumps_configured_) {
      // ICNTL(13) = 1: the root front is factorised on one process, so that the inertia
      // (the count of negative pivots of LDLᵀ) is available in parallel; ICNTL(24) = 1:
      // null pivots are detected (and counted as zero eigenvalues).
      Mat F = nullptr;
      SOFTHD_PETSC(PCFactorSetUpMatSolverType(pc));
      SOFTHD_PETSC(PCFactorGetMatrix(pc, &F));
      SOFTHD_PETSC(MatMumpsSetIcntl(F, 13, 1));
      SOFTHD_PETSC(MatMumpsSetIcntl(F, 24, 1));
      mumps_configured_ = true;
    }
    SOFTHD_PETSC(KSPSetUp(ksp_));
    PCFailedReason failed = PC_NOERROR;
    SOFTHD_PETSC(PCGetFailedReasonRank(pc, &failed));
    double bad = failed != PC_NOERROR ? 1.0 : 0.0;
    if (sum(bad) != 0.0) return false;
    Mat F = nullptr;
    SOFTHD_PETSC(PCFactorGetMatrix(pc, &F));
    PetscInt nneg = 0, nzero = 0, npos = 0;
    SOFTHD_PETSC(MatGetInertia(F, &nneg, &nzero, &npos));
    if (nneg != 0 || nzero != 0) return false;
    SOFTHD_PETSC(KSPSolve(ksp_, b, x));
    SOFTHD_PETSC(KSPGetConvergedReason(ksp_, &reason));
    return reason > 0;
  }
  SOFTHD_PETSC(KSPSetTolerances(ksp_, rtol, 0.0, PETSC_DEFAULT, max_krylov_iterations_));
  SOFTHD_PETSC(KSPSolve(ksp_, b, x));
  PetscInt its = 0;
  SOFTHD_PETSC(KSPGetIterationNumber(ksp_, &its));
  report->krylov += static_cast<int>(its);
  SOFTHD_PETSC(KSPGetConvergedReason(ksp_, &reason));
  // Negative curvature says K (or the preconditioner) is not positive definite: shift.
  // Running out of iterations is a failure a shift would not cure.
  if (reason == KSP_DIVERGED_ITS) report->stalled = true;
  return reason > 0;
}

LinearSolveReport DistributedSystem::solve(const Eigen::VectorXd& b, double rtol, bool allow_shift,
                                           Eigen::VectorXd* x) {
  const auto t0 = std::chrono::steady_clock::now();
  LinearSolveReport report;
  PetscScalar* a = nullptr;
  SOFTHD_PETSC(VecGetArray(global_, &a));
  std::copy(b.data(), b.data() + b.size(), a);
  SOFTHD_PETSC(VecRestoreArray(global_, &a));
  // The shift sequence of LinearSolver::factorize_shifted.
  Vec diagonal = nullptr;
  SOFTHD_PETSC(VecDuplicate(global_, &diagonal));
  SOFTHD_PETSC(MatGetDiagonal(K_, diagonal));
  PetscReal dmax = 0.0;
  SOFTHD_PETSC(VecNorm(diagonal, NORM_INFINITY, &dmax));
  SOFTHD_PETSC(VecDestroy(&diagonal));
  double shift = last_shift_ > 0.0 ? 0.01 * last_shift_ : 0.0, applied = 0.0;
  if (shift < 1e-8 * dmax || !allow_shift) shift = 0.0;
  for (int k = 0; k <= (allow_shift ? 20 : 0) && !report.ok && !report.stalled; ++k) {
    if (k > 0) shift = shift > 0.0 ? 10.0 * shift : 1e-8 * dmax;
    if (shift != applied) SOFTHD_PETSC(MatShift(K_, shift - applied));
    applied = shift;
    report.ok = attempt(global_, global2_, rtol, &report);
  }
  if (applied != 0.0) SOFTHD_PETSC(MatShift(K_, -applied));
  last_shift_ = report.ok ? shift : 0.0;
  report.shift = report.ok ? shift : std::numeric_limits<double>::infinity();
  if (report.ok) {
    const PetscScalar* v = nullptr;
    SOFTHD_PETSC(VecGetArrayRead(global2_, &v));
    *x = Eigen::Map<const Eigen::VectorXd>(v, owned());
    SOFTHD_PETSC(VecRestoreArrayRead(global2_, &v));
  }
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return report;
}

}  // namespace softhd::fe::petsc_detail
