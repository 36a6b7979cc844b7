#include "softhd/fe/linear_solver.hpp"

#include <Eigen/CholmodSupport>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <limits>

#include "softhd/enum_names.hpp"
#include "softhd/error.hpp"

namespace softhd::fe {

using Sparse = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

constexpr auto kLinearSolverNames =
    enum_sequence<LinearSolverType::kCholmod>({"eigen-llt", "eigen-ldlt", "cholmod"});

std::string to_string(LinearSolverType type) { return enum_name(kLinearSolverNames, type); }

LinearSolverType parse_linear_solver(const std::string& name) {
  return enum_from_name(kLinearSolverNames, name, "linear solver");
}

double LinearSolver::factorize_shifted(const Sparse& K, bool allow_shift, int* attempts) {
  double dmax = 0.0;
  for (int j = 0; j < K.outerSize(); ++j) dmax = std::max(dmax, std::abs(K.coeff(j, j)));
  double shift = last_shift_ > 0.0 ? 0.01 * last_shift_ : 0.0;
  if (shift < 1e-8 * dmax || !allow_shift) shift = 0.0;
  bool ok = false;
  int count = 0;
  for (int attempt = 0; attempt <= (allow_shift ? 20 : 0) && !ok; ++attempt) {
    if (attempt > 0) shift = shift > 0.0 ? 10.0 * shift : 1e-8 * dmax;
    ++count;
    if (shift == 0.0) {
      ok = factorize(K);
    } else {
      shifted_ = K;  // K + μ I on the stored lower triangle
      for (int j = 0; j < shifted_.outerSize(); ++j) shifted_.coeffRef(j, j) += shift;
      ok = factorize(shifted_);
    }
  }
  if (attempts) *attempts = count;
  last_shift_ = ok ? shift : 0.0;
  return ok ? shift : std::numeric_limits<double>::infinity();
}

namespace {

// Eigen's simplicial factorisations (SimplicialLLT or SimplicialLDLT, lower triangle).
template <class Factorization, LinearSolverType kType>
class EigenSolver final : public LinearSolver {
 public:
  void analyze(const Sparse& pattern) override { f_.analyzePattern(pattern); }
  bool factorize(const Sparse& K) override {
    f_.factorize(K);
    if (f_.info() != Eigen::Success) return false;
    if constexpr (kType == LinearSolverType::kEigenLDLT) {
      // LDLᵀ succeeds on indefinite matrices: positive definite iff D > 0.
      if (!(f_.vectorD().minCoeff() > 0.0)) return false;
    }
    return true;
  }
  Eigen::VectorXd solve(const Eigen::VectorXd& b) const override { return f_.solve(b); }
  LinearSolverType type() const override { return kType; }

 private:
  Factorization f_;
};

class CholmodSolver final : public LinearSolver {
 public:
  CholmodSolver() { f_.cholmod().print = 0; }  // non-PD is reported by status, not stderr
  void analyze(const Sparse& pattern) override { f_.analyzePattern(pattern); }
  bool factorize(const Sparse& K) override {
    f_.factorize(K);
    return f_.info() == Eigen::Success;
  }
  Eigen::VectorXd solve(const Eigen::VectorXd& b) const override { return f_.solve(b); }
  LinearSolverType type() const override { return LinearSolverType::kCholmod; }

 private:
  Eigen::CholmodSupernodalLLT<Sparse, Eigen::Lower> f_;
};

}  // namespace

std::unique_ptr<LinearSolver> make_linear_solver(LinearSolverType type) {
  switch (type) {
    case LinearSolverType::kEigenLLT:
      return std::make_unique<
          EigenSolver<Eigen::SimplicialLLT<Sparse, Eigen::Lower>, LinearSolverType::kEigenLLT>>();
    case LinearSolverType::kEigenLDLT:
      return std::make_unique<
          EigenSolver<Eigen::SimplicialLDLT<Sparse, Eigen::Lower>, LinearSolverType::kEigenLDLT>>();
    case LinearSolverType::kCholmod:
      return std::make_unique<CholmodSolver>();
  }
  throw InvalidArgument("unknown linear solver type");
}

}  // namespace softhd::fe
