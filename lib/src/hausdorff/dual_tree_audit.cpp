// The budget audit of the dual-tree backend (DualTreeConfig::audit, tests only): the
// guarantee of docs/tree_tolerance.md §7 is that, for every outer point o and requested
// sum, the error bounds of the interactions covering o add up to at most τ L(o), L(o)
// o's lower bound of the sum. The planner keeps that by a share per source box or by a
// ledger per outer box; the audit recomputes each interaction's bound from the boxes alone
// and sums them point by point, without either.

#include <algorithm>
#include <cmath>

#include "dual_tree_internal.hpp"

namespace softhd::detail::dual {

namespace {

/// The logarithms of the error bounds per unit weight (value, gradient kernel) of a
/// pruned or interpolated interaction, from the gap of the boxes and the remainder bound.
LogBounds interaction_bound(const Pass& p, const Interaction& it) {
  if (it.op == kPrune) {
    const KdNode& T = p.ot->nodes()[static_cast<size_t>(it.t)];
    const KdNode& S = p.st->nodes()[static_cast<size_t>(it.s)];
    const double l = std::log(std::sqrt(box_gap2(T, S, p.d)) + p.eps);
    return {-p.alpha * l, -(p.alpha + 1.0) * l};
  }
  return interpolation_log_bound(p.obox[static_cast<size_t>(it.t)], it.op != kM2P,
                                 p.sbox[static_cast<size_t>(it.s)], it.op != kP2L, p.d, it.deg,
                                 p.alpha, p.eps);
}

/// Adds the errors of interaction (t, s) (error bound per unit weight e) beyond its own
/// term to the four sums of outer point q, over τ_share L(q) (in logarithms up to the last
/// step, so that large α cannot overflow; the own terms, used only for α ≤ 16, add up to
/// at most τ_own times the sum).
void charge(const Pass& p, int t, int s, const LogBounds& e, Eigen::Index q, double* used) {
  for (int k = 0; k < 4; ++k) {
    const double lw = p.log_weight[4 * static_cast<size_t>(s) + k];
    if (!p.want[k] || lw == -kInf) continue;
    const double norm = p.log_tau_share + p.point_low[4 * static_cast<size_t>(q) + k];
    const double own = t < 0 ? 0.0 : own_term(p, t, s, k);
    const double le = lw + ((k == kS || k == kH) ? e.value : e.grad) - norm;
    const double over = own > 0.0 ? std::exp(le) - own * std::exp(-norm) : std::exp(le);
    used[k] += std::max(over, 0.0);
  }
}

/// The pruning regime's leaf pairs dropped point by point (dual_tree.cpp, to_points).
void charge_points(const Pass& p, const Interaction& it, std::vector<double>& spent) {
  const KdNode& T = p.ot->nodes()[static_cast<size_t>(it.t)];
  const KdNode& S = p.st->nodes()[static_cast<size_t>(it.s)];
  for (Eigen::Index q = T.begin; q < T.end; ++q) {
    double o[3] = {0.0, 0.0, 0.0}, g2 = 0.0;
    for (int k = 0; k < p.d; ++k) {
      o[k] = p.ot->points()(q, k);
      const double gap = std::max({S.lo[k] - o[k], o[k] - S.hi[k], 0.0});
      g2 += gap * gap;
    }
    if (!prunable_for_point(p, o, q, it.s)) continue;
    const double l = std::log(std::sqrt(g2) + p.eps);
    charge(p, -1, it.s, {-p.alpha * l, -(p.alpha + 1.0) * l}, q,
           &spent[4 * static_cast<size_t>(q)]);
  }
}

}  // namespace

double audit_budget(const Pass& p, const std::vector<int>& roots, UnitRange mine,
                    const std::vector<std::vector<Interaction>>& lists) {
  // Per outer point and sum: Σ (error bound − own term)⁺ / (τ_share L(o)).
  std::vector<double> spent(4 * static_cast<size_t>(p.ot->size()), 0.0);
  double worst = 0.0;
  for (size_t r = mine.first; r < mine.last; ++r) {
    for (const Interaction& it : lists[r]) {
      if (it.op == kP2P) {
        if (p.point_prune) charge_points(p, it, spent);
        continue;
      }
      const LogBounds e = interaction_bound(p, it);
      const KdNode& T = p.ot->nodes()[static_cast<size_t>(it.t)];
      for (Eigen::Index q = T.begin; q < T.end; ++q)
        charge(p, it.t, it.s, e, q, &spent[4 * static_cast<size_t>(q)]);
    }
    const KdNode& R = p.ot->nodes()[static_cast<size_t>(roots[r])];
    for (Eigen::Index q = R.begin; q < R.end; ++q)
      for (int k = 0; k < 4; ++k) {
        if (!p.want[k]) continue;
        const double used = spent[4 * static_cast<size_t>(q) + static_cast<size_t>(k)];
        if (!(used <= worst)) worst = used;  // NaN propagates (and fails the test)
      }
  }
  return worst;
}

}  // namespace softhd::detail::dual
