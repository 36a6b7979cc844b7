#pragma once
// The dual-tree backend's parts (internal to dual_tree*.cpp; dual_tree.hpp describes the
// method). One pass runs in three steps:
//   planning     (dual_tree_plan.cpp)     the budget's lower bounds, then the traversal
//                                          choosing per node pair an operation and a degree,
//   far field    (dual_tree_farfield.cpp) proxies upwards (anterpolation, M2M) and locals
//                                          downwards (L2L, L2P), one chain per degree,
//   evaluation   (dual_tree.cpp)          the interactions of each task, the cost model.

#include <Eigen/Core>
#include <algorithm>
#include <cstdint>
#include <limits>
#include <vector>

#include "chebyshev.hpp"
#include "dual_tree.hpp"
#include "kd_tree.hpp"
#include "pair_backend.hpp"
#include "pair_kernel.hpp"

namespace softhd::detail::dual {

constexpr double kInf = std::numeric_limits<double>::infinity();
enum Op : std::uint8_t { kP2P, kM2P, kP2L, kM2L, kPrune, kNone };
enum Kind { kS = 0, kG = 1, kH = 2, kG2 = 3 };  // the four sums; budgets per kind

// Cost model (docs/tree_tolerance.md §8): work in units of one pair of the all-pairs
// kernel summing S alone, fitted to the ladder's planned passes in value mode
// (bench_hausdorff --no-fallback, 3 162 ≤ N = M ≤ 31 623, four shapes, τ = 1e-2…1e-6).
// Direct pairs and kernel evaluations cost what an all-pairs pair of the same sums costs;
// basis work and planning do not grow with the sums, so in a pass with gradient or inner
// sums they weigh 1/kGradPairCost as much (Pass::overhead_scale).
constexpr double kCostNear = 1.6;      // direct pairs in leaf slices
constexpr double kCostFar = 1.0;       // kernel evaluations at interpolation points
constexpr double kCostBasis = 0.33;    // point-interpolation-point basis products
constexpr double kCostVisit = 270.0;   // planning: per node pair visited
constexpr double kCostAxis = 430.0;    // planning: per axis's remainder-bound terms
constexpr double kCostBound = 440.0;   // planning: the lower bounds of one outer point
constexpr double kGradPairCost = 1.5;  // an all-pairs pair with more sums than S (≥ 1.5 S's)
constexpr double kFallBack = 0.9;      // predicted by the sample: plan and run < 90 % of all pairs
constexpr double kFallBackPlanned = 1.0;  // planned: the run < all pairs (planning is spent)
// Outer subtrees planned and run as tasks: N/64 points, at least kMinTaskPoints (smaller
// tasks make worse plans: an outer box never interacts above its task's root), but at
// most N/kFewTasks, so that a small pass still has tasks for every thread (task_limit).
constexpr Eigen::Index kMinTaskPoints = 1024;
constexpr Eigen::Index kFewTasks = 4;
/// The most outer points of a task for N outer points (independent of the thread count,
/// so that the result is too): max(min(kMinTaskPoints, ⌈N/kFewTasks⌉), N/64).
inline Eigen::Index task_limit(Eigen::Index N) {
  const Eigen::Index few = (N + kFewTasks - 1) / kFewTasks;
  return std::max(std::min(kMinTaskPoints, few), N / 64);
}

/// One planned node pair: outer node t, source node s, the operation and, for the far
/// field, the points per axis of its interpolation grids.
struct Interaction {
  int t, s;
  Op op;
  std::uint8_t deg;
};

/// A choice of choose(): the operation, its degree, and the logarithms of its error
/// bounds per unit source weight (value kernel, gradient kernel).
struct Choice {
  Op op = kNone;
  int deg = 0;
  double lv = -kInf, lg = -kInf;
  int axes = 0;  // axes' ellipse terms computed to choose (planning work)
};

/// The planning's work: node pairs visited, axes' ellipse terms computed (cost model).
struct PlanCounts {
  std::int64_t visits = 0, axes = 0;
  PlanCounts& operator+=(const PlanCounts& o) {
    visits += o.visits, axes += o.axes;
    return *this;
  }
};

/// Sums accumulated for one outer point.
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

/// The source nodes of the lower bounds' partition as arrays: box corners per axis, the
/// weights of S and G (mw) and the weights and scales of H and G2 (mh).
struct CutBoxes {
  std::vector<double> lo[3], hi[3];
  std::vector<double> w, hw, hs;
};

/// The interpolation points of one source box at one degree, and their weights.
struct ProxySet {
  std::vector<double> coord;             // d blocks of P coordinates
  std::vector<double> weight, coef, sc;  // P each
};

inline Eigen::Index size_of(const KdNode& n) { return n.end - n.begin; }

/// Everything one pass needs, in the trees' orders.
struct Pass {
  const KdTree* ot = nullptr;  // outer tree
  const KdTree* st = nullptr;  // source tree
  DualTreeConfig cfg;
  int d = 3;
  int n = 8;     // the largest degree (points per axis) a node pair may use
  int m_lo = 8;  // the least
  unsigned flags = 0;
  bool want[4] = {false, false, false, false};
  bool interp = true;  // α ≤ max_interp_alpha: far field allowed
  double alpha = 4.0, eps = 1e-3;
  // The budget of a node pair (dual_tree_plan.cpp): log τ_share for the shares of the
  // outer lower bound, log τ_own for the pair's own least contribution (−∞: not used).
  double log_tau_share = 0.0, log_tau_own = -kInf;
  bool recycle = false;  // the share term from a ledger per outer box (dual_tree_plan.cpp)
  const KernelPower* power = nullptr;
  Eigen::VectorXd w, h, c, oc;  // source weights, coefficients, scales; outer scales
  std::vector<NodeMoments> mw, mh;
  PairSources src;
  std::vector<double> log_low;    // 4 per outer node: log min_{o∈T} of the unscaled lower bound
  bool point_prune = false;       // pruning regime: leaf pairs also pruned point by point
  std::vector<double> point_low;  // 4 per outer point (tree order, point_prune or audit only)
  std::vector<double> kappa;      // per outer node: max c_o (scale of its locals)
  std::vector<char> local_ok;     // per outer node: locals allowed (scales do not underflow)
  std::vector<double> cmin;       // per outer node: min c_o
  std::vector<int> cut;           // source nodes of the lower bounds (cut_nodes)
  CutBoxes cut_boxes;             // their boxes and moments, structure of arrays
  int cut_depth = 5;              // their depth in the source tree
  std::vector<double> log_weight, log_share;  // 4 per source node (prepare_sources)
  std::vector<Box> obox, sbox;                // interpolation boxes (interp only)
  int nf = 0;                                 // fields of an outer box's locals (P values each):
  int field[4] = {-1, -1, -1, -1};            // first field of S, G (d), H, G2 (d), or −1
  double log_total[4] = {0.0, 0.0, 0.0, 0.0};
  std::vector<ChebyshevRule> rules;  // rules[q]: q points per axis (q ≥ 2)
  // lagrange[a (n + 1) + b], 2 ≤ b ≤ a ≤ n: a × b, [j b + q] = ℓ^(b)_q(ξ^(a)_j) (the values
  // of a b-point axis's basis at an a-point axis's nodes: raises a grid's axis from b to a)
  std::vector<std::vector<double>> lagrange;

  const double* raise(int a, int b) const {
    return lagrange[static_cast<size_t>(a * (n + 1) + b)].data();
  }
  /// Points of source box s's grid at degree m (outer box t's: local_points).
  int proxy_points(int s, int m) const { return sbox[static_cast<size_t>(s)].grid_size(d, m); }
  int local_points(int t, int m) const { return obox[static_cast<size_t>(t)].grid_size(d, m); }
  bool outer_kinds() const { return want[kS] || want[kG]; }
  /// The weight of basis and planning work relative to kCost* (S alone: 1).
  double overhead_scale() const { return want[kG] || want[kH] ? 1.0 / kGradPairCost : 1.0; }
  /// Fields of a source box's proxies: the weights of S and G, and those of H and G2.
  int source_fields() const { return (outer_kinds() ? 1 : 0) + (want[kH] ? 1 : 0); }
  /// Whether source node s may carry proxies at degree m (more points than proxies).
  bool has_proxy(int s, int m) const {
    return interp && size_of(st->nodes()[static_cast<size_t>(s)]) > proxy_points(s, m);
  }
  /// Whether outer node t may carry locals at degree m.
  bool has_local(int t, int m) const {
    return local_ok[static_cast<size_t>(t)] &&
           size_of(ot->nodes()[static_cast<size_t>(t)]) > local_points(t, m);
  }
  /// Index of (node, degree) in per-degree arrays.
  size_t slot(int node, int m) const {
    return static_cast<size_t>(node) * static_cast<size_t>(n + 1) + static_cast<size_t>(m);
  }
  /// The sources [begin, end) of the source tree's order.
  PairSources range(Eigen::Index begin, Eigen::Index end) const {
    PairSources sub = src;
    sub.size = end - begin;
    for (int k = 0; k < d; ++k) sub.coord[k] += begin;
    if (sub.weight != nullptr) sub.weight += begin;
    if (sub.coef != nullptr) sub.coef += begin;
    if (sub.scale != nullptr) sub.scale += begin;
    return sub;
  }
  PairSources slice(const KdNode& s) const { return range(s.begin, s.end); }
};

// ---- planning (dual_tree_plan.cpp) ----

/// The pass's settings, source data and outer lower bounds.
void prepare(Pass& p, const DualTreeConfig& cfg, const PassSources& src, const PassOuter& outer,
             const PassSettings& set);
/// Lower bounds (dual_tree_bounds.cpp) of the sums of every outer point in the subtrees of `roots`,
/// their minima per outer node, and the locals' scales, for those subtrees' nodes: the planning of
/// a task reads nothing else, so a process bounds only the tasks it plans.
void outer_bounds(Pass& p, const std::vector<int>& roots, int threads);
/// The outer data every task shares (dual_tree_bounds.cpp): scales in tree order, room for
/// the per-node bounds, and the partition of the sources the lower bounds use.
void prepare_outer(Pass& p, const PassOuter& in);
/// Grids that nest down the subtree of `root` (each child's slopes at least its parent's).
void inherit_slopes(const KdTree& tree, int root, int d, std::vector<Box>& box);
/// The end of node id's subtree in preorder (its nodes are [id, end)).
int subtree_end(const KdTree& tree, int id);
/// Outer subtrees processed as independent tasks (nodes of at most `limit` points).
void task_roots(const KdTree& ot, int id, Eigen::Index limit, std::vector<int>& out);
/// Bounds (outer_bounds) and plans the tasks of `mine` (their planned work in `work`);
/// false when the plan costs more than its limit (fall back to all pairs): with `all_pairs`
/// N·M, kFallBack·N·M for the sample's prediction, kFallBackPlanned·N·M for the planned
/// run (all_pairs = ∞: never). A sample of
/// tasks, or below N ≈ 16 000 of subtrees of tasks (whose plans are then dropped), is
/// bounded and planned first to predict the plan's work, so a fall-back costs about the
/// sample's share of the planning. With a share, the prediction and the verdict are summed
/// over the processes (each plans its own tasks).
bool plan_tasks(Pass& p, const std::vector<int>& roots, UnitRange mine, double all_pairs,
                const PassSettings& set, std::vector<std::vector<Interaction>>& lists,
                std::vector<double>& work, PlanCounts& counts);
/// Distributed passes: the tasks this process executes, split by planned work (summed
/// over the processes); tasks that move are planned again by their new process (a task's
/// plan depends on the task alone), the lists of tasks that left are dropped.
UnitRange rebalance(Pass& p, const std::vector<int>& roots, UnitRange planned,
                    const PassSettings& set, std::vector<std::vector<Interaction>>& lists,
                    std::vector<double>& work, PlanCounts& counts);
/// Whether source node s may be dropped for the outer point o (tree position q) alone.
bool prunable_for_point(const Pass& p, const double* o, Eigen::Index q, int s);
/// The own term of the budget of pair (t, s) for sum k: τ_own W_S u(R_max), at most τ_own
/// times S's contribution to the sum of every point of T (0 without own_budget).
double own_term(const Pass& p, int t, int s, int k);
/// The planning's work in pair units: `c` for the lower bounds of `points` outer points.
double planning_cost(const Pass& p, const PlanCounts& c, double points);
/// Planned work of one interaction in pair units (kCost weights).
double interaction_cost(const Pass& p, const Interaction& it);
/// The budget audit (DualTreeConfig::audit): per outer point of the tasks of `mine`, the
/// error bounds of every interaction covering it, recomputed and summed, over τ times its
/// lower bound; the largest over points and requested sums.
double audit_budget(const Pass& p, const std::vector<int>& roots, UnitRange mine,
                    const std::vector<std::vector<Interaction>>& lists);

// ---- far field (dual_tree_farfield.cpp) ----

/// The source proxies of every (node, degree) that the interactions use.
struct SourceProxies {
  std::vector<int> slot;  // per Pass::slot(node, m): index into `sets`, or −1
  std::vector<ProxySet> sets;
  const ProxySet& at(const Pass& p, int s, int m) const {
    return sets[static_cast<size_t>(slot[p.slot(s, m)])];
  }
};
/// Marks the (node, degree) grids that the interactions reach (with the descendants that
/// translate to or from them): `smark` over the source tree, `omark` over the outer tree.
/// A box that can carry a grid at the largest degree n keeps one chain: its lower-degree
/// proxies are derived from its degree-n weights (`sderive`), its lower-degree locals
/// raised to degree n before the downward pass (exact both ways, tensor_rect).
void mark_grids(const Pass& p, const std::vector<std::vector<Interaction>>& lists,
                std::vector<char>& smark, std::vector<char>& sderive, std::vector<char>& omark);
/// Upward pass: the proxies of every marked (source node, degree), then the derived ones.
void source_upward(const Pass& p, const std::vector<char>& smark, const std::vector<char>& sderive,
                   SourceProxies& out, int threads);
/// The proxies of one source box as the kernel's sources.
PairSources proxy_sources(const Pass& p, const ProxySet& ps);
/// The tensor grid of interpolation points of box b at degree m (d blocks of m^d).
std::vector<double> grid_points(const Pass& p, const Box& b, int m);
/// Adds one interpolation point's sums to an outer box's locals (the requested fields).
void add_local(const Pass& p, const PairSums& s, int j, int P, double* loc);
/// Downward pass over one task's subtree [root, root + local.size()/(n+1)): L2L and L2P.
void downward(const Pass& p, int root, std::vector<std::vector<double>>& local,
              std::vector<Acc>& acc);
/// Basis work of the marked grids and the number of translations (stats).
std::int64_t grid_work(const Pass& p, const KdTree& tree, const std::vector<Box>& box,
                       const std::vector<char>& mark, int fields, std::int64_t& translations);

}  // namespace softhd::detail::dual
