// The exact and single-tree pair-sum backends, and the helpers every backend shares.

#include "pair_backend.hpp"

#include <algorithm>
#include <chrono>
#include <vector>

#include "softhd/interrupt.hpp"
#include "tree_sums.hpp"

namespace softhd::detail {

PassSums allocate_sums(Eigen::Index n, int d, unsigned flags) {
  PassSums out;
  out.S.setZero(n);
  if (flags & kOuterGrad) out.G.setZero(n, d);
  if (flags & kInner) {
    out.H.setZero(n);
    out.G2.setZero(n, d);
  }
  return out;
}

void store_sums(PassSums& out, Eigen::Index i, const PairSums& s, unsigned flags, int d) {
  out.S[i] = s.S;
  if (flags & kOuterGrad)
    for (int k = 0; k < d; ++k) out.G(i, k) = s.G[k];
  if (flags & kInner) {
    out.H[i] = s.H;
    for (int k = 0; k < d; ++k) out.G2(i, k) = s.G2[k];
  }
}

PassSums run_pass(const PairSumBackend& backend, const PassSources& src, const PassOuter& outer,
                  const PassSettings& set) {
  check_interrupt("between distance passes");
  PassSums out = backend.sums(src, outer, set);
  if (set.share == nullptr || set.share->size() == 1) return out;
  const WorkShare& share = *set.share;
  for (Eigen::VectorXd* v : {&out.S, &out.H})
    if (v->size() > 0) share.sum(v->data(), static_cast<std::size_t>(v->size()));
  for (Eigen::MatrixXd* m : {&out.G, &out.G2})
    if (m->size() > 0) share.sum(m->data(), static_cast<std::size_t>(m->size()));
  std::int64_t counts[6] = {out.kernel_evaluations, out.stats.near_pairs, out.stats.far_kernel,
                            out.stats.far_basis,    out.stats.node_pairs, out.stats.bound_axes};
  share.sum(counts, 6);
  out.kernel_evaluations = counts[0];
  out.stats.near_pairs = counts[1];
  out.stats.far_kernel = counts[2];
  out.stats.far_basis = counts[3];
  out.stats.node_pairs = counts[4];
  out.stats.bound_axes = counts[5];
  return out;
}

UnitRange share_of(const PassSettings& set, const std::vector<double>& cost) {
  if (set.share == nullptr) return {0, cost.size()};
  return split_by_cost(cost, set.share->size(), set.share->rank());
}

namespace {

unsigned flags_of(const PassOuter& outer, Eigen::Index i) {
  return outer.mask != nullptr && !(*outer.mask)[i] ? unsigned{kOuterSum} : outer.flags;
}

/// Relative cost of one outer point's sums over all sources, by the sums it needs: a
/// model (S alone 1, with G 1.2, all four 1.6), which only weighs points the mask leaves
/// with S alone against the others; unmasked, every point costs the same.
double point_cost(unsigned flags) {
  double c = 1.0;
  if (flags & kOuterGrad) c += 0.2;
  if (flags & kInner) c += 0.4;
  return c;
}

/// The modelled cost of every outer point (caller's order).
std::vector<double> point_costs(const PassOuter& outer) {
  const Eigen::Index n = outer.points->rows();
  std::vector<double> cost(static_cast<size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i)
    cost[static_cast<size_t>(i)] = point_cost(flags_of(outer, i));
  return cost;
}

/// Pairs per block of the exact backend between interrupt checks.
constexpr Eigen::Index kBlockPairs = Eigen::Index{1} << 29;

/// All pairs. OpenMP over the outer points; each result depends on its own point only,
/// so any thread count gives the same bits.
class ExactBackend final : public PairSumBackend {
 public:
  PassSums sums(const PassSources& src, const PassOuter& outer,
                const PassSettings& set) const override {
    const auto start = std::chrono::steady_clock::now();
    const Eigen::MatrixXd& P = *outer.points;
    const Eigen::Index n = P.rows();
    const int d = static_cast<int>(P.cols());
    PairSources ps;
    ps.dim = d;
    ps.size = src.points->rows();
    for (int k = 0; k < d; ++k) ps.coord[k] = src.points->col(k).data();
    ps.weight = src.weight;
    ps.coef = src.coef;
    ps.scale = src.scale;
    PassSums out = allocate_sums(n, d, outer.flags);
    const UnitRange mine = set.share != nullptr ? share_of(set, point_costs(outer))
                                                : UnitRange{0, static_cast<size_t>(n)};
    const Eigen::Index first = static_cast<Eigen::Index>(mine.first);
    const Eigen::Index last = static_cast<Eigen::Index>(mine.last);
    const bool parallel = static_cast<double>(last - first) * static_cast<double>(ps.size) > 2.0e4;
    // In blocks of about kBlockPairs pairs (~0.2 s on 2 cores), the interrupt check between
    // them; the results do not depend on the blocks.
    const Eigen::Index block =
        std::max<Eigen::Index>(256, kBlockPairs / std::max<Eigen::Index>(1, ps.size));
    for (Eigen::Index b = first; b < last; b += block) {
      if (b > first) check_interrupt("between blocks of a distance pass");
      const Eigen::Index end = std::min(last, b + block);
#pragma omp parallel for schedule(dynamic, 16) num_threads(set.threads) if (parallel)
      for (Eigen::Index i = b; i < end; ++i) {
        double o[3] = {0.0, 0.0, 0.0};
        for (int k = 0; k < d; ++k) o[k] = P(i, k);
        const unsigned f = flags_of(outer, i);
        store_sums(out, i, pair_sums(o, outer.scale[i], ps, *set.power, set.eps, f), f, d);
      }
    }
    out.kernel_evaluations = static_cast<std::int64_t>(last - first) * ps.size;
    out.stats.near_pairs = out.kernel_evaluations;
    out.stats.run_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return out;
  }
};

/// Per outer point, the adaptive single-tree traversal of tree_sums.hpp, visiting the
/// outer points in their own tree's order (neighbouring points together).
class SingleTreeBackend final : public PairSumBackend {
 public:
  PassSums sums(const PassSources& src, const PassOuter& outer,
                const PassSettings& set) const override {
    const auto start = std::chrono::steady_clock::now();
    const KdTree& t = *src.tree;
    const int d = t.dim();
    const Eigen::Index n = outer.points->rows();
    // Source data in tree order, and the node moments of the weights.
    Eigen::VectorXd w, h, c;
    std::vector<NodeMoments> mw, mh;
    TreePass pass;
    pass.tree = &t;
    pass.src.dim = d;
    pass.src.size = t.size();
    for (int k = 0; k < d; ++k) pass.src.coord[k] = t.points().col(k).data();
    if (outer.flags & (kOuterSum | kOuterGrad)) {
      w = t.permute(Eigen::Map<const Eigen::VectorXd>(src.weight, t.size()));
      mw = node_moments(t, w.data(), nullptr, *set.power);
      pass.src.weight = w.data();
      pass.outer = mw.data();
    }
    if (outer.flags & kInner) {
      h = t.permute(Eigen::Map<const Eigen::VectorXd>(src.coef, t.size()));
      c = t.permute(Eigen::Map<const Eigen::VectorXd>(src.scale, t.size()));
      mh = node_moments(t, h.data(), c.data(), *set.power);
      pass.src.coef = h.data();
      pass.src.scale = c.data();
      pass.inner = mh.data();
    }
    const std::vector<Eigen::Index>& visit = outer.tree->order();
    const Eigen::MatrixXd& P = *outer.points;
    PassSums out = allocate_sums(n, d, outer.flags);
    std::int64_t evaluations = 0;
    // Split by count along the tree order (neighbouring points together).
    const UnitRange mine = share_of(set, std::vector<double>(static_cast<size_t>(n), 1.0));
    const Eigen::Index first = static_cast<Eigen::Index>(mine.first);
    const Eigen::Index last = static_cast<Eigen::Index>(mine.last);
#pragma omp parallel for schedule(dynamic, 16) num_threads(set.threads) if (n > 64) \
    reduction(+ : evaluations)
    for (Eigen::Index q = first; q < last; ++q) {
      const Eigen::Index i = visit[static_cast<size_t>(q)];
      double o[3] = {0.0, 0.0, 0.0};
      for (int k = 0; k < d; ++k) o[k] = P(i, k);
      const unsigned f = flags_of(outer, i);
      store_sums(out, i,
                 tree_sums(o, outer.scale[i], pass, *set.power, set.eps, set.tau, f, evaluations),
                 f, d);
    }
    out.kernel_evaluations = evaluations;
    out.stats.run_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return out;
  }
};

}  // namespace

std::unique_ptr<PairSumBackend> make_exact_backend() { return std::make_unique<ExactBackend>(); }
std::unique_ptr<PairSumBackend> make_single_tree_backend() {
  return std::make_unique<SingleTreeBackend>();
}

}  // namespace softhd::detail
