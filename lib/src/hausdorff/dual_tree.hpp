#pragma once
// Method tree's pair-sum backend (internal): a dual-tree traversal over the outer and
// the source k-d trees with a far field of tensor Chebyshev interpolation
// (chebyshev.hpp) and rigorous pruning, each sum within relative tolerance τ
// (docs/tree_tolerance.md §7).
//
// Node pair (T outer, S source), cheapest admissible of
//     prune  drop S: error ≤ W_S sup k                                  cost 0
//     M2P    S's interpolation points (weights Σ w L_p(x)) to each o ∈ T  cost |T| P
//     P2L    S's points to T's interpolation points (locals)             cost P |S|
//     M2L    S's interpolation points to T's                             cost P²
// (P ≤ m^d points per box, m = 2 … n points per axis chosen per node pair: the least m
// whose remainder bound fits the pair's budget; fewer than m along a box's thin axes,
// grid_rho); otherwise the larger node is split, and
// leaf pairs (or small pairs) are summed directly (P2P) with the vectorised kernel. Above
// max_interp_alpha (pruning only), a leaf pair's source box is also pruned point by
// point, with each outer point's own lower bound and distance to the box. Proxy weights
// are computed upwards (M2M from children's grids, anterpolation from the points of
// children without grids) and locals pushed downwards (L2L to children's grids, L2P to
// the points of the others), one chain of grids per degree m: both translations are
// exact for tensor polynomials of degree m − 1, so they add no error term.
//
// Budget. Before the traversal, a lower bound L(o) of every sum is computed from one
// source leaf near o (all terms ≥ 0). Pair (T, S) may use an approximation with error
// bound e only if e ≤ τ · min_{o∈T} L(o) · mass(S)/mass(all), for every requested sum
// (in the unscaled form, k = c_o^α (r + ε)^(−α), so the bound is uniform over T). The
// far nodes of one outer point are disjoint, so their shares sum to ≤ 1 and every sum
// is within τ of exact. With `recycle` (default, α ≤ max_interp_alpha) a ledger per outer
// box hands what a pair left of its share to the pairs planned after it (the farther
// source child first); docs/tree_tolerance.md §7.
//
// Cost model: the planned work (kernel evaluations weighted per operation) is compared
// with N·M; if the plan is not clearly cheaper, the pass is summed exactly.

#include <cstdint>
#include <memory>
#include <vector>

#include "pair_backend.hpp"

namespace softhd::detail {

struct DualTreeConfig {
  int degree = 0;           ///< most points per axis n; 0: from τ (degree_for)
  int min_degree = 0;       ///< least points per axis a node pair may use; 0: n (one degree)
  bool own_budget = false;  ///< budget also from each pair's own least contribution
  /// Far-field regime: the budget a node pair leaves unused passes to the pairs planned
  /// after it for the same outer points (a ledger per outer box)
  bool recycle = true;
  /// Tests: after planning, every outer point's error bounds are summed again from the
  /// interaction lists (DualTreeOps::budget_used); costly
  bool audit = false;
  double min_pairs = 3.0e7;        ///< passes with fewer N·M pairs are summed exactly
  bool cost_model = true;          ///< false: never fall back to exact (tests)
  double max_interp_alpha = 16.0;  ///< above: pruning only (the far field is negligible)
  int small_pairs = 4096;  ///< α ≤ max_interp_alpha: pairs with |T||S| ≤ this are summed directly
  /// Grids with fewer points along a box's thin axes (set_grid_slopes, reference ρ;
  /// docs/tree_tolerance.md §7); ≤ 1: every axis at the pair's degree
  double grid_rho = 3.0;
};

/// The largest n from τ: 4 at τ = 1e-2, 6 at 1e-4, 8 at 1e-6, at most 12.
int degree_for(double tau);

/// Counts of each operation of the last pass (tests check that each one was used).
struct DualTreeOps {
  std::int64_t p2p = 0, m2p = 0, p2l = 0, m2l = 0, prune = 0;
  std::int64_t point_pruned = 0;     ///< direct pairs skipped by pruning point by point
  std::int64_t m2m = 0, l2l = 0;     ///< translations between a box's grid and a child's
  std::int64_t far_degree[17] = {};  ///< far-field node pairs per points per axis m
  std::int64_t thin = 0;  ///< far-field node pairs with a grid of fewer points along an axis
  /// With DualTreeConfig::audit: the largest, over outer points and requested sums, of
  /// (sum of the error bounds of the interactions covering the point) / (τ · its lower
  /// bound); the guarantee needs ≤ 1
  double budget_used = 0.0;
  /// With DualTreeConfig::audit: per outer point (the caller's order), the logarithms of
  /// the lower bounds of its four sums in the unscaled form (S/c_o^α, Gm/c_o^α, H, G2m)
  /// that set the budget; each must be at most the true sum's.
  std::vector<double> log_lower;
};

std::unique_ptr<PairSumBackend> make_dual_tree_backend(const DualTreeConfig& config,
                                                       DualTreeOps* ops);

}  // namespace softhd::detail
