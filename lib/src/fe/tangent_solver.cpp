#include "softhd/fe/tangent_solver.hpp"

#include <chrono>
#include <cmath>

#include "../common/seconds_since.hpp"
#include "softhd/error.hpp"

namespace softhd::fe {

using Sparse = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

using detail::Clock;
using detail::seconds_since;

void TangentSolverOptions::validate() const {
  if (max_krylov_iterations < 1)
    throw InvalidArgument("tangent solver: max_krylov_iterations must be >= 1");
  if (refactor_after_iterations < 1)
    throw InvalidArgument("tangent solver: refactor_after_iterations must be >= 1");
}

TangentSolver::TangentSolver(const Sparse& pattern, TangentSolverOptions options)
    : options_(options) {
  options_.validate();
  factor_ = make_linear_solver(options_.linear_solver);
  if (pattern.rows() > 0) factor_->analyze(pattern);  // symbolic analysis once per pattern
}

bool TangentSolver::pcg(const Sparse& K, const Eigen::VectorXd& b, double tolerance,
                        Eigen::VectorXd* x, int* iterations, bool* negative_curvature) const {
  // Conjugate gradients on K x = b preconditioned by P⁻¹ (the kept factorisation):
  // r = b − K x, z = P⁻¹ r, p = z + (rᵀz / r₀ᵀz₀) p, x += (rᵀz / pᵀK p) p.
  const double target = tolerance * b.norm();
  x->setZero(b.size());
  Eigen::VectorXd r = b, z = factor_->solve(r), p = z, Kp(b.size());
  double rz = r.dot(z);
  *iterations = 0;
  *negative_curvature = false;
  const double r0 = r.norm();
  if (r0 <= target) return true;
  for (int k = 1; k <= options_.max_krylov_iterations; ++k) {
    Kp.noalias() = K.selfadjointView<Eigen::Lower>() * p;
    const double curvature = p.dot(Kp);
    *iterations = k;
    if (!(curvature > 0.0) || !(rz > 0.0)) {  // K (or P) not positive definite
      *negative_curvature = true;
      return false;
    }
    const double step = rz / curvature;
    x->noalias() += step * p;
    r.noalias() -= step * Kp;
    const double rnorm = r.norm();
    if (rnorm <= target) return true;
    // A factor too stale to converge within the budget: stop early. The residual falls
    // about geometrically, so after k iterations the rate (|r_k|/|r_0|)^(1/k) predicts the
    // iterations still needed (pessimistically: PCG accelerates, hence the 1.5).
    if (k >= 6 && rnorm < r0) {
      const double rate = std::pow(rnorm / r0, 1.0 / k);
      if (k + std::log(target / rnorm) / std::log(rate) > 1.5 * options_.max_krylov_iterations)
        return false;
    }
    z = factor_->solve(r);
    const double rz_next = r.dot(z);
    p = z + (rz_next / rz) * p;
    rz = rz_next;
  }
  return false;
}

TangentSolveReport TangentSolver::solve(const Sparse& K, const Eigen::VectorXd& b, double tolerance,
                                        bool allow_shift, Eigen::VectorXd* x,
                                        bool allow_truncation) {
  TangentSolveReport report;
  if (K.rows() != b.size()) throw InvalidArgument("tangent solver: K and b differ in size");
  if (b.size() == 0) {
    x->resize(0);
    report.ok = true;
    return report;
  }
  if (options_.reuse_factorization && have_factor_ && !stale_) {
    const auto t0 = Clock::now();
    bool negative = false;
    const bool converged = pcg(K, b, tolerance, x, &report.krylov_iterations, &negative);
    report.seconds_solve += seconds_since(t0);
    // Newton–CG: at negative curvature after some progress, the iterate so far is a
    // descent direction of the energy (its slope is −xᵀb < 0); the line search takes it.
    if (negative && allow_shift && allow_truncation && options_.truncate_on_negative_curvature &&
        report.krylov_iterations > 1) {
      report.ok = true;
      report.truncated = true;
      return report;
    }
    if (converged) {
      stale_ = report.krylov_iterations > options_.refactor_after_iterations;
      report.ok = true;
      return report;
    }
  }
  // Factorise K itself (shifted until positive definite if allowed) and solve directly.
  auto t0 = Clock::now();
  report.shift = factor_->factorize_shifted(K, allow_shift, &report.factorizations);
  report.factorized = true;
  report.seconds_factorization = seconds_since(t0);
  have_factor_ = std::isfinite(report.shift);
  stale_ = false;
  if (!have_factor_ || (!allow_shift && report.shift != 0.0)) return report;
  t0 = Clock::now();
  *x = factor_->solve(b);
  report.seconds_solve += seconds_since(t0);
  report.ok = true;
  return report;
}

}  // namespace softhd::fe
