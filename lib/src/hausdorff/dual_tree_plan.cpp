// Planning of the dual-tree backend (dual_tree_internal.hpp): the pass's source data, and
// the dual traversal choosing per node pair an operation and a degree within the budget
// that the lower bounds (dual_tree_bounds.cpp) set (docs/tree_tolerance.md §7).

#include <algorithm>
#include <atomic>
#include <cmath>
#include <stdexcept>

#include "dual_tree_internal.hpp"

namespace softhd::detail::dual {

namespace {

double node_gap(const KdNode& a, const KdNode& b, int d) { return std::sqrt(box_gap2(a, b, d)); }

double node_radius2(const KdNode& a, int d) {
  double r2 = 0.0;
  for (int k = 0; k < d; ++k) r2 += (a.hi[k] - a.lo[k]) * (a.hi[k] - a.lo[k]);
  return r2;
}

}  // namespace

/// Grids that nest down the subtree of `root`: every child's slopes at least its
/// parent's (preorder: parents first), so that its grids have at least as many points
/// along every axis and M2M, L2L translate between them (grid_nests).
void inherit_slopes(const KdTree& tree, int root, int d, std::vector<Box>& box) {
  const std::vector<KdNode>& nodes = tree.nodes();
  const int end = subtree_end(tree, root);
  for (int id = root; id < end; ++id) {
    const KdNode& n = nodes[static_cast<size_t>(id)];
    if (n.right < 0) continue;
    const Box& parent = box[static_cast<size_t>(id)];
    for (const int ch : {id + 1, n.right})
      for (int k = 0; k < d; ++k) {
        double& s = box[static_cast<size_t>(ch)].slope[k];
        s = std::max(s, parent.slope[k]);
      }
  }
}

namespace {

/// Source data in tree order, node moments, and the totals of the budget shares.
void prepare_sources(Pass& p, const PassSources& in) {
  const KdTree& st = *p.st;
  p.src.dim = p.d;
  p.src.size = st.size();
  for (int k = 0; k < p.d; ++k) p.src.coord[k] = st.points().col(k).data();
  const Eigen::Index m = st.size();
  if (p.outer_kinds()) {
    p.w = st.permute(Eigen::Map<const Eigen::VectorXd>(in.weight, m));
    p.mw = node_moments(st, p.w.data(), nullptr, *p.power);
    p.src.weight = p.w.data();
    p.log_total[kS] = p.log_total[kG] = std::log(p.mw[0].mass);
  }
  if (p.want[kH]) {
    p.h = st.permute(Eigen::Map<const Eigen::VectorXd>(in.coef, m));
    p.c = st.permute(Eigen::Map<const Eigen::VectorXd>(in.scale, m));
    p.mh = node_moments(st, p.h.data(), p.c.data(), *p.power);
    p.src.coef = p.h.data();
    p.src.scale = p.c.data();
    p.log_total[kH] = p.log_total[kG2] = std::log(p.mh[0].mass);
  }
  const std::vector<KdNode>& nodes = st.nodes();
  // Per node and kind: log of the weight in the unscaled bounds (−∞: no such sum or no
  // mass) and log of the budget share mass/total.
  p.log_weight.assign(4 * nodes.size(), -kInf);
  p.log_share.assign(4 * nodes.size(), -kInf);
  for (size_t i = 0; i < nodes.size(); ++i)
    for (int k = 0; k < 4; ++k) {
      if (!p.want[k]) continue;
      const NodeMoments& m = k < 2 ? p.mw[i] : p.mh[i];
      if (!(m.mass > 0.0)) continue;
      p.log_weight[4 * i + k] = std::log(m.weight) + (k < 2 ? 0.0 : p.alpha * std::log(m.scale));
      p.log_share[4 * i + k] = std::log(m.mass) - p.log_total[k];
    }
  if (!p.interp) return;
  p.sbox.resize(nodes.size());
  for (size_t i = 0; i < nodes.size(); ++i) {
    p.sbox[i] = interpolation_box(nodes[i].lo, nodes[i].hi, p.d);
    set_grid_slopes(p.sbox[i], p.d, p.cfg.grid_rho);
  }
  inherit_slopes(st, 0, p.d, p.sbox);
}

/// The budget ledger of an outer box T during its traversal (DualTreeConfig::recycle), per
/// kind: `done`, the mass share of the source boxes already planned for every point of T,
/// and `spent`, an upper bound, over the points o of T, of Σ e/(τ λ) over the error bounds
/// e charged to o so far, each relative to λ = min L over the box T' ∋ o it was charged
/// at (λ ≤ L(o)). Pair (T, S) may use an error e when spent + e/(τ λ_T) ≤ done + share(S),
/// λ_T = min_{o∈T} L(o); then spent ≤ done at every step, and at the end (done ≤ 1, the
/// boxes planned for o are disjoint) every point carries errors ≤ τ L(o). A box's
/// children start from its ledger; after both, it keeps the larger `spent`. Every pair
/// may use at least its share (spent ≤ done), as without the ledger.
struct Ledger {
  double done[4] = {0.0, 0.0, 0.0, 0.0};
  double spent[4] = {0.0, 0.0, 0.0, 0.0};
};

/// The budgets of pair (t, s) per kind: log of the source node's weight in the unscaled
/// bounds (lw) and log of the error allowed (lb), the larger of
///     τ_share · min_{o∈T} L(o) · mass(S)/mass(all)   and   τ_own · W_S u(R_max),
/// or, with a ledger, τ_share λ_T (done + mass(S)/mass(all) − spent) (above);
/// u(R_max) the kernel (value or gradient) at the largest distance between the boxes, so
/// that W_S u(R_max) is at most S's contribution to the sum of every o ∈ T. Over the
/// disjoint source nodes approximated for one outer point the first terms add up to at
/// most τ_share L(o) ≤ τ_share S(o), the second to at most τ_own S(o); τ_share + τ_own = τ.
struct Budget {
  double lw[4], lb[4];
  bool want[4];
  /// Whether errors of at most exp(lv) (value kernel) and exp(lg) (gradient kernel) per
  /// unit weight fit every requested sum's budget.
  bool fits(double lv, double lg) const {
    for (int k = 0; k < 4; ++k)
      if (want[k] && !(lw[k] + ((k == kS || k == kH) ? lv : lg) <= lb[k])) return false;
    return true;
  }
};

/// The largest distance between the boxes of two nodes.
double node_far(const KdNode& a, const KdNode& b, int d) {
  double r2 = 0.0;
  for (int k = 0; k < d; ++k) {
    const double span = std::max(a.hi[k] - b.lo[k], b.hi[k] - a.lo[k]);
    r2 += span * span;
  }
  return std::sqrt(r2);
}

}  // namespace

double own_term(const Pass& p, int t, int s, int k) {
  if (p.log_tau_own == -kInf) return 0.0;
  const double lr = std::log(
      node_far(p.ot->nodes()[static_cast<size_t>(t)], p.st->nodes()[static_cast<size_t>(s)], p.d) +
      p.eps);
  const double lu = -(k == kS || k == kH ? p.alpha : p.alpha + 1.0) * lr;
  return std::exp(p.log_tau_own + p.log_weight[4 * static_cast<size_t>(s) + k] + lu);
}

namespace {

Budget budget(const Pass& p, int t, int s, const Ledger* ledger) {
  Budget b;
  const double lr = std::log(
      node_far(p.ot->nodes()[static_cast<size_t>(t)], p.st->nodes()[static_cast<size_t>(s)], p.d) +
      p.eps);
  for (int k = 0; k < 4; ++k) {
    b.want[k] = p.want[k];
    b.lw[k] = p.log_weight[4 * static_cast<size_t>(s) + k];
    if (b.lw[k] == -kInf) {
      b.lb[k] = kInf;
      continue;
    }
    const double low = p.log_low[4 * static_cast<size_t>(t) + k];
    const double ls = p.log_share[4 * static_cast<size_t>(s) + k];
    double share = p.log_tau_share + low + ls;
    if (ledger != nullptr) {
      const double avail = ledger->done[k] + std::exp(ls) - ledger->spent[k];
      share = avail > 0.0 ? p.log_tau_share + low + std::log(avail) : -kInf;
    }
    const double lu = -(k == kS || k == kH ? p.alpha : p.alpha + 1.0) * lr;
    const double own = p.log_tau_own + b.lw[k] + lu;
    // Without a ledger, max(a, b) ≤ a + b: half of the budget at worst, without exp/log
    // per pair; with one, the sum (book() charges the ledger only beyond the own term).
    b.lb[k] = ledger == nullptr || own == -kInf || share == -kInf
                  ? std::max(share, own)
                  : std::max(share, own) + std::log1p(std::exp(-std::fabs(share - own)));
  }
  return b;
}

/// Work of operation op at degree m for pair (t, s) of nT outer and nS source points, in
/// kernel evaluations.
double far_cost(const Pass& p, Op op, int m, int t, int s, double nT, double nS) {
  if (op == kM2L) return static_cast<double>(p.local_points(t, m)) * p.proxy_points(s, m);
  if (op == kM2P) return nT * p.proxy_points(s, m);
  return p.local_points(t, m) * nS;  // kP2L
}

/// The smallest degree in [2, p.n] at which operation op's remainder bound fits the
/// budget, or 0. A cheap necessary condition first: every bound of the operation is at
/// least the one-axis bound of its widest interpolated axis (half-width a), with
/// |u| ≥ (gap + ε)^(−α) and the largest ellipse the bound searches, ρ ≤ √2 R/a + 1, R the
/// largest distance between the two boxes (chebyshev.cpp). Then the bound of the widest
/// interpolated axis alone at degree n, which no degree's combined bound is below
/// (PairBounds::axis_bound), at a sixth of the full bounds' cost (cube, N = 10⁴, τ = 1e-2:
/// of 169 380 tests past the first one, 10 368 fit, and 43 986 pass the axis). The bounds use
/// both interpolation boxes (each contains its node's box), so `pb` serves every operation.
int least_degree(const Pass& p, const Budget& b, Op op, const Box& bt, const Box& bs,
                 PairBounds& pb, double l, LogBounds& at) {
  const bool it = op != kM2P, is = op != kP2L;
  double a_max = 0.0, far2 = 0.0;
  bool wide_t = it;  // the widest interpolated axis: (side, axis)
  int wide_k = 0;
  for (int k = 0; k < p.d; ++k) {
    if (it && bt.a[k] > a_max) a_max = bt.a[k], wide_t = true, wide_k = k;
    if (is && bs.a[k] > a_max) a_max = bs.a[k], wide_t = false, wide_k = k;
    const double span = std::fabs(bt.c[k] - bs.c[k]) + bt.a[k] + bs.a[k];
    far2 += span * span;
  }
  const double rho = std::sqrt(2.0 * far2) / a_max + 1.0;
  const double least =
      std::log(4.0) - p.alpha * l - (p.n - 1) * std::log(rho) - std::log(rho - 1.0);
  if (!b.fits(least, least - l)) return 0;
  const LogBounds one = pb.axis_bound(wide_t, wide_k, p.n);  // then the widest axis alone
  if (!b.fits(one.value, one.grad)) return 0;
  LogBounds e[kMaxChebyshev + 1];
  pb.bounds(it, is, p.m_lo, p.n, e);
  for (int m = p.m_lo; m <= p.n; ++m)
    if (b.fits(e[m].value, e[m].grad)) {
      at = e[m];
      return m;
    }
  return 0;
}

/// An admissible approximation of pair (t, s) and its degree, or kNone: the operations are
/// tried in the order of their cost at the largest degree n, and the first that fits is
/// used at its least admissible degree (bounding every operation at every pair costs more
/// planning time than the cheaper choices save).
Choice choose(const Pass& p, int t, int s, double gap, const Ledger* ledger) {
  const Budget b = budget(p, t, s, ledger);
  const double l = std::log(gap + p.eps);
  if (b.fits(-p.alpha * l, -(p.alpha + 1.0) * l))
    return {kPrune, 0, -p.alpha * l, -(p.alpha + 1.0) * l};
  if (!p.interp) return {};
  const double nT = static_cast<double>(size_of(p.ot->nodes()[static_cast<size_t>(t)]));
  const double nS = static_cast<double>(size_of(p.st->nodes()[static_cast<size_t>(s)]));
  struct Option {
    double cost;
    Op op;
  } options[3];
  int count = 0;
  for (const Op op : {kM2L, kM2P, kP2L}) {
    const bool m_ok = op == kP2L || p.has_proxy(s, p.m_lo);
    const bool l_ok = op == kM2P || p.has_local(t, p.m_lo);
    if (m_ok && l_ok) options[count++] = {far_cost(p, op, p.n, t, s, nT, nS), op};
  }
  for (int i = 1; i < count; ++i)  // insertion sort by cost at degree n (count ≤ 3)
    for (int j = i; j > 0 && options[j].cost < options[j - 1].cost; --j)
      std::swap(options[j], options[j - 1]);
  const Box& bt = p.obox[static_cast<size_t>(t)];
  const Box& bs = p.sbox[static_cast<size_t>(s)];
  PairBounds pb(bt, bs, p.d, p.alpha, p.eps);
  Choice best;
  double best_cost = nT * nS;  // direct
  for (int i = 0; i < count; ++i) {
    const Op op = options[i].op;
    // Skipped when even its lowest degree would not be cheaper than the best so far.
    if (!(far_cost(p, op, p.m_lo, t, s, nT, nS) < best_cost)) continue;
    LogBounds e{kInf, kInf};
    const int m = least_degree(p, b, op, bt, bs, pb, l, e);
    if (m == 0) continue;
    const double cost = far_cost(p, op, m, t, s, nT, nS);
    // The grids must have fewer points than their boxes (else the op is not cheaper).
    const bool grids_ok = (op == kP2L || p.has_proxy(s, m)) && (op == kM2P || p.has_local(t, m));
    if (grids_ok && cost < best_cost) best_cost = cost, best = {op, m, e.value, e.grad};
    if (best.op != kNone) break;  // the cheapest at degree n that fits, at its least degree
  }
  best.axes = pb.computed();
  return best;
}

/// One task's planning state. `spent` is shared by the tasks: the planned near and far
/// work so far (in pair units, kCost weights). It is a lower bound of the plan's total,
/// so once it exceeds `limit` the pass will be summed exactly whatever the order of the
/// tasks, and planning stops.
struct PlanState {
  std::vector<Interaction> out;
  PlanCounts counts;
  double pending = 0.0;  // work not yet added to `spent`
  double total = 0.0;    // all work planned by this task
  std::atomic<double>* spent = nullptr;
  double limit = kInf;
  bool stop() {
    if (pending < 1e6) return false;
    double now = spent->load(std::memory_order_relaxed);
    while (!spent->compare_exchange_weak(now, now + pending, std::memory_order_relaxed)) {
    }
    pending = 0.0;
    return now > limit;
  }
  void add(const Pass& p, const Interaction& it) {
    out.push_back(it);
    const double w = interaction_cost(p, it);
    pending += w;
    total += w;
  }
};

/// Books pair (t, s) in the ledger: its mass shares are done, and the error bounds of
/// choice c (none for a direct sum) are charged, beyond the pair's own term.
void book(const Pass& p, int t, int s, const Choice* c, Ledger& ledger) {
  for (int k = 0; k < 4; ++k) {
    const double lw = p.log_weight[4 * static_cast<size_t>(s) + k];
    if (!p.want[k] || lw == -kInf) continue;
    ledger.done[k] += std::exp(p.log_share[4 * static_cast<size_t>(s) + k]);
    if (c == nullptr) continue;
    const double e = std::exp(lw + ((k == kS || k == kH) ? c->lv : c->lg));
    const double over = e - own_term(p, t, s, k);
    if (over > 0.0)
      ledger.spent[k] +=
          over * std::exp(-p.log_tau_share - p.log_low[4 * static_cast<size_t>(t) + k]);
  }
}

/// Depth-first dual traversal from (t, s): appends the interactions to `st.out`, books
/// them in T's ledger (recycling only). Returns false when planning was stopped (the plan
/// costs more than the limit).
bool plan(const Pass& p, int t, int s, PlanState& st, Ledger& ledger) {
  ++st.counts.visits;
  const KdNode& T = p.ot->nodes()[static_cast<size_t>(t)];
  const KdNode& S = p.st->nodes()[static_cast<size_t>(s)];
  const bool outer_mass = p.outer_kinds() && p.mw[static_cast<size_t>(s)].mass > 0.0;
  const bool inner_mass = p.want[kH] && p.mh[static_cast<size_t>(s)].mass > 0.0;
  if (!outer_mass && !inner_mass) return true;  // every term is zero
  const double gap = node_gap(T, S, p.d);
  if (gap > 0.0) {
    const Choice c = choose(p, t, s, gap, p.recycle ? &ledger : nullptr);
    st.counts.axes += c.axes;
    if (c.op != kNone) {
      st.add(p, {t, s, c.op, static_cast<std::uint8_t>(c.deg)});
      if (p.recycle) book(p, t, s, &c, ledger);
      return !st.stop();
    }
  }
  const bool tl = T.right < 0, sl = S.right < 0;
  // Small pairs at low α are summed at once (their children would not be pruned either);
  // at large α leaf pairs are worth pruning one by one.
  const std::int64_t small = p.interp ? p.cfg.small_pairs : 0;
  if ((tl && sl) || size_of(T) * size_of(S) <= small) {
    st.add(p, {t, s, kP2P, 0});
    if (p.recycle) book(p, t, s, nullptr, ledger);
    return !st.stop();
  }
  if (sl || (!tl && node_radius2(T, p.d) >= node_radius2(S, p.d))) {
    if (!p.recycle) return plan(p, t + 1, s, st, ledger) && plan(p, T.right, s, st, ledger);
    Ledger a = ledger, b = ledger;  // each child from T's ledger; then the larger spent
    if (!plan(p, t + 1, s, st, a) || !plan(p, T.right, s, st, b)) return false;
    for (int k = 0; k < 4; ++k)
      ledger.done[k] = a.done[k], ledger.spent[k] = std::max(a.spent[k], b.spent[k]);
    return true;
  }
  int first = s + 1, second = S.right;
  // Recycling: the farther child first, so that the nearer one (which needs the larger
  // budget) receives what the farther one left.
  if (p.recycle && node_gap(T, p.st->nodes()[static_cast<size_t>(first)], p.d) <
                       node_gap(T, p.st->nodes()[static_cast<size_t>(second)], p.d))
    std::swap(first, second);
  return plan(p, t, first, st, ledger) && plan(p, t, second, st, ledger);
}

constexpr size_t kSampleStride = 64;            // planning units sampled to predict the plan's work
constexpr Eigen::Index kMinSamplePoints = 256;  // the smallest unit of the sample

}  // namespace

double planning_cost(const Pass& p, const PlanCounts& c, double points) {
  return p.overhead_scale() * (kCostVisit * static_cast<double>(c.visits) +
                               kCostAxis * static_cast<double>(c.axes) + kCostBound * points);
}

double interaction_cost(const Pass& p, const Interaction& it) {
  const double nT = static_cast<double>(size_of(p.ot->nodes()[static_cast<size_t>(it.t)]));
  const double nS = static_cast<double>(size_of(p.st->nodes()[static_cast<size_t>(it.s)]));
  if (it.op == kP2P) return kCostNear * nT * nS;
  if (it.op == kPrune) return 0.0;
  return kCostFar * far_cost(p, it.op, it.deg, it.t, it.s, nT, nS);
}

/// Whether source node s may be dropped for the outer point o (tree position q) alone:
/// the prune test of choose() with o's own lower bounds and its own distance to the box.
/// The boxes dropped for o are still disjoint, so the budget argument is unchanged.
bool prunable_for_point(const Pass& p, const double* o, Eigen::Index q, int s) {
  const KdNode& S = p.st->nodes()[static_cast<size_t>(s)];
  const double l = std::log(std::sqrt(box_gap2(S, o, p.d)) + p.eps);
  for (int k = 0; k < 4; ++k) {
    if (!p.want[k]) continue;
    const double lw = p.log_weight[4 * static_cast<size_t>(s) + k];
    if (lw == -kInf) continue;
    const double lb = p.log_tau_share + p.point_low[4 * static_cast<size_t>(q) + k] +
                      p.log_share[4 * static_cast<size_t>(s) + k];
    if (!(lw - ((k == kS || k == kH) ? p.alpha : p.alpha + 1.0) * l <= lb)) return false;
  }
  return true;
}

/// Outer subtrees processed as independent tasks (they partition the outer points):
/// nodes of at most `limit` points. The partition depends on the tree only, so that the
/// plan, hence every bit of the result, does not depend on the thread count.
void task_roots(const KdTree& ot, int id, Eigen::Index limit, std::vector<int>& out) {
  const KdNode& n = ot.nodes()[static_cast<size_t>(id)];
  if (size_of(n) <= limit || n.right < 0) {
    out.push_back(id);
    return;
  }
  task_roots(ot, id + 1, limit, out);
  task_roots(ot, n.right, limit, out);
}

/// The pass's settings, source data and outer lower bounds.
void prepare(Pass& p, const DualTreeConfig& cfg, const PassSources& src, const PassOuter& outer,
             const PassSettings& set) {
  p.ot = outer.tree;
  p.st = src.tree;
  p.cfg = cfg;
  p.d = p.ot->dim();
  p.n = cfg.degree > 0 ? cfg.degree : degree_for(set.tau);
  p.m_lo = cfg.min_degree > 0 ? std::min(cfg.min_degree, p.n) : p.n;
  p.rules.clear();
  for (int m = 0; m <= p.n; ++m) p.rules.emplace_back(std::max(m, 2));
  p.lagrange.assign(static_cast<size_t>((p.n + 1) * (p.n + 1)), {});
  for (int a = 2; a <= p.n; ++a)
    for (int b = 2; b <= a; ++b) {
      std::vector<double>& R = p.lagrange[static_cast<size_t>(a * (p.n + 1) + b)];
      R.resize(static_cast<size_t>(a * b));
      for (int j = 0; j < a; ++j)
        p.rules[static_cast<size_t>(b)].basis(p.rules[static_cast<size_t>(a)].xi[j],
                                              &R[static_cast<size_t>(j * b)]);
    }
  p.flags = outer.flags;
  p.want[kS] = (p.flags & kOuterSum) != 0;
  p.want[kG] = (p.flags & kOuterGrad) != 0;
  p.want[kH] = p.want[kG2] = (p.flags & kInner) != 0;
  for (int k = 0; k < 4; ++k)
    if (p.want[k]) {
      p.field[k] = p.nf;
      p.nf += (k == kG || k == kG2) ? p.d : 1;
    }
  p.alpha = set.power->alpha();
  p.eps = set.eps;
  p.interp = p.alpha <= cfg.max_interp_alpha;
  p.point_prune = !p.interp;
  // Far field: half of τ for the shares, half for the pairs' own contributions. Pruning
  // only (large α): the own term could never pay for a dropped node.
  const bool own = p.interp && cfg.own_budget;
  p.log_tau_share = std::log(own ? 0.5 * set.tau : set.tau);
  p.log_tau_own = own ? std::log(0.5 * set.tau) : -kInf;
  p.recycle = p.interp && cfg.recycle;
  p.power = set.power;
  prepare_sources(p, src);
  prepare_outer(p, outer);
}

/// The basis work (kCostBasis weights) of the grids that the sample's interactions mark:
/// added to `outer` for the outer boxes' (L2L, L2P: it grows with the outer points), to
/// `source` for the source boxes' (anterpolation, M2M: shared by every outer box).
void sample_basis(const Pass& p, const std::vector<std::vector<Interaction>>& lists, double& outer,
                  double& source) {
  const size_t grids = static_cast<size_t>(p.n + 1);
  std::vector<char> smark(p.st->nodes().size() * grids, 0), omark(p.ot->nodes().size() * grids, 0);
  std::vector<char> sderive(smark.size(), 0);
  mark_grids(p, lists, smark, sderive, omark);
  std::int64_t translations = 0;
  const double basis = kCostBasis * p.overhead_scale();
  outer += basis * static_cast<double>(grid_work(p, *p.ot, p.obox, omark, p.nf, translations));
  source += basis * static_cast<double>(
                        grid_work(p, *p.st, p.sbox, smark, p.source_fields(), translations));
}

/// Plans the outer tree's root `root` within `limit` of the shared `spent` (PlanState): its
/// work in *work, its interactions in *list, the planning work added to *visits and *axes.
/// False if the plan ran over the limit.
bool plan_root(Pass& p, int root, std::atomic<double>* spent, double limit, double* work,
               std::vector<Interaction>* list, std::int64_t* visits, std::int64_t* axes) {
  PlanState st;
  st.spent = spent;
  st.limit = limit;
  Ledger ledger;
  const bool within = plan(p, root, 0, st, ledger);
  *visits += st.counts.visits;
  *axes += st.counts.axes;
  *work = st.total;
  *list = std::move(st.out);
  return within;
}

/// Whether the sample predicts a plan over `limit`. Its units are the tasks of `mine`, cut
/// into subtrees of at most N/16 points (at least kMinSamplePoints) where tasks are larger,
/// i.e. only below N ≈ 16 000, where 4–8 tasks would make the sample half or a quarter of the
/// planning. Every stride-th unit (stride ≤ kSampleStride) is bounded and planned; the
/// work, scaled by the share of the outer points covered, predicts the plan's, and planning
/// stops as soon as the work exceeds that share of the limit. The prediction adds the
/// planning still to do (the sample's per point, planning_cost). A unit that is a whole task
/// keeps its plan (`lists`, `work`, `done`); a smaller unit's plan is dropped (it plans
/// more work per point than its task: the prediction errs towards a fall-back).
bool sample_exceeds(Pass& p, const std::vector<int>& roots, UnitRange mine, double limit,
                    const PassSettings& set, std::vector<std::vector<Interaction>>& lists,
                    std::vector<double>& work, std::vector<char>& done, PlanCounts& counts) {
  const double n_all = static_cast<double>(p.ot->size());
  const Eigen::Index unit_limit =
      std::max(kMinSamplePoints, static_cast<Eigen::Index>(n_all / 16.0));
  std::vector<int> units, task_of;  // task_of: the task a unit is, or −1 for part of one
  for (size_t r = mine.first; r < mine.last; ++r) {
    const size_t before = units.size();
    task_roots(*p.ot, roots[r], unit_limit, units);
    const bool whole = units.size() == before + 1;
    task_of.resize(units.size(), whole ? static_cast<int>(r) : -1);
  }
  // At least two units (planned in parallel); not a function of the thread count, so
  // neither is the verdict (the sums are bit-identical for any number of threads).
  const size_t stride = std::clamp<size_t>(units.size() / 2, 1, kSampleStride);
  std::vector<int> sample_roots, sample_task;
  double covered = 0.0, kept = 0.0;  // points sampled; those of them whose plans are kept
  for (size_t u = 0; u < units.size(); u += stride) {
    sample_roots.push_back(units[u]);
    sample_task.push_back(task_of[u]);
    const double points =
        static_cast<double>(size_of(p.ot->nodes()[static_cast<size_t>(units[u])]));
    covered += points;
    if (task_of[u] >= 0) kept += points;
  }
  outer_bounds(p, sample_roots, set.threads);
  std::atomic<double> spent{0.0};
  std::atomic<bool> stopped{false};
  std::vector<double> sampled(sample_roots.size(), 0.0);
  std::vector<std::vector<Interaction>> sample_lists(sample_roots.size());
  std::int64_t visits = 0, axes = 0;  // the sample's planning work
#pragma omp parallel for schedule(dynamic, 1) num_threads(set.threads) reduction(+ : visits, axes)
  for (size_t i = 0; i < sample_roots.size(); ++i) {
    if (stopped.load()) continue;
    if (!plan_root(p, sample_roots[i], &spent, limit * covered / n_all, &sampled[i],
                   &sample_lists[i], &visits, &axes))
      stopped = true;
  }
  counts += {visits, axes};
  // stopped, the sample's planned work (with its outer grids' basis work), its points,
  // points kept, its planning work, its source grids' basis work
  double totals[6] = {
      stopped ? 1.0 : 0.0, 0.0, covered, kept, planning_cost(p, {visits, axes}, covered), 0.0};
  if (!stopped) sample_basis(p, sample_lists, totals[1], totals[5]);
  for (const double w : sampled) totals[1] += w;
  if (set.share != nullptr) set.share->sum(totals, 6);
  if (totals[0] > 0.0) return true;
  for (size_t i = 0; i < sample_roots.size(); ++i) {
    const auto r = static_cast<size_t>(sample_task[i]);
    if (sample_task[i] < 0) continue;
    work[r] = sampled[i], lists[r] = std::move(sample_lists[i]), done[r] = 1;
  }
  if (!(totals[2] > 0.0)) return false;
  // The work left if the plan goes on: the whole plan's (predicted), the planning of every
  // point whose plan is not kept, at the sample's planning work per point, and at least
  // the sample's source grids (shared by every outer box, so not scaled).
  return (totals[1] * n_all + totals[4] * (n_all - totals[3])) / totals[2] + totals[5] > limit;
}

bool plan_tasks(Pass& p, const std::vector<int>& roots, UnitRange mine, double all_pairs,
                const PassSettings& set, std::vector<std::vector<Interaction>>& lists,
                std::vector<double>& work, PlanCounts& counts) {
  std::vector<char> done(roots.size(), 0);  // planned by the sample
  if (all_pairs < kInf &&
      sample_exceeds(p, roots, mine, kFallBack * all_pairs, set, lists, work, done, counts))
    return false;
  std::vector<int> rest;
  double planned = 0.0;
  for (size_t r = mine.first; r < mine.last; ++r)
    if (done[r])
      planned += work[r];
    else
      rest.push_back(roots[r]);
  outer_bounds(p, rest, set.threads);
  std::atomic<double> spent{planned};
  std::atomic<bool> stopped{false};
  std::int64_t visits = 0, axes = 0;
#pragma omp parallel for schedule(dynamic, 1) num_threads(set.threads) reduction(+ : visits, axes)
  for (size_t r = mine.first; r < mine.last; ++r) {
    if (done[r] || stopped.load()) continue;
    if (!plan_root(p, roots[r], &spent, kFallBackPlanned * all_pairs, &work[r], &lists[r], &visits,
                   &axes))
      stopped = true;
  }
  counts += {visits, axes};
  double verdict = stopped ? 1.0 : 0.0;
  if (set.share != nullptr) set.share->sum(&verdict, 1);
  return verdict == 0.0;
}

UnitRange rebalance(Pass& p, const std::vector<int>& roots, UnitRange planned,
                    const PassSettings& set, std::vector<std::vector<Interaction>>& lists,
                    std::vector<double>& work, PlanCounts& counts) {
  set.share->sum(work.data(), work.size());
  const UnitRange mine = share_of(set, work);
  std::vector<int> moved;  // tasks new to this process: their outer points bounded first
  for (size_t r = mine.first; r < mine.last; ++r)
    if (r < planned.first || r >= planned.last) moved.push_back(roots[r]);
  outer_bounds(p, moved, set.threads);
  for (size_t r = 0; r < roots.size(); ++r) {
    const bool run = r >= mine.first && r < mine.last;
    const bool had = r >= planned.first && r < planned.last;
    if (!run) std::vector<Interaction>().swap(lists[r]);
    if (!run || had) continue;
    PlanState st;
    std::atomic<double> spent{0.0};
    st.spent = &spent;
    Ledger ledger;
    plan(p, roots[r], 0, st, ledger);
    counts += st.counts;
    lists[r] = std::move(st.out);
  }
  return mine;
}

}  // namespace softhd::detail::dual
