// Evaluation of the dual-tree backend (dual_tree.hpp): planning, the cost model, the
// upward pass, each task's interactions and downward pass, and the sums in the caller's
// order.

#include "dual_tree.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <vector>

#include "dual_tree_internal.hpp"

namespace softhd::detail {

int degree_for(double tau) {
  const int n = static_cast<int>(std::lround(2.0 + std::log10(1.0 / tau)));
  return std::clamp(n, 3, 12);
}

namespace dual {
namespace {

/// A direct or M2P interaction: the sources (points or proxies) summed at every outer
/// point of T. Returns the number of direct pairs skipped by pruning point by point.
std::int64_t to_points(const Pass& p, const Interaction& it, const PairSources& src,
                       std::vector<Acc>& acc) {
  const KdNode& T = p.ot->nodes()[static_cast<size_t>(it.t)];
  const Eigen::MatrixXd& X = p.ot->points();
  const bool point_prune = it.op == kP2P && p.point_prune;
  std::int64_t skipped = 0;
  for (Eigen::Index q = T.begin; q < T.end; ++q) {
    double o[3] = {0.0, 0.0, 0.0};
    for (int k = 0; k < p.d; ++k) o[k] = X(q, k);
    if (point_prune && prunable_for_point(p, o, q, it.s)) {
      skipped += src.size;
      continue;
    }
    acc[static_cast<size_t>(q)].add(pair_sums(o, p.oc[q], src, *p.power, p.eps, p.flags));
  }
  return skipped;
}

/// A P2L or M2L interaction: the sources summed at T's interpolation points (degree m),
/// into T's locals (scale κ_T).
void to_locals(const Pass& p, const Interaction& it, const PairSources& src, double* loc) {
  const int m = it.deg, P = p.local_points(it.t, m);
  const std::vector<double> grid = grid_points(p, p.obox[static_cast<size_t>(it.t)], m);
  const double kappa = p.kappa[static_cast<size_t>(it.t)];
  for (int j = 0; j < P; ++j) {
    double o[3] = {0.0, 0.0, 0.0};
    for (int k = 0; k < p.d; ++k) o[k] = grid[static_cast<size_t>(k * P + j)];
    add_local(p, pair_sums(o, kappa, src, *p.power, p.eps, p.flags), j, P, loc);
  }
}

/// Runs one task's interactions (outer subtree of `root`), then its downward pass.
/// Returns the number of direct pairs skipped by pruning point by point.
std::int64_t execute(const Pass& p, int root, const std::vector<Interaction>& list,
                     const SourceProxies& sp, std::vector<Acc>& acc) {
  std::int64_t skipped = 0;
  const size_t nodes = static_cast<size_t>(subtree_end(*p.ot, root) - root);
  std::vector<std::vector<double>> local(nodes * static_cast<size_t>(p.n + 1));
  for (size_t i = 0; i < list.size(); ++i) {
    const Interaction& it = list[i];
    if (it.op == kPrune) continue;
    const KdNode& S = p.st->nodes()[static_cast<size_t>(it.s)];
    if (it.op == kP2P && !p.point_prune) {
      // The direct sums of T over this leaf and the next ones of T whose sources follow
      // on in the source order: one loop per outer point over the whole run.
      Eigen::Index begin = S.begin, end = S.end;
      for (; i + 1 < list.size() && list[i + 1].op == kP2P && list[i + 1].t == it.t; ++i) {
        const KdNode& next = p.st->nodes()[static_cast<size_t>(list[i + 1].s)];
        if (next.begin == end) {
          end = next.end;
        } else if (next.end == begin) {
          begin = next.begin;
        } else {
          break;
        }
      }
      to_points(p, it, p.range(begin, end), acc);
      continue;
    }
    const bool points = it.op == kP2P || it.op == kP2L;
    const PairSources src = points ? p.slice(S) : proxy_sources(p, sp.at(p, it.s, it.deg));
    if (it.op == kP2P || it.op == kM2P) {
      skipped += to_points(p, it, src, acc);
      continue;
    }
    std::vector<double>& loc = local[p.slot(it.t - root, it.deg)];
    if (loc.empty()) loc.assign(static_cast<size_t>(p.nf * p.local_points(it.t, it.deg)), 0.0);
    to_locals(p, it, src, loc.data());
  }
  downward(p, root, local, acc);
  return skipped;
}

/// Counts of the planned work: per-operation counts and the stats' kernel and basis work.
void count_work(const Pass& p, const std::vector<std::vector<Interaction>>& lists,
                const std::vector<char>& smark, const std::vector<char>& omark, PassStats& st,
                DualTreeOps& ops) {
  for (const auto& list : lists)
    for (const Interaction& it : list) {
      const double nT = static_cast<double>(size_of(p.ot->nodes()[static_cast<size_t>(it.t)]));
      const double nS = static_cast<double>(size_of(p.st->nodes()[static_cast<size_t>(it.s)]));
      if (it.op != kP2P && it.op != kPrune) {
        ops.far_degree[it.deg]++;
        const int full = it.deg * it.deg * (p.d == 3 ? it.deg : 1);
        const bool thin_s = it.op != kP2L && p.proxy_points(it.s, it.deg) < full;
        const bool thin_t = it.op != kM2P && p.local_points(it.t, it.deg) < full;
        if (thin_s || thin_t) ops.thin++;
      }
      switch (it.op) {
        case kP2P:
          ops.p2p++, st.near_pairs += static_cast<std::int64_t>(nT * nS);
          break;
        case kM2P:
          ops.m2p++;
          st.far_kernel += static_cast<std::int64_t>(nT * p.proxy_points(it.s, it.deg));
          break;
        case kP2L:
          ops.p2l++;
          st.far_kernel += static_cast<std::int64_t>(p.local_points(it.t, it.deg) * nS);
          break;
        case kM2L:
          ops.m2l++;
          st.far_kernel +=
              std::int64_t{p.local_points(it.t, it.deg)} * p.proxy_points(it.s, it.deg);
          break;
        default:
          ops.prune++;
          break;
      }
    }
  st.far_basis = grid_work(p, *p.st, p.sbox, smark, p.source_fields(), ops.m2m) +
                 grid_work(p, *p.ot, p.obox, omark, p.nf, ops.l2l);
}

double since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// All pairs, after a plan that did not pay; the stats keep the planning's cost.
PassSums fall_back(const PassSources& src, const PassOuter& outer, const PassSettings& set,
                   const PlanCounts& planning, double plan_seconds) {
  PassSums out = make_exact_backend()->sums(src, outer, set);
  out.stats.fell_back = true;
  out.stats.node_pairs = planning.visits;
  out.stats.bound_axes = planning.axes;
  out.stats.plan_seconds = plan_seconds;
  out.stats.run_seconds += plan_seconds;
  return out;
}

/// The accumulated sums, from the outer tree's order to the caller's.
PassSums gather(const Pass& p, const std::vector<Acc>& acc) {
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
  return out;
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

/// The counts of the planned work (with a share: of this process's interactions, with the
/// grid work of the union of the marks counted once, on the first process).
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

/// The far field and the near field of a planned pass (the tasks of `mine`); returns the
/// direct pairs skipped by pruning point by point.
std::int64_t run_plan(const Pass& p, const std::vector<int>& roots, UnitRange mine,
                      const std::vector<std::vector<Interaction>>& lists,
                      const std::vector<char>& smark, const std::vector<char>& sderive, int threads,
                      std::vector<Acc>& acc) {
  SourceProxies sp;
  source_upward(p, smark, sderive, sp, threads);
  // The largest tasks first (planned work), so that the last ones to finish are small.
  // Each task writes only its own outer points: the order does not change the result.
  std::vector<double> work(roots.size(), 0.0);
  std::vector<size_t> order;
  for (size_t r = mine.first; r < mine.last; ++r) {
    for (const Interaction& it : lists[r]) work[r] += interaction_cost(p, it);
    order.push_back(r);
  }
  std::stable_sort(order.begin(), order.end(),
                   [&work](size_t a, size_t b) { return work[a] > work[b]; });
  std::int64_t skipped = 0;
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads) reduction(+ : skipped)
  for (size_t i = 0; i < order.size(); ++i) {
    const size_t r = order[i];
    skipped += execute(p, roots[r], lists[r], sp, acc);
  }
  return skipped;
}

class DualTreeBackend final : public PairSumBackend {
 public:
  DualTreeBackend(const DualTreeConfig& cfg, DualTreeOps* ops) : cfg_(cfg), ops_(ops) {}
  PassSums sums(const PassSources& src, const PassOuter& outer,
                const PassSettings& set) const override;

 private:
  DualTreeConfig cfg_;
  DualTreeOps* ops_;
};

PassSums DualTreeBackend::sums(const PassSources& src, const PassOuter& outer,
                               const PassSettings& set) const {
  const auto start = std::chrono::steady_clock::now();
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
  task_roots(*p.ot, 0, task_limit(p.ot->size()), roots);
  std::vector<std::vector<Interaction>> lists(roots.size());
  std::vector<double> work(roots.size(), 0.0);
  PlanCounts planning;
  // This process's tasks (all of them without a share): planned by points, run by work.
  std::vector<double> points(roots.size());
  for (size_t r = 0; r < roots.size(); ++r)
    points[r] = static_cast<double>(size_of(p.ot->nodes()[static_cast<size_t>(roots[r])]));
  UnitRange mine = share_of(set, points);
  if (!plan_tasks(p, roots, mine, cfg_.cost_model ? all_pairs : kInf, set, lists, work, planning))
    return fall_back(src, outer, set, planning, since(start));
  if (set.share != nullptr) mine = rebalance(p, roots, mine, set, lists, work, planning);
  // The grids: those the interactions use and their descendants (M2M and L2L).
  const size_t grids = static_cast<size_t>(p.n + 1);
  std::vector<char> smark(p.st->nodes().size() * grids, 0), omark(p.ot->nodes().size() * grids, 0);
  std::vector<char> sderive(smark.size(), 0);
  mark_grids(p, lists, smark, sderive, omark);
  PassStats stats;
  DualTreeOps ops;
  count_planned(p, lists, smark, omark, set, stats, ops);
  stats.node_pairs = planning.visits;
  stats.bound_axes = planning.axes;
  stats.plan_seconds = since(start);
  // Cost model (docs/tree_tolerance.md §8): fall back unless the planned run is cheaper.
  std::int64_t counts[3] = {stats.near_pairs, stats.far_kernel, stats.far_basis};
  if (set.share != nullptr) set.share->sum(counts, 3);  // the serial pass's counts
  const double planned = kCostNear * static_cast<double>(counts[0]) +
                         kCostFar * static_cast<double>(counts[1]) +
                         kCostBasis * p.overhead_scale() * static_cast<double>(counts[2]);
  if (cfg_.audit) {
    ops.budget_used = audit_budget(p, roots, mine, lists);
    ops.log_lower.assign(p.point_low.size(), 0.0);
    const std::vector<Eigen::Index>& order = p.ot->order();
    for (size_t q = 0; q < order.size(); ++q)
      for (size_t k = 0; k < 4; ++k)
        ops.log_lower[4 * static_cast<size_t>(order[q]) + k] = p.point_low[4 * q + k];
  }
  if (ops_ != nullptr) *ops_ = ops;
  if (cfg_.cost_model && planned > kFallBackPlanned * all_pairs)
    return fall_back(src, outer, set, planning, stats.plan_seconds);
  std::vector<Acc> acc(static_cast<size_t>(p.ot->size()));
  const std::int64_t skipped = run_plan(p, roots, mine, lists, smark, sderive, set.threads, acc);
  stats.near_pairs -= skipped;
  if (ops_ != nullptr) ops_->point_pruned = skipped;
  PassSums out = gather(p, acc);
  out.stats = stats;
  out.kernel_evaluations = stats.near_pairs + stats.far_kernel;
  out.stats.run_seconds = since(start);
  return out;
}

}  // namespace
}  // namespace dual

std::unique_ptr<PairSumBackend> make_dual_tree_backend(const DualTreeConfig& config,
                                                       DualTreeOps* ops) {
  return std::make_unique<dual::DualTreeBackend>(config, ops);
}

std::unique_ptr<PairSumBackend> make_dual_tree_backend() {
  return make_dual_tree_backend(DualTreeConfig{}, nullptr);
}

}  // namespace softhd::detail
