#pragma once
/// \file linear_solver.hpp
/// Sparse symmetric positive definite direct solvers behind one interface: Eigen's
/// SimplicialLLT / SimplicialLDLT and CHOLMOD's supernodal LLᵀ. The symbolic analysis is
/// done once per pattern, the numeric factorisation once per matrix; a factorisation
/// object can be kept and reused (the adjoint reuses the converged tangent's).
/// Matrices store their lower triangle only.

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <memory>
#include <string>

namespace softhd::fe {

/// The sparse direct solvers for the symmetric positive definite tangent.
enum class LinearSolverType {
  kEigenLLT,   ///< Eigen::SimplicialLLT (AMD ordering)
  kEigenLDLT,  ///< Eigen::SimplicialLDLT (AMD ordering)
  kCholmod,    ///< CHOLMOD supernodal LLᵀ (METIS/AMD chosen by CHOLMOD)
};

/// "eigen-llt", "eigen-ldlt", "cholmod".
std::string to_string(LinearSolverType type);
/// Inverse of to_string; throws InvalidArgument listing the valid names.
LinearSolverType parse_linear_solver(const std::string& name);

/// A sparse symmetric positive definite direct solver: analyse a pattern once, factorise
/// matrices with that pattern, solve with the last factorisation.
class LinearSolver {
 public:
  virtual ~LinearSolver() = default;
  /// Factorises K + μ I with the smallest μ >= 0 found in the sequence below for which the
  /// factorisation succeeds, and returns μ (+inf if none of 20 attempts succeeds; the
  /// solver then holds no factorisation). The search starts at μ = 0 if the previous call
  /// needed no shift, else at a hundredth of the previous shift (shifts fall along a Newton
  /// solve, so one or two attempts usually suffice instead of a climb from 1e-8 max|K_ii|;
  /// a hundredth saved 10-20 % of the factorisations of bending's early optimisation
  /// steps against a tenth, and did not change the torsion forward solve from rest),
  /// and multiplies μ by 10 after each failure (from 1e-8 max|K_ii| when it was 0).
  /// With `allow_shift` false only μ = 0 is tried. `attempts` (optional) gets the number
  /// of numeric factorisations made.
  double factorize_shifted(const Eigen::SparseMatrix<double, Eigen::ColMajor, int>& K,
                           bool allow_shift = true, int* attempts = nullptr);
  /// Symbolic analysis of the pattern (lower triangle); call again only if it changes.
  virtual void analyze(const Eigen::SparseMatrix<double, Eigen::ColMajor, int>& pattern) = 0;
  /// Numeric factorisation of a matrix with the analysed pattern. Returns false if the
  /// matrix is not (numerically) positive definite.
  virtual bool factorize(const Eigen::SparseMatrix<double, Eigen::ColMajor, int>& K) = 0;
  /// x = K⁻¹ b with the last successful factorisation.
  virtual Eigen::VectorXd solve(const Eigen::VectorXd& b) const = 0;
  /// Which solver this is.
  virtual LinearSolverType type() const = 0;

 private:
  double last_shift_ = 0.0;
  Eigen::SparseMatrix<double, Eigen::ColMajor, int> shifted_;
};

/// A new solver of the given type.
std::unique_ptr<LinearSolver> make_linear_solver(LinearSolverType type);

}  // namespace softhd::fe
