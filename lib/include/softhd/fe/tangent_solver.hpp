#pragma once
/// \file tangent_solver.hpp
/// Linear solves with the tangent K of a Newton iterate that reuse one Cholesky
/// factorisation across iterations and across Newton solves: preconditioned conjugate
/// gradients (PCG) on the exact K with the last factorisation (of an earlier K, possibly
/// shifted) as preconditioner, and a new factorisation only when the Krylov iteration says
/// the factor is stale (it did not converge within its budget, met negative curvature, or
/// needed many iterations last time). A factorisation costs about 30 triangular solves on
/// the bending mesh (bench_state newton), a PCG iteration one pair of them plus one sparse
/// product, so a factor that still preconditions well is used many times.

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <memory>
#include <string>

#include "softhd/fe/linear_solver.hpp"

namespace softhd::fe {

/// Options of TangentSolver.
struct TangentSolverOptions {
  /// Sparse direct solver that makes the factorisations.
  LinearSolverType linear_solver = LinearSolverType::kCholmod;
  /// Reuse the last factorisation as a PCG preconditioner. false: every solve factorises
  /// its matrix (classical Newton).
  bool reuse_factorization = true;
  /// PCG iterations allowed before the factorisation is declared stale and K factorised.
  int max_krylov_iterations = 30;
  /// A solve whose PCG needed more than this many iterations marks the factorisation
  /// stale: the next solve factorises its K first. A factorisation costs about as much as
  /// 15 PCG iterations on the paper's meshes.
  int refactor_after_iterations = 12;
  /// Newton directions (solves that allow a shift): when PCG meets negative curvature
  /// after its first iteration, return the iterate so far (a descent direction, as in
  /// line-search Newton–CG) instead of factorising the indefinite K with a shift.
  bool truncate_on_negative_curvature = true;

  /// Throws InvalidArgument naming the first invalid field.
  void validate() const;
};

/// What one solve did.
struct TangentSolveReport {
  bool ok = false;                     ///< a solution was returned
  bool factorized = false;             ///< this solve factorised its matrix
  int factorizations = 0;              ///< numeric factorisations made (shift search included)
  int krylov_iterations = 0;           ///< PCG iterations (0 after a direct solve)
  double shift = 0.0;                  ///< μ of a direct solve with K + μ I (0 if none)
  bool truncated = false;              ///< PCG stopped at negative curvature (a descent direction)
  double seconds_factorization = 0.0;  ///< wall time of the factorisations
  double seconds_solve = 0.0;          ///< wall time of PCG or the triangular solves
};

/// Solves with Newton tangents, reusing one factorisation as a PCG preconditioner.
class TangentSolver {
 public:
  /// `pattern`: lower triangle with the sparsity of every matrix to be solved.
  TangentSolver(const Eigen::SparseMatrix<double, Eigen::ColMajor, int>& pattern,
                TangentSolverOptions options = {});

  /// x with ‖K x − b‖₂ ≤ tolerance ‖b‖₂ by PCG with the kept factorisation; if there is
  /// none, it is stale, or PCG fails, K is factorised (and kept) and x = (K + μ I)⁻¹ b,
  /// μ = 0 unless K is not positive definite and `allow_shift` is set (Newton directions;
  /// the report gives μ). Returns ok = false if K cannot be factorised (with μ = 0 when
  /// shifts are not allowed). K stores its lower triangle.
  /// `allow_truncation`: with allow_shift, PCG may stop at negative curvature (see
  /// TangentSolverOptions::truncate_on_negative_curvature).
  TangentSolveReport solve(const Eigen::SparseMatrix<double, Eigen::ColMajor, int>& K,
                           const Eigen::VectorXd& b, double tolerance, bool allow_shift,
                           Eigen::VectorXd* x, bool allow_truncation = true);

  /// True if a factorisation is kept.
  bool has_factorization() const { return have_factor_; }
  /// Forgets the kept factorisation (the next solve factorises).
  void drop_factorization() { have_factor_ = false; }
  /// The options given at construction.
  const TangentSolverOptions& options() const { return options_; }

 private:
  /// PCG on K from x = 0 with the kept factorisation; false on negative curvature or no
  /// convergence within max_krylov_iterations.
  bool pcg(const Eigen::SparseMatrix<double, Eigen::ColMajor, int>& K, const Eigen::VectorXd& b,
           double tolerance, Eigen::VectorXd* x, int* iterations, bool* negative_curvature) const;

  TangentSolverOptions options_;
  std::unique_ptr<LinearSolver> factor_;
  bool have_factor_ = false;
  bool stale_ = false;
};

}  // namespace softhd::fe
