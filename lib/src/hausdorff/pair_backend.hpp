#pragma once
// Pair-sum backends (internal). One batch call computes the kernel sums of
// pair_kernel.hpp (S, G, H, G2) for every outer point of one pass; hausdorff.cpp writes
// the chain rule (means, gradients) once above this interface. Implementations:
//   ExactBackend       all pairs (the reference),
//   SingleTreeBackend  per-point traversal with one-term far field (tree_sums.hpp),
//   DualTreeBackend    dual-tree traversal with Chebyshev far field and rigorous pruning
//                      (dual_tree.hpp), falling back to exact when that is cheaper.

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <vector>

#include "kd_tree.hpp"
#include "pair_kernel.hpp"
#include "softhd/work_share.hpp"

namespace softhd::detail {

/// The source points of a pass and their per-point data, all in the caller's order.
struct PassSources {
  const Eigen::MatrixXd* points = nullptr;  ///< M by d
  const KdTree* tree = nullptr;             ///< over *points (tree backends only)
  const double* weight = nullptr;           ///< w_n ≥ 0 (kOuterSum, kOuterGrad)
  const double* coef = nullptr;             ///< h_n ≥ 0 (kInner)
  const double* scale = nullptr;            ///< c_n > 0 (kInner)
};

/// The outer points of a pass, in the caller's order.
using Mask = Eigen::Array<bool, Eigen::Dynamic, 1>;
struct PassOuter {
  const Eigen::MatrixXd* points = nullptr;  ///< N by d
  const KdTree* tree = nullptr;             ///< over *points (tree backends only)
  const double* scale = nullptr;            ///< c_o = r_min(o) + ε
  unsigned flags = kOuterSum;               ///< sums wanted (PairFlags)
  const Mask* mask = nullptr;               ///< optional: points with `false` need kOuterSum only
};

/// Where one pass's work went (for the benchmarks' split).
struct PassStats {
  std::int64_t near_pairs = 0;  ///< source–outer pairs summed directly
  std::int64_t far_kernel = 0;  ///< kernel evaluations at proxies (far field)
  std::int64_t far_basis = 0;   ///< point–proxy basis products (anterpolation, L2P)
  std::int64_t node_pairs = 0;  ///< node pairs visited by the traversal
  std::int64_t bound_axes = 0;  ///< axes' remainder-bound terms computed by the traversal
  double plan_seconds = 0.0;    ///< traversal (planning) wall time
  double run_seconds = 0.0;     ///< evaluation wall time
  bool fell_back = false;       ///< the cost model chose all pairs
};

/// The sums of one pass, one row per outer point (caller's order). Members not
/// requested by the flags are empty; rows of masked points hold S only.
struct PassSums {
  Eigen::VectorXd S, H;
  Eigen::MatrixXd G, G2;
  std::int64_t kernel_evaluations = 0;
  PassStats stats;
};

/// Settings shared by every pass of one evaluation.
struct PassSettings {
  const KernelPower* power = nullptr;
  double eps = 1e-3;
  double tau = 1e-6;  ///< relative tolerance (tree backends)
  int threads = 1;
  /// Processes sharing the pass (softhd/work_share.hpp); nullptr: this one does all.
  /// With a share, a backend computes the rows of its share of the outer points only (the
  /// others stay zero) and its stats count its own work; run_pass completes the sums.
  const WorkShare* share = nullptr;
};

class PairSumBackend {
 public:
  virtual ~PairSumBackend() = default;
  /// The sums of every outer point over all sources: one call per pass.
  virtual PassSums sums(const PassSources& src, const PassOuter& outer,
                        const PassSettings& set) const = 0;
};

/// Leaf size of the trees the tree backends expect.
constexpr int kLeafSize = 32;

std::unique_ptr<PairSumBackend> make_exact_backend();
std::unique_ptr<PairSumBackend> make_single_tree_backend();
std::unique_ptr<PairSumBackend> make_dual_tree_backend();

/// One pass: backend.sums(), then, with a share, every row and count summed over the
/// processes (exact: each row is computed by one process and is zero on the others).
PassSums run_pass(const PairSumBackend& backend, const PassSources& src, const PassOuter& outer,
                  const PassSettings& set);

/// This process's run of `n` units with costs `cost` (all of them without a share).
UnitRange share_of(const PassSettings& set, const std::vector<double>& cost);

/// Allocates the members of PassSums the flags ask for (n rows, d columns).
PassSums allocate_sums(Eigen::Index n, int d, unsigned flags);
/// Stores one point's sums into row i of `out` (only what `flags` asked for).
void store_sums(PassSums& out, Eigen::Index i, const PairSums& s, unsigned flags, int d);

}  // namespace softhd::detail
