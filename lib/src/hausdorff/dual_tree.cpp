#include "dual_tree.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <vector>

#include "chebyshev.hpp"

namespace softhd::detail {

int degree_for(double tau) {
  const int n = static_cast<int>(std::lround(2.0 + std::log10(1.0 / tau)));
  return std::clamp(n, 3, 12);
}

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
enum Op : std::uint8_t { kP2P, kM2P, kP2L, kM2L, kPrune, kNone };
enum Kind { kS = 0, kG = 1, kH = 2, kG2 = 3 };  // the four sums; budgets per kind

// Cost model: work per unit relative to one pair of the all-pairs kernel (docs/tree_tolerance.md
// §8).
constexpr double kCostNear = 1.3;    // direct pairs in short slices (leaf pairs)
constexpr double kCostFar = 1.0;     // kernel evaluations at interpolation points
constexpr double kCostBasis = 0.3;   // point-interpolation-point basis products
constexpr double kFallBack = 0.8;    // the plan must cost < 80 % of all pairs
constexpr size_t kSampleStride = 8;  // planning tasks sampled to predict the plan's work

struct Interaction {
  int t, s;
  Op op;
};

/// Sums accumulated for one outer point or one interpolation point of an outer box.
struct Acc {
  double S = 0.0, G[3] = {0.0, 0.0, 0.0}, H = 0.0, G2[3] = {0.0, 0.0, 0.0};
  void add(const PairSums& s, double f = 1.0) {
    S += f * s.S;
    H += s.H;
    for (int k = 0; k < 3; ++k) {
      G[k] += f * s.G[k];
      G2[k] += s.G2[k];
    }
  }
};

/// The interpolation points of one source box (tree slot) and their weights.
struct ProxySet {
  std::vector<double> coord;             // d blocks of P coordinates
  std::vector<double> weight, coef, sc;  // P each
};

Box bounds_box(const KdNode& n, int d) {
  Box b;
  for (int k = 0; k < d; ++k) {
    b.c[k] = 0.5 * (n.lo[k] + n.hi[k]);
    b.a[k] = 0.5 * (n.hi[k] - n.lo[k]);
  }
  return b;
}

double node_gap(const KdNode& a, const KdNode& b, int d) {
  double g2 = 0.0;
  for (int k = 0; k < d; ++k) {
    const double gap = std::max({a.lo[k] - b.hi[k], b.lo[k] - a.hi[k], 0.0});
    g2 += gap * gap;
  }
  return std::sqrt(g2);
}

double node_radius2(const KdNode& a, int d) {
  double r2 = 0.0;
  for (int k = 0; k < d; ++k) r2 += (a.hi[k] - a.lo[k]) * (a.hi[k] - a.lo[k]);
  return r2;
}

Eigen::Index size_of(const KdNode& n) { return n.end - n.begin; }

/// Everything one pass needs, in the trees' orders.
struct Pass {
  const KdTree* ot = nullptr;  // outer tree
  const KdTree* st = nullptr;  // source tree
  DualTreeConfig cfg;
  int d = 3, n = 8, P = 512;
  unsigned flags = 0;
  bool want[4] = {false, false, false, false};
  double alpha = 4.0, eps = 1e-3, log_tau = 0.0;
  const KernelPower* power = nullptr;
  Eigen::VectorXd w, h, c, oc;  // source weights, coefficients, scales; outer scales
  std::vector<NodeMoments> mw, mh;
  PairSources src;
  std::vector<double> log_low;    // 4 per outer node: log min_{o∈T} of the unscaled lower bound
  bool point_prune = false;       // pruning regime: leaf pairs also pruned point by point
  std::vector<double> point_low;  // 4 per outer point (tree order, point_prune only)
  std::vector<double> kappa;      // per outer node: max c_o (scale of its locals)
  std::vector<double> cmin;       // per outer node: min c_o
  std::vector<int> cut;           // source nodes of the lower bounds (cut_nodes)
  std::vector<char> has_local, has_proxy;
  std::vector<double> log_weight, log_share;  // 4 per source node (prepare_sources)
  std::vector<Box> obox, sbox;                // interpolation boxes (eligible nodes)
  int nf = 0;                                 // fields of an outer box's locals (P values each):
  int field[4] = {-1, -1, -1, -1};            // first field of S, G (d), H, G2 (d), or −1
  double log_total[4] = {0.0, 0.0, 0.0, 0.0};
  ChebyshevRule rule{2};

  bool outer_kinds() const { return want[kS] || want[kG]; }
  PairSources slice(const KdNode& s) const {
    PairSources sub = src;
    sub.size = size_of(s);
    for (int k = 0; k < d; ++k) sub.coord[k] += s.begin;
    if (sub.weight != nullptr) sub.weight += s.begin;
    if (sub.coef != nullptr) sub.coef += s.begin;
    if (sub.scale != nullptr) sub.scale += s.begin;
    return sub;
  }
};

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
  const bool interp = p.alpha <= p.cfg.max_interp_alpha;
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
  p.has_proxy.assign(nodes.size(), 0);
  p.sbox.resize(nodes.size());
  for (size_t i = 0; i < nodes.size(); ++i) {
    if (!interp || size_of(nodes[i]) <= p.P) continue;
    p.has_proxy[i] = 1;
    p.sbox[i] = interpolation_box(nodes[i].lo, nodes[i].hi, p.d);
  }
}

constexpr int kCutDepth = 5;  // the lower bounds' coarse partition: source nodes at this depth

/// Greedy descent to a source leaf near q (any leaf gives a valid lower bound); `cut`
/// receives its ancestor at depth kCutDepth (or the leaf, if shallower).
int leaf_near(const KdTree& st, const double* q, int d, int& cut) {
  const std::vector<KdNode>& nodes = st.nodes();
  int id = 0, depth = 0;
  cut = 0;
  while (nodes[static_cast<size_t>(id)].right >= 0) {
    if (depth == kCutDepth) cut = id;
    const int l = id + 1, r = nodes[static_cast<size_t>(id)].right;
    double dl = 0.0, dr = 0.0;
    for (int k = 0; k < d; ++k) {
      const KdNode& a = nodes[static_cast<size_t>(l)];
      const KdNode& b = nodes[static_cast<size_t>(r)];
      const double ga = std::max({a.lo[k] - q[k], q[k] - a.hi[k], 0.0});
      const double gb = std::max({b.lo[k] - q[k], q[k] - b.hi[k], 0.0});
      dl += ga * ga;
      dr += gb * gb;
    }
    id = dl <= dr ? l : r;
    ++depth;
  }
  if (depth <= kCutDepth) cut = id;
  return id;
}

/// The source nodes at depth kCutDepth, and the leaves above it: a partition.
void cut_nodes(const KdTree& st, int id, int depth, std::vector<int>& out) {
  const KdNode& n = st.nodes()[static_cast<size_t>(id)];
  if (depth == kCutDepth || n.right < 0) {
    out.push_back(id);
    return;
  }
  cut_nodes(st, id + 1, depth + 1, out);
  cut_nodes(st, n.right, depth + 1, out);
}

/// Lower bounds (scaled, as pair_sums returns them) of the four sums at o: over the
/// partition `cut`, each node contributes W k(R_max) (every term is ≥ its value at the
/// farthest corner; the vector sums only from boxes not containing o, whose terms all
/// have r > 0), except the node `near_cut` holding `leaf`, which contributes the larger
/// of that and the exact sum over `leaf`.
PairSums lower_sums(const Pass& p, const double* o, double c_o, const std::vector<int>& cut,
                    int near_cut, const PairSums& leaf) {
  PairSums low;
  const std::vector<KdNode>& nodes = p.st->nodes();
  for (int id : cut) {
    const KdNode& n = nodes[static_cast<size_t>(id)];
    double near2 = 0.0, far2 = 0.0;
    for (int k = 0; k < p.d; ++k) {
      const double gap = std::max({n.lo[k] - o[k], o[k] - n.hi[k], 0.0});
      const double span = std::max(std::fabs(o[k] - n.lo[k]), std::fabs(o[k] - n.hi[k]));
      near2 += gap * gap;
      far2 += span * span;
    }
    const double t = 1.0 / (std::sqrt(far2) + p.eps), inside = near2 > 0.0 ? 1.0 : 0.0;
    PairSums b;
    if (p.outer_kinds()) {
      b.S = p.mw[static_cast<size_t>(id)].weight * p.power->scalar(c_o * t);
      b.Gm = inside * b.S * t;
    }
    if (p.want[kH]) {
      const NodeMoments& m = p.mh[static_cast<size_t>(id)];
      b.H = m.weight * p.power->scalar(m.scale * t);
      b.G2m = inside * b.H * t;
    }
    if (id == near_cut) {
      b.S = std::max(b.S, leaf.S);
      b.Gm = std::max(b.Gm, leaf.Gm);
      b.H = std::max(b.H, leaf.H);
      b.G2m = std::max(b.G2m, leaf.G2m);
    }
    low.S += b.S;
    low.Gm += b.Gm;
    low.H += b.H;
    low.G2m += b.G2m;
  }
  return low;
}

/// The outer data every task shares: scales in tree order and room for the per-node
/// bounds (outer_bounds fills them for the tasks a process plans).
void prepare_outer(Pass& p, const PassOuter& in) {
  const KdTree& ot = *p.ot;
  const size_t nn = ot.nodes().size();
  p.oc = ot.permute(Eigen::Map<const Eigen::VectorXd>(in.scale, ot.size()));
  p.log_low.assign(4 * nn, kInf);
  if (p.point_prune) p.point_low.assign(4 * static_cast<size_t>(ot.size()), kInf);
  p.kappa.assign(nn, 0.0);
  p.cmin.assign(nn, kInf);
  p.has_local.assign(nn, 0);
  p.obox.resize(nn);
  cut_nodes(*p.st, 0, 0, p.cut);
}

int subtree_end(const KdTree& tree, int id);

/// Lower bounds of the sums of every outer point in the subtrees of `roots` (lower_sums
/// with the source leaf found by descending towards the point), their minima per outer
/// node, and the locals' scales, for those subtrees' nodes: the planning of a task reads
/// nothing else, so a process bounds only the tasks it plans.
void outer_bounds(Pass& p, const std::vector<int>& roots, int threads) {
  const KdTree& ot = *p.ot;
  const std::vector<KdNode>& nodes = ot.nodes();
  std::vector<int> leaves;
  for (const int root : roots) {
    const int end = subtree_end(ot, root);
    for (int id = root; id < end; ++id)
      if (nodes[static_cast<size_t>(id)].right < 0) leaves.push_back(id);
  }
  const Eigen::MatrixXd& X = ot.points();
  const unsigned flags = p.flags | kMagnitude;
  const double w_min = p.outer_kinds() ? p.w.minCoeff() : 0.0;
#pragma omp parallel for schedule(dynamic, 8) num_threads(threads)
  for (size_t l = 0; l < leaves.size(); ++l) {
    const size_t id = static_cast<size_t>(leaves[l]);
    const KdNode& T = nodes[id];
    for (Eigen::Index q = T.begin; q < T.end; ++q) {
      double o[3] = {0.0, 0.0, 0.0};
      for (int k = 0; k < p.d; ++k) o[k] = X(q, k);
      int near_cut = 0;
      const int leaf_id = leaf_near(*p.st, o, p.d, near_cut);
      const PairSources leaf = p.slice(p.st->nodes()[static_cast<size_t>(leaf_id)]);
      const PairSums exact = pair_sums(o, p.oc[q], leaf, *p.power, p.eps, flags);
      PairSums s = lower_sums(p, o, p.oc[q], p.cut, near_cut, exact);
      // The nearest source (r = r_min, so p = 1) alone gives S ≥ w_min, and, when
      // r_min > 0, Gm ≥ w_min/c_o: the bound that matters at large α.
      s.S = std::max(s.S, w_min);
      if (p.oc[q] > p.eps) s.Gm = std::max(s.Gm, w_min / p.oc[q]);
      const double lc = p.alpha * std::log(p.oc[q]);
      const double v[4] = {std::log(s.S) - lc, std::log(s.Gm) - lc, std::log(s.H), std::log(s.G2m)};
      for (int k = 0; k < 4; ++k) p.log_low[4 * id + k] = std::min(p.log_low[4 * id + k], v[k]);
      if (p.point_prune) std::copy(v, v + 4, &p.point_low[4 * static_cast<size_t>(q)]);
      p.kappa[id] = std::max(p.kappa[id], p.oc[q]);
      p.cmin[id] = std::min(p.cmin[id], p.oc[q]);
    }
  }
  const bool interp = p.alpha <= p.cfg.max_interp_alpha;
  for (const int root : roots) {
    for (size_t id = static_cast<size_t>(subtree_end(ot, root));
         id-- > static_cast<size_t>(root);) {
      const KdNode& T = nodes[id];  // children follow their parents
      if (T.right >= 0) {
        const size_t l = id + 1, r = static_cast<size_t>(T.right);
        for (int k = 0; k < 4; ++k)
          p.log_low[4 * id + k] = std::min(p.log_low[4 * l + k], p.log_low[4 * r + k]);
        p.kappa[id] = std::max(p.kappa[l], p.kappa[r]);
        p.cmin[id] = std::min(p.cmin[l], p.cmin[r]);
      }
      // Locals carry (κ_T t)^α; the factor (c_o/κ_T)^α must not underflow.
      const bool scales_ok = p.alpha * (std::log(p.kappa[id]) - std::log(p.cmin[id])) <= 300.0;
      if (!interp || size_of(nodes[id]) <= p.P || !scales_ok) continue;
      p.has_local[id] = 1;
      p.obox[id] = interpolation_box(nodes[id].lo, nodes[id].hi, p.d);
    }
  }
}

/// The cheapest admissible approximation of pair (t, s), or kNone.
Op choose(const Pass& p, int t, int s, double gap) {
  const KdNode& T = p.ot->nodes()[static_cast<size_t>(t)];
  const KdNode& S = p.st->nodes()[static_cast<size_t>(s)];
  double lb[4], lw[4];
  for (int k = 0; k < 4; ++k) {
    lw[k] = p.log_weight[4 * static_cast<size_t>(s) + k];
    lb[k] = lw[k] == -kInf ? kInf
                           : p.log_tau + p.log_low[4 * static_cast<size_t>(t) + k] +
                                 p.log_share[4 * static_cast<size_t>(s) + k];
  }
  auto fits = [&](double lv, double lg) {
    for (int k = 0; k < 4; ++k)
      if (p.want[k] && !(lw[k] + ((k == kS || k == kH) ? lv : lg) <= lb[k])) return false;
    return true;
  };
  const double l = std::log(gap + p.eps);
  if (fits(-p.alpha * l, -(p.alpha + 1.0) * l)) return kPrune;
  const double nT = static_cast<double>(size_of(T)), nS = static_cast<double>(size_of(S));
  const double P = p.P, direct = nT * nS;
  struct Option {
    double cost;
    Op op;
  } options[3];
  int count = 0;
  const bool m_ok = p.has_proxy[static_cast<size_t>(s)], l_ok = p.has_local[static_cast<size_t>(t)];
  if (m_ok && l_ok && P * P < direct) options[count++] = {P * P, kM2L};
  if (m_ok && nT * P < direct) options[count++] = {nT * P, kM2P};
  if (l_ok && P * nS < direct) options[count++] = {P * nS, kP2L};
  std::sort(options, options + count,
            [](const Option& a, const Option& b) { return a.cost < b.cost; });
  const Box tb = bounds_box(T, p.d), sb = bounds_box(S, p.d);
  for (int i = 0; i < count; ++i) {
    const bool it = options[i].op != kM2P, is = options[i].op != kP2L;
    // Cheap necessary condition: every bound of the operation is at least the
    // one-axis bound of its widest interpolated axis (half-width a), with
    // |u| ≥ (gap + ε)^(−α) and the largest ellipse the bound searches,
    // ρ ≤ √2 R/a + 1, R the largest distance between the two boxes (chebyshev.cpp).
    const Box& bt = it ? p.obox[static_cast<size_t>(t)] : tb;
    const Box& bs = is ? p.sbox[static_cast<size_t>(s)] : sb;
    double a_max = 0.0, far2 = 0.0;
    for (int k = 0; k < p.d; ++k) {
      if (it) a_max = std::max(a_max, bt.a[k]);
      if (is) a_max = std::max(a_max, bs.a[k]);
      const double span = std::fabs(bt.c[k] - bs.c[k]) + bt.a[k] + bs.a[k];
      far2 += span * span;
    }
    const double rho = std::sqrt(2.0 * far2) / a_max + 1.0;
    const double least =
        std::log(4.0) - p.alpha * l - (p.n - 1) * std::log(rho) - std::log(rho - 1.0);
    if (!fits(least, least - l)) continue;
    const LogBounds e = interpolation_log_bound(bt, it, bs, is, p.d, p.n, p.alpha, p.eps);
    if (fits(e.value, e.grad)) return options[i].op;
  }
  return kNone;
}

/// Whether source node s may be dropped for the outer point o (tree position q) alone:
/// the prune test of choose() with o's own lower bounds and its own distance to the box.
/// The boxes dropped for o are still disjoint, so the budget argument is unchanged.
bool prunable_for_point(const Pass& p, const double* o, Eigen::Index q, int s) {
  const KdNode& S = p.st->nodes()[static_cast<size_t>(s)];
  double g2 = 0.0;
  for (int k = 0; k < p.d; ++k) {
    const double gap = std::max({S.lo[k] - o[k], o[k] - S.hi[k], 0.0});
    g2 += gap * gap;
  }
  const double l = std::log(std::sqrt(g2) + p.eps);
  for (int k = 0; k < 4; ++k) {
    if (!p.want[k]) continue;
    const double lw = p.log_weight[4 * static_cast<size_t>(s) + k];
    if (lw == -kInf) continue;
    const double lb = p.log_tau + p.point_low[4 * static_cast<size_t>(q) + k] +
                      p.log_share[4 * static_cast<size_t>(s) + k];
    if (!(lw - ((k == kS || k == kH) ? p.alpha : p.alpha + 1.0) * l <= lb)) return false;
  }
  return true;
}

/// One task's planning state. `spent` is shared by the tasks: the planned near and far
/// work so far (in pair units, kCost weights). It is a lower bound of the plan's total,
/// so once it exceeds `limit` the pass will be summed exactly whatever the order of the
/// tasks, and planning stops.
struct PlanState {
  std::vector<Interaction> out;
  std::int64_t visits = 0;
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
  void add(const Pass& p, int t, int s, Op op) {
    out.push_back({t, s, op});
    const double nT = static_cast<double>(size_of(p.ot->nodes()[static_cast<size_t>(t)]));
    const double nS = static_cast<double>(size_of(p.st->nodes()[static_cast<size_t>(s)]));
    const double P = p.P;
    double w = 0.0;
    if (op == kP2P) w = kCostNear * nT * nS;
    if (op == kM2P) w = kCostFar * nT * P;
    if (op == kP2L) w = kCostFar * P * nS;
    if (op == kM2L) w = kCostFar * P * P;
    pending += w;
    total += w;
  }
};

/// Depth-first dual traversal from (t, s): appends the interactions to `st.out`. Returns
/// false when planning was stopped (the plan costs more than the limit).
bool plan(const Pass& p, int t, int s, PlanState& st) {
  ++st.visits;
  const KdNode& T = p.ot->nodes()[static_cast<size_t>(t)];
  const KdNode& S = p.st->nodes()[static_cast<size_t>(s)];
  const bool outer_mass = p.outer_kinds() && p.mw[static_cast<size_t>(s)].mass > 0.0;
  const bool inner_mass = p.want[kH] && p.mh[static_cast<size_t>(s)].mass > 0.0;
  if (!outer_mass && !inner_mass) return true;  // every term is zero
  const double gap = node_gap(T, S, p.d);
  if (gap > 0.0) {
    const Op op = choose(p, t, s, gap);
    if (op != kNone) {
      st.add(p, t, s, op);
      return !st.stop();
    }
  }
  const bool tl = T.right < 0, sl = S.right < 0;
  // Small pairs at low α are summed at once (their children would not be pruned either);
  // at large α leaf pairs are worth pruning one by one.
  const std::int64_t small = p.alpha <= p.cfg.max_interp_alpha ? p.cfg.small_pairs : 0;
  if ((tl && sl) || size_of(T) * size_of(S) <= small) {
    st.add(p, t, s, kP2P);
    return !st.stop();
  }
  if (sl || (!tl && node_radius2(T, p.d) >= node_radius2(S, p.d)))
    return plan(p, t + 1, s, st) && plan(p, T.right, s, st);
  return plan(p, t, s + 1, st) && plan(p, t, S.right, st);
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

/// The tensor grid of interpolation points of box b (d blocks of P coordinates).
std::vector<double> grid_points(const Pass& p, const Box& b) {
  std::vector<double> x(static_cast<size_t>(p.d * p.P));
  for (int q = 0; q < p.P; ++q) {
    int rest = q;
    for (int k = p.d - 1; k >= 0; --k) {
      x[static_cast<size_t>(k * p.P + q)] = b.c[k] + b.a[k] * p.rule.xi[rest % p.n];
      rest /= p.n;
    }
  }
  return x;
}

/// The tensor basis values L_q(x) of box b at point x (P values, same order as grid_points).
void tensor_basis(const Pass& p, const Box& b, const double* x, double* L) {
  double axis[3][kMaxChebyshev];
  for (int k = 0; k < p.d; ++k) p.rule.basis((x[k] - b.c[k]) / b.a[k], axis[k]);
  if (p.d == 2) {
    for (int i = 0; i < p.n; ++i)
      for (int j = 0; j < p.n; ++j) L[i * p.n + j] = axis[0][i] * axis[1][j];
    return;
  }
  for (int i = 0; i < p.n; ++i)
    for (int j = 0; j < p.n; ++j) {
      const double lij = axis[0][i] * axis[1][j];
      double* row = L + (i * p.n + j) * p.n;
      for (int l = 0; l < p.n; ++l) row[l] = lij * axis[2][l];
    }
}

/// Anterpolation into source box s: adds the points [begin, end) to the weights at its
/// interpolation points, W_q += Σ_x w_x L_q(x) and, for inner sums, Σ_x h̃_x L_q(x) with
/// h̃ = h (c/C)^α, C = the box's scale.
void anterpolate(const Pass& p, int s, Eigen::Index begin, Eigen::Index end, ProxySet& ps) {
  const Box& b = p.sbox[static_cast<size_t>(s)];
  const size_t P = static_cast<size_t>(p.P);
  std::vector<double> L(P);
  const Eigen::MatrixXd& X = p.st->points();
  for (Eigen::Index q = begin; q < end; ++q) {
    double x[3] = {0.0, 0.0, 0.0};
    for (int k = 0; k < p.d; ++k) x[k] = X(q, k);
    tensor_basis(p, b, x, L.data());
    if (p.outer_kinds())
      for (size_t j = 0; j < P; ++j) ps.weight[j] += p.w[q] * L[j];
    if (p.want[kH]) {
      const double ht = p.h[q] * p.power->scalar(p.c[q] / ps.sc[0]);
      for (size_t j = 0; j < P; ++j) ps.coef[j] += ht * L[j];
    }
  }
}

/// The proxies of source box s: from its marked children by translation (M2M; an inner
/// weight is rescaled by (C_child/C)^α ≤ 1), from the points of the others.
void source_proxies(const Pass& p, int s, const std::vector<int>& sslot,
                    std::vector<ProxySet>& sprox) {
  const KdNode& S = p.st->nodes()[static_cast<size_t>(s)];
  ProxySet& ps = sprox[static_cast<size_t>(sslot[static_cast<size_t>(s)])];
  const size_t P = static_cast<size_t>(p.P);
  ps.coord = grid_points(p, p.sbox[static_cast<size_t>(s)]);
  if (p.outer_kinds()) ps.weight.assign(P, 0.0);
  if (p.want[kH]) {
    ps.coef.assign(P, 0.0);
    ps.sc.assign(P, p.mh[static_cast<size_t>(s)].scale);
  }
  if (S.right < 0) {
    anterpolate(p, s, S.begin, S.end, ps);
    return;
  }
  for (const int ch : {s + 1, S.right}) {
    const KdNode& C = p.st->nodes()[static_cast<size_t>(ch)];
    const int slot = sslot[static_cast<size_t>(ch)];
    if (slot < 0) {
      anterpolate(p, s, C.begin, C.end, ps);
      continue;
    }
    const ProxySet& cs = sprox[static_cast<size_t>(slot)];
    Translation E;
    make_translation(p.rule, p.sbox[static_cast<size_t>(s)], p.sbox[static_cast<size_t>(ch)], p.d,
                     E);
    if (p.outer_kinds()) tensor_apply(E, true, p.n, p.d, cs.weight.data(), 1.0, ps.weight.data());
    if (p.want[kH])
      tensor_apply(E, true, p.n, p.d, cs.coef.data(), p.power->scalar(cs.sc[0] / ps.sc[0]),
                   ps.coef.data());
  }
}

/// Marks node id and its descendants that are `eligible` (every descendant of an
/// ineligible node is ineligible: boxes with grids have more than P points).
void mark_subtree(const KdTree& tree, const std::vector<char>& eligible, int id,
                  std::vector<char>& mark) {
  if (!eligible[static_cast<size_t>(id)] || mark[static_cast<size_t>(id)]) return;
  mark[static_cast<size_t>(id)] = 1;
  const KdNode& n = tree.nodes()[static_cast<size_t>(id)];
  if (n.right < 0) return;
  mark_subtree(tree, eligible, id + 1, mark);
  mark_subtree(tree, eligible, n.right, mark);
}

/// Upward pass: the proxies of every marked source box, the deepest level first so that
/// every box translates from its children (deterministic: each box is computed alone).
void source_upward(const Pass& p, const std::vector<char>& mark, std::vector<int>& sslot,
                   std::vector<ProxySet>& sprox, int threads) {
  const std::vector<KdNode>& nodes = p.st->nodes();
  std::vector<int> depth(nodes.size(), 0);
  std::vector<std::vector<int>> level;
  for (size_t id = 0; id < nodes.size(); ++id) {
    if (nodes[id].right >= 0)
      depth[id + 1] = depth[static_cast<size_t>(nodes[id].right)] = depth[id] + 1;
    if (!mark[id]) continue;
    if (level.size() <= static_cast<size_t>(depth[id]))
      level.resize(static_cast<size_t>(depth[id]) + 1);
    level[static_cast<size_t>(depth[id])].push_back(static_cast<int>(id));
    sslot[id] = static_cast<int>(sprox.size());
    sprox.emplace_back();
  }
  for (size_t l = level.size(); l-- > 0;) {
    const std::vector<int>& ids = level[l];
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
    for (size_t i = 0; i < ids.size(); ++i) source_proxies(p, ids[i], sslot, sprox);
  }
}

PairSources proxy_sources(const Pass& p, const ProxySet& ps) {
  PairSources src;
  src.dim = p.d;
  src.size = p.P;
  for (int k = 0; k < p.d; ++k) src.coord[k] = ps.coord.data() + k * p.P;
  src.weight = ps.weight.empty() ? nullptr : ps.weight.data();
  src.coef = ps.coef.empty() ? nullptr : ps.coef.data();
  src.scale = ps.sc.empty() ? nullptr : ps.sc.data();
  return src;
}

/// Adds one interpolation point's sums to an outer box's locals (the requested fields).
void add_local(const Pass& p, const PairSums& s, int j, double* loc) {
  auto at = [&](int field) { return loc + static_cast<size_t>(field) * p.P + j; };
  if (p.field[kS] >= 0) *at(p.field[kS]) += s.S;
  if (p.field[kH] >= 0) *at(p.field[kH]) += s.H;
  for (int k = 0; k < p.d; ++k) {
    if (p.field[kG] >= 0) *at(p.field[kG] + k) += s.G[k];
    if (p.field[kG2] >= 0) *at(p.field[kG2] + k) += s.G2[k];
  }
}

/// L2P: the locals of outer box t interpolated to its points [begin, end), the outer sums
/// rescaled from κ_T to each point's own scale, (c_o/κ_T)^α ≤ 1.
void locals_to_points(const Pass& p, int t, Eigen::Index begin, Eigen::Index end, const double* loc,
                      std::vector<Acc>& acc) {
  const Eigen::MatrixXd& X = p.ot->points();
  const Box& b = p.obox[static_cast<size_t>(t)];
  std::vector<double> L(static_cast<size_t>(p.P));
  double v[8];
  for (Eigen::Index q = begin; q < end; ++q) {
    double o[3] = {0.0, 0.0, 0.0};
    for (int k = 0; k < p.d; ++k) o[k] = X(q, k);
    tensor_basis(p, b, o, L.data());
    for (int f = 0; f < p.nf; ++f) {
      const double* lf = loc + static_cast<size_t>(f) * p.P;
      double sum = 0.0;
#pragma omp simd reduction(+ : sum)
      for (int j = 0; j < p.P; ++j) sum += L[static_cast<size_t>(j)] * lf[j];
      v[f] = sum;
    }
    PairSums s;
    if (p.field[kS] >= 0) s.S = v[p.field[kS]];
    if (p.field[kH] >= 0) s.H = v[p.field[kH]];
    for (int k = 0; k < p.d; ++k) {
      if (p.field[kG] >= 0) s.G[k] = v[p.field[kG] + k];
      if (p.field[kG2] >= 0) s.G2[k] = v[p.field[kG2] + k];
    }
    acc[static_cast<size_t>(q)].add(s, p.power->scalar(p.oc[q] / p.kappa[static_cast<size_t>(t)]));
  }
}

/// Downward pass over one task's subtree [root, end) (parents before children): a box's
/// locals go to each child that carries locals by translation (L2L; the outer fields
/// rescaled by (κ_child/κ_T)^α ≤ 1), to the points of the others (L2P).
void downward(const Pass& p, int root, std::vector<std::vector<double>>& local,
              std::vector<Acc>& acc) {
  const std::vector<KdNode>& nodes = p.ot->nodes();
  const size_t size = static_cast<size_t>(p.nf) * p.P;
  for (size_t i = 0; i < local.size(); ++i) {
    if (local[i].empty()) continue;
    const int t = root + static_cast<int>(i);
    const KdNode& T = nodes[static_cast<size_t>(t)];
    if (T.right < 0) {
      locals_to_points(p, t, T.begin, T.end, local[i].data(), acc);
    } else {
      for (const int ch : {t + 1, T.right}) {
        const KdNode& C = nodes[static_cast<size_t>(ch)];
        if (!p.has_local[static_cast<size_t>(ch)]) {
          locals_to_points(p, t, C.begin, C.end, local[i].data(), acc);
          continue;
        }
        std::vector<double>& cl = local[static_cast<size_t>(ch - root)];
        if (cl.empty()) cl.assign(size, 0.0);
        Translation E;
        make_translation(p.rule, p.obox[static_cast<size_t>(t)], p.obox[static_cast<size_t>(ch)],
                         p.d, E);
        const double scale =
            p.power->scalar(p.kappa[static_cast<size_t>(ch)] / p.kappa[static_cast<size_t>(t)]);
        for (int f = 0; f < p.nf; ++f) {
          const bool outer = p.field[kH] < 0 || f < p.field[kH];  // S, G come before H, G2
          tensor_apply(E, false, p.n, p.d, local[i].data() + static_cast<size_t>(f) * p.P,
                       outer ? scale : 1.0, cl.data() + static_cast<size_t>(f) * p.P);
        }
      }
    }
    std::vector<double>().swap(local[i]);
  }
}

/// The end of node id's subtree in preorder (its nodes are [id, end)).
int subtree_end(const KdTree& tree, int id) {
  while (tree.nodes()[static_cast<size_t>(id)].right >= 0)
    id = tree.nodes()[static_cast<size_t>(id)].right;
  return id + 1;
}

/// Runs one task's interactions (outer subtree of `root`), then its downward pass.
/// Returns the number of direct pairs skipped by pruning point by point.
std::int64_t execute(const Pass& p, int root, const std::vector<Interaction>& list,
                     const std::vector<int>& sslot, const std::vector<ProxySet>& sprox,
                     std::vector<Acc>& acc) {
  std::int64_t skipped = 0;
  const Eigen::MatrixXd& X = p.ot->points();
  std::vector<std::vector<double>> local(static_cast<size_t>(subtree_end(*p.ot, root) - root));
  for (const Interaction& it : list) {
    const KdNode& T = p.ot->nodes()[static_cast<size_t>(it.t)];
    const KdNode& S = p.st->nodes()[static_cast<size_t>(it.s)];
    if (it.op == kPrune) continue;
    const PairSources src =
        (it.op == kP2P || it.op == kP2L)
            ? p.slice(S)
            : proxy_sources(p, sprox[static_cast<size_t>(sslot[static_cast<size_t>(it.s)])]);
    if (it.op == kP2P || it.op == kM2P) {
      const bool point_prune = it.op == kP2P && p.point_prune;
      for (Eigen::Index q = T.begin; q < T.end; ++q) {
        double o[3] = {0.0, 0.0, 0.0};
        for (int k = 0; k < p.d; ++k) o[k] = X(q, k);
        if (point_prune && prunable_for_point(p, o, q, it.s)) {
          skipped += size_of(S);
          continue;
        }
        acc[static_cast<size_t>(q)].add(pair_sums(o, p.oc[q], src, *p.power, p.eps, p.flags));
      }
      continue;
    }
    std::vector<double>& loc = local[static_cast<size_t>(it.t - root)];
    if (loc.empty()) loc.assign(static_cast<size_t>(p.nf) * p.P, 0.0);
    const std::vector<double> grid = grid_points(p, p.obox[static_cast<size_t>(it.t)]);
    const double kappa = p.kappa[static_cast<size_t>(it.t)];
    for (int j = 0; j < p.P; ++j) {
      double o[3] = {0.0, 0.0, 0.0};
      for (int k = 0; k < p.d; ++k) o[k] = grid[static_cast<size_t>(k * p.P + j)];
      add_local(p, pair_sums(o, kappa, src, *p.power, p.eps, p.flags), j, loc.data());
    }
  }
  downward(p, root, local, acc);
  return skipped;
}

/// Basis work of the boxes with grids (`mark`): a leaf interpolates at its points; an
/// inner box translates to or from each marked child (d n^(d+1) products per field) and
/// interpolates at the points of the others.
std::int64_t grid_work(const Pass& p, const KdTree& tree, const std::vector<char>& mark, int fields,
                       std::int64_t& translations) {
  std::int64_t work = 0;
  std::int64_t per_translation = p.d;
  for (int k = 0; k <= p.d; ++k) per_translation *= p.n;
  const std::vector<KdNode>& nodes = tree.nodes();
  for (size_t id = 0; id < nodes.size(); ++id) {
    if (!mark[id]) continue;
    if (nodes[id].right < 0) {
      work += size_of(nodes[id]) * p.P;
      continue;
    }
    for (const size_t ch : {id + 1, static_cast<size_t>(nodes[id].right)}) {
      if (mark[ch]) {
        work += per_translation * fields;
        ++translations;
      } else {
        work += size_of(nodes[ch]) * p.P;
      }
    }
  }
  return work;
}

/// Counts of the planned work: per-operation counts and the stats' kernel and basis work.
void count_work(const Pass& p, const std::vector<std::vector<Interaction>>& lists,
                const std::vector<char>& smark, const std::vector<char>& omark, PassStats& st,
                DualTreeOps& ops) {
  const double P = p.P;
  for (const auto& list : lists)
    for (const Interaction& it : list) {
      const double nT = static_cast<double>(size_of(p.ot->nodes()[static_cast<size_t>(it.t)]));
      const double nS = static_cast<double>(size_of(p.st->nodes()[static_cast<size_t>(it.s)]));
      switch (it.op) {
        case kP2P:
          ops.p2p++, st.near_pairs += static_cast<std::int64_t>(nT * nS);
          break;
        case kM2P:
          ops.m2p++, st.far_kernel += static_cast<std::int64_t>(nT * P);
          break;
        case kP2L:
          ops.p2l++, st.far_kernel += static_cast<std::int64_t>(P * nS);
          break;
        case kM2L:
          ops.m2l++, st.far_kernel += static_cast<std::int64_t>(P * P);
          break;
        default:
          ops.prune++;
          break;
      }
    }
  const int source_fields = (p.outer_kinds() ? 1 : 0) + (p.want[kH] ? 1 : 0);
  st.far_basis = grid_work(p, *p.st, smark, source_fields, ops.m2m) +
                 grid_work(p, *p.ot, omark, p.nf, ops.l2l);
}

/// The pass's settings, source data and outer lower bounds.
void prepare(Pass& p, const DualTreeConfig& cfg, const PassSources& src, const PassOuter& outer,
             const PassSettings& set) {
  p.ot = outer.tree;
  p.st = src.tree;
  p.cfg = cfg;
  p.d = p.ot->dim();
  p.n = cfg.degree > 0 ? cfg.degree : degree_for(set.tau);
  p.rule = ChebyshevRule(p.n);
  p.P = p.d == 2 ? p.n * p.n : p.n * p.n * p.n;
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
  p.log_tau = std::log(set.tau);
  p.power = set.power;
  p.point_prune = p.alpha > cfg.max_interp_alpha;
  prepare_sources(p, src);
  prepare_outer(p, outer);
}

/// Plans the tasks of `mine`: first every kSampleStride-th task, whose planned work, scaled
/// by the share of outer points it covers, predicts the whole plan (a fall-back then costs
/// about 1/kSampleStride of the planning), then the others. Returns false (fall back to all
/// pairs) when the predicted or the planned work exceeds `limit`. With a share, the
/// prediction and the verdict are summed over the processes (each plans its own tasks).
bool plan_tasks(const Pass& p, const std::vector<int>& roots, UnitRange mine, double limit,
                const PassSettings& set, std::vector<std::vector<Interaction>>& lists,
                std::vector<double>& work, std::int64_t& visits) {
  std::atomic<double> spent{0.0};
  std::atomic<bool> stopped{false};
  for (int phase = 0; phase < 2 && !stopped; ++phase) {
#pragma omp parallel for schedule(dynamic, 1) num_threads(set.threads) reduction(+ : visits)
    for (size_t r = mine.first; r < mine.last; ++r) {
      if ((r % kSampleStride == 0) != (phase == 0) || stopped.load()) continue;
      PlanState st;
      st.spent = &spent;
      st.limit = limit;
      if (!plan(p, roots[r], 0, st)) stopped = true;
      visits += st.visits;
      work[r] = st.total;
      lists[r] = std::move(st.out);
    }
    double totals[3] = {stopped ? 1.0 : 0.0, 0.0, 0.0};  // stopped, sampled, covered
    if (phase == 0)
      for (size_t r = mine.first; r < mine.last; ++r) {
        if (r % kSampleStride != 0) continue;
        totals[1] += work[r];
        totals[2] += static_cast<double>(size_of(p.ot->nodes()[static_cast<size_t>(roots[r])]));
      }
    if (set.share != nullptr) set.share->sum(totals, 3);
    stopped = totals[0] > 0.0;
    if (phase == 0 && !stopped && totals[2] > 0.0 &&
        totals[1] * static_cast<double>(p.ot->size()) / totals[2] > limit)
      stopped = true;
  }
  return !stopped;
}

/// Distributed passes: the tasks each process executes, split by their planned work
/// (summed over the processes; each planned its run of the tasks split by points). Tasks
/// that move are planned again by their new process (the plan of a task depends on the
/// task alone, so it is the same) after bounding their outer points; the lists of tasks
/// that left are dropped.
UnitRange rebalance(Pass& p, const std::vector<int>& roots, UnitRange planned,
                    const PassSettings& set, std::vector<std::vector<Interaction>>& lists,
                    std::vector<double>& work, std::int64_t& visits) {
  set.share->sum(work.data(), work.size());
  const UnitRange mine = share_of(set, work);
  std::vector<int> moved;
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
    plan(p, roots[r], 0, st);
    visits += st.visits;
    lists[r] = std::move(st.out);
  }
  return mine;
}

/// The boxes with grids of the interactions in `lists` (and their descendants with grids,
/// reached by M2M and L2L).
void mark_grids(const Pass& p, const std::vector<std::vector<Interaction>>& lists,
                std::vector<char>& smark, std::vector<char>& omark) {
  smark.assign(p.st->nodes().size(), 0);
  omark.assign(p.ot->nodes().size(), 0);
  for (const auto& list : lists)
    for (const Interaction& it : list) {
      if (it.op == kM2P || it.op == kM2L) mark_subtree(*p.st, p.has_proxy, it.s, smark);
      if (it.op == kP2L || it.op == kM2L) mark_subtree(*p.ot, p.has_local, it.t, omark);
    }
}

/// The union over the processes of every process's marks (for the work counts, which
/// then equal the serial pass's).
std::vector<char> union_marks(const WorkShare& share, const std::vector<char>& mark) {
  std::vector<double> m(mark.begin(), mark.end());
  share.sum(m.data(), m.size());
  std::vector<char> out(mark.size());
  for (size_t i = 0; i < m.size(); ++i) out[i] = m[i] > 0.0 ? 1 : 0;
  return out;
}

/// Counts of this process's interactions. With a share, the grid work of the union of
/// every process's marks is counted once, on the first process: summed over the
/// processes (run_pass), the counts are the serial pass's.
void count_planned(const Pass& p, const std::vector<std::vector<Interaction>>& lists,
                   const std::vector<char>& smark, const std::vector<char>& omark,
                   const PassSettings& set, PassStats& stats, DualTreeOps& ops) {
  if (set.share == nullptr) {
    count_work(p, lists, smark, omark, stats, ops);
    return;
  }
  count_work(p, lists, union_marks(*set.share, smark), union_marks(*set.share, omark), stats, ops);
  if (set.share->rank() != 0) stats.far_basis = 0;
}

/// The planned work of the whole pass (kernel evaluations weighted per operation, summed
/// over the processes of a share), for the cost model.
double planned_work(const PassStats& stats, const PassSettings& set) {
  std::int64_t counts[3] = {stats.near_pairs, stats.far_kernel, stats.far_basis};
  if (set.share != nullptr) set.share->sum(counts, 3);
  return kCostNear * static_cast<double>(counts[0]) + kCostFar * static_cast<double>(counts[1]) +
         kCostBasis * static_cast<double>(counts[2]);
}

class DualTreeBackend final : public PairSumBackend {
 public:
  DualTreeBackend(const DualTreeConfig& cfg, DualTreeOps* ops) : cfg_(cfg), ops_(ops) {}
  bool uses_trees() const override { return true; }
  PassSums sums(const PassSources& src, const PassOuter& outer,
                const PassSettings& set) const override;

 private:
  DualTreeConfig cfg_;
  DualTreeOps* ops_;
};

/// All pairs, after a plan that did not pay; the stats keep the planning's cost.
PassSums fall_back(const PassSources& src, const PassOuter& outer, const PassSettings& set,
                   std::int64_t visits, double plan_seconds) {
  PassSums out = make_exact_backend()->sums(src, outer, set);
  out.stats.fell_back = true;
  out.stats.node_pairs = visits;
  out.stats.plan_seconds = plan_seconds;
  out.stats.run_seconds += plan_seconds;
  return out;
}

PassSums DualTreeBackend::sums(const PassSources& src, const PassOuter& outer,
                               const PassSettings& set) const {
  const auto start = std::chrono::steady_clock::now();
  auto since = [](std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  };
  const double all_pairs =
      static_cast<double>(outer.points->rows()) * static_cast<double>(src.points->rows());
  if (cfg_.cost_model && all_pairs < cfg_.min_pairs) {
    PassSums out = make_exact_backend()->sums(src, outer, set);
    out.stats.fell_back = true;
    return out;
  }
  Pass p;
  prepare(p, cfg_, src, outer, set);

  std::vector<int> roots;
  task_roots(*p.ot, 0, std::max<Eigen::Index>(1024, p.ot->size() / 64), roots);
  std::vector<std::vector<Interaction>> lists(roots.size());
  std::vector<double> work(roots.size(), 0.0);
  std::int64_t visits = 0;
  const double limit = cfg_.cost_model ? kFallBack * all_pairs : kInf;
  // This process's tasks (all of them without a share): planned by points, run by work.
  std::vector<double> points(roots.size());
  for (size_t r = 0; r < roots.size(); ++r)
    points[r] = static_cast<double>(size_of(p.ot->nodes()[static_cast<size_t>(roots[r])]));
  UnitRange mine = share_of(set, points);
  outer_bounds(p, std::vector<int>(roots.begin() + mine.first, roots.begin() + mine.last),
               set.threads);
  if (!plan_tasks(p, roots, mine, limit, set, lists, work, visits))
    return fall_back(src, outer, set, visits, since(start));
  if (set.share != nullptr) mine = rebalance(p, roots, mine, set, lists, work, visits);

  std::vector<char> smark, omark;
  mark_grids(p, lists, smark, omark);
  PassStats stats;
  DualTreeOps ops;
  count_planned(p, lists, smark, omark, set, stats, ops);
  stats.node_pairs = visits;
  stats.plan_seconds = since(start);
  if (ops_ != nullptr) *ops_ = ops;
  // Cost model (docs/tree_tolerance.md §8): weights per unit of work measured against
  // the all-pairs kernel; fall back unless the plan is clearly cheaper.
  const double planned = planned_work(stats, set);
  if (cfg_.cost_model && planned > kFallBack * all_pairs)
    return fall_back(src, outer, set, visits, stats.plan_seconds);

  std::vector<int> sslot(p.st->nodes().size(), -1);
  std::vector<ProxySet> sprox;
  source_upward(p, smark, sslot, sprox, set.threads);
  std::vector<Acc> acc(static_cast<size_t>(p.ot->size()));
  std::int64_t skipped = 0;
#pragma omp parallel for schedule(dynamic, 1) num_threads(set.threads) reduction(+ : skipped)
  for (size_t r = mine.first; r < mine.last; ++r)
    skipped += execute(p, roots[r], lists[r], sslot, sprox, acc);
  stats.near_pairs -= skipped;
  if (ops_ != nullptr) ops_->point_pruned = skipped;

  const int d = p.d;
  PassSums out = allocate_sums(p.ot->size(), d, p.flags);
  const std::vector<Eigen::Index>& order = p.ot->order();
  for (size_t q = 0; q < acc.size(); ++q) {
    PairSums s;
    s.S = acc[q].S;
    s.H = acc[q].H;
    for (int k = 0; k < d; ++k) {
      s.G[k] = acc[q].G[k];
      s.G2[k] = acc[q].G2[k];
    }
    store_sums(out, order[q], s, p.flags, d);
  }
  out.stats = stats;
  out.kernel_evaluations = stats.near_pairs + stats.far_kernel;
  out.stats.run_seconds = since(start);
  return out;
}

}  // namespace

std::unique_ptr<PairSumBackend> make_dual_tree_backend(const DualTreeConfig& config,
                                                       DualTreeOps* ops) {
  return std::make_unique<DualTreeBackend>(config, ops);
}

std::unique_ptr<PairSumBackend> make_dual_tree_backend() {
  return make_dual_tree_backend(DualTreeConfig{}, nullptr);
}

}  // namespace softhd::detail
