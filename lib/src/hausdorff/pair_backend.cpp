// The exact and single-tree pair-sum backends, and the helpers every backend shares.

#include "pair_backend.hpp"

#include <chrono>
#include <vector>

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

namespace {

unsigned flags_of(const PassOuter& outer, Eigen::Index i) {
  return outer.mask != nullptr && !(*outer.mask)[i] ? unsigned{kOuterSum} : outer.flags;
}

/// All pairs. OpenMP over the outer points; each result depends on its own point only,
/// so any thread count gives the same bits.
class ExactBackend final : public PairSumBackend {
 public:
  bool uses_trees() const override { return false; }
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
    const bool parallel = static_cast<double>(n) * static_cast<double>(ps.size) > 2.0e4;
#pragma omp parallel for schedule(dynamic, 16) num_threads(set.threads) if (parallel)
    for (Eigen::Index i = 0; i < n; ++i) {
      double o[3] = {0.0, 0.0, 0.0};
      for (int k = 0; k < d; ++k) o[k] = P(i, k);
      const unsigned f = flags_of(outer, i);
      store_sums(out, i, pair_sums(o, outer.scale[i], ps, *set.power, set.eps, f), f, d);
    }
    out.kernel_evaluations = static_cast<std::int64_t>(n) * ps.size;
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
  bool uses_trees() const override { return true; }
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
#pragma omp parallel for schedule(dynamic, 16) num_threads(set.threads) if (n > 64) \
    reduction(+ : evaluations)
    for (Eigen::Index q = 0; q < n; ++q) {
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
