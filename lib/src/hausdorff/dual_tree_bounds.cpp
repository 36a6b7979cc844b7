// Lower bounds of the dual-tree backend's sums (dual_tree_internal.hpp), which set the
// planning's budget (docs/tree_tolerance.md §7, "Budget"): for every outer point o, the
// exact sum over one source leaf near o plus W k(R_max) for the other boxes of a coarse
// partition of the sources; per outer node their minimum.

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "dual_tree_internal.hpp"

namespace softhd::detail::dual {

namespace {

/// Depth of the lower bounds' coarse partition (source nodes at this depth): 5, plus
/// log2 of the sources per outer point when there are more sources than outer points
/// (at most 11). It costs 2^depth kernel evaluations per outer leaf, and tightens the
/// bounds where the outer points are few.
int cut_depth(Eigen::Index outer, Eigen::Index sources) {
  const double ratio =
      static_cast<double>(sources) / static_cast<double>(std::max<Eigen::Index>(outer, 1));
  return std::clamp(5 + static_cast<int>(std::floor(std::log2(std::max(ratio, 1.0)))), 5, 11);
}

/// Greedy descent to a source leaf near q (any leaf gives a valid lower bound); `cut`
/// receives its ancestor at depth `cut_at` (or the leaf, if shallower).
int leaf_near(const KdTree& st, const double* q, int d, int cut_at, int& cut) {
  const std::vector<KdNode>& nodes = st.nodes();
  int id = 0, depth = 0;
  cut = 0;
  while (nodes[static_cast<size_t>(id)].right >= 0) {
    if (depth == cut_at) cut = id;
    const int l = id + 1, r = nodes[static_cast<size_t>(id)].right;
    const double dl = box_gap2(nodes[static_cast<size_t>(l)], q, d);
    const double dr = box_gap2(nodes[static_cast<size_t>(r)], q, d);
    id = dl <= dr ? l : r;
    ++depth;
  }
  if (depth <= cut_at) cut = id;
  return id;
}

/// The source nodes at depth `cut_at`, and the leaves above it: a partition.
void cut_nodes(const KdTree& st, int id, int depth, int cut_at, std::vector<int>& out) {
  const KdNode& n = st.nodes()[static_cast<size_t>(id)];
  if (depth == cut_at || n.right < 0) {
    out.push_back(id);
    return;
  }
  cut_nodes(st, id + 1, depth + 1, cut_at, out);
  cut_nodes(st, n.right, depth + 1, cut_at, out);
}

/// Appends box i of `from` to `to`.
void append_box(const CutBoxes& from, size_t i, int d, CutBoxes& to) {
  for (int k = 0; k < d; ++k) {
    to.lo[k].push_back(from.lo[k][i]);
    to.hi[k].push_back(from.hi[k][i]);
  }
  to.w.push_back(from.w[i]);
  to.hw.push_back(from.hw[i]);
  to.hs.push_back(from.hs[i]);
}

/// The cut's boxes and moments as arrays (lower_sums).
void fill_cut_boxes(Pass& p) {
  CutBoxes& c = p.cut_boxes;
  const size_t n = p.cut.size();
  for (int k = 0; k < p.d; ++k) {
    c.lo[k].resize(n);
    c.hi[k].resize(n);
  }
  c.w.assign(n, 0.0);
  c.hw.assign(n, 0.0);
  c.hs.assign(n, 1.0);
  for (size_t i = 0; i < n; ++i) {
    const size_t id = static_cast<size_t>(p.cut[i]);
    const KdNode& node = p.st->nodes()[id];
    for (int k = 0; k < p.d; ++k) {
      c.lo[k][i] = node.lo[k];
      c.hi[k][i] = node.hi[k];
    }
    if (p.outer_kinds()) c.w[i] = p.mw[id].weight;
    if (p.want[kH]) {
      c.hw[i] = p.mh[id].weight;
      c.hs[i] = p.mh[id].scale;
    }
  }
}

constexpr int kChunk = 256;  // cut boxes per sweep of add_box_lowers

/// One chunk's Σ_j w_j q_j^α (added to `sum`) and Σ_j in_j w_j q_j^α t_j (to `vec`),
/// except for the box `skip` (−1: none), whose two terms go to `skip_sum`, `skip_vec`.
void chunk_sums(const KernelPower& power, const double* q, const double* w, const double* t,
                const double* in, int len, int skip, double& sum, double& vec, double& skip_sum,
                double& skip_vec) {
  alignas(64) double pw[kChunk];
  power.apply(q, pw, len);
  if (skip >= 0 && skip < len) {
    skip_sum += w[skip] * pw[skip];
    skip_vec += in[skip] * w[skip] * pw[skip] * t[skip];
    pw[skip] = 0.0;
  }
  double S = 0.0, V = 0.0;
#pragma omp simd reduction(+ : S, V)
  for (int j = 0; j < len; ++j) {
    const double v = w[j] * pw[j];
    S += v;
    V += in[j] * v * t[j];
  }
  sum += S;
  vec += V;
}

/// Adds to `low` the lower bounds of the boxes of `c` at every point of the box [lo, hi]
/// (a point: lo = hi = o), kChunk at a time (the distances in one vectorised sweep, the
/// powers and sums by chunk_sums): per box W k(R_max), R_max the largest distance between
/// the two boxes, with the scale c_o (every term is ≥ it), and W k(R_max) t_max for the
/// vector sums where the boxes are disjoint (there every term has r > 0). The bounds of the
/// box `skip` (−1: none) go to `skipped` instead.
void add_box_lowers(const Pass& p, const CutBoxes& c, const double* lo, const double* hi,
                    double c_o, int skip, PairSums& low, PairSums& skipped) {
  alignas(64) double t[kChunk], in[kChunk], q[kChunk];
  const size_t n = c.w.size();
  for (size_t b0 = 0; b0 < n; b0 += kChunk) {
    const int len = static_cast<int>(std::min<size_t>(kChunk, n - b0));
    const int sk = skip - static_cast<int>(b0);
#pragma omp simd
    for (int j = 0; j < len; ++j) {
      double near2 = 0.0, far2 = 0.0;
      for (int k = 0; k < p.d; ++k) {
        const double blo = c.lo[k][b0 + j], bhi = c.hi[k][b0 + j];
        const double gap = std::max(std::max(blo - hi[k], lo[k] - bhi), 0.0);
        const double span = std::max(hi[k] - blo, bhi - lo[k]);
        near2 += gap * gap;
        far2 += span * span;
      }
      t[j] = 1.0 / (std::sqrt(far2) + p.eps);
      in[j] = near2 > 0.0 ? 1.0 : 0.0;
      q[j] = c_o * t[j];
    }
    chunk_sums(*p.power, q, &c.w[b0], t, in, len, sk, low.S, low.Gm, skipped.S, skipped.Gm);
    if (!p.want[kH]) continue;
#pragma omp simd
    for (int j = 0; j < len; ++j) q[j] = c.hs[b0 + j] * t[j];
    chunk_sums(*p.power, q, &c.hw[b0], t, in, len, sk, low.H, low.G2m, skipped.H, skipped.G2m);
  }
}

/// Lower bounds (scaled, as pair_sums returns them) of the four sums at o from the boxes
/// of `c`: the sum of their bounds (add_box_lowers), except for the box `near` holding
/// `leaf`, which contributes the larger of its bound and the exact sum over `leaf`.
PairSums lower_sums(const Pass& p, const CutBoxes& c, const double* o, double c_o, int near,
                    const PairSums& leaf) {
  PairSums low, b;
  add_box_lowers(p, c, o, o, c_o, near, low, b);
  low.S += std::max(b.S, leaf.S);
  low.Gm += std::max(b.Gm, leaf.Gm);
  low.H += std::max(b.H, leaf.H);
  low.G2m += std::max(b.G2m, leaf.G2m);
  return low;
}

/// Cut boxes farther than this many diagonals of an outer leaf from it are bounded once
/// for the whole leaf (R_max between the boxes), the others point by point. A far box's
/// R_max(T, B) is at most R_max(o, B)/(1 − 1/kReach), so its bound is at least
/// (1 − 1/kReach)^(α+1) of the point's own (0.24 at α = 4).
constexpr double kReach = 4.0;

/// One thread's scratch of leaf_bounds: the cut split for one outer leaf.
struct LeafCut {
  CutBoxes nearby, far;       // boxes bounded point by point, and for the whole leaf
  std::vector<int> position;  // per cut box: its index in `nearby`, or −1
  std::vector<int> leaf_of;   // per point of the leaf: its source leaf (leaf_near)
  std::vector<int> near_of;   // per point: the cut box holding that leaf
};

/// Splits the cut for outer leaf T: into `nearby` the boxes within kReach diagonals of T
/// and those holding a point's source leaf (lc.near_of, turned into positions in
/// `nearby`), into `far` the others.
void split_cut(const Pass& p, const KdNode& T, LeafCut& lc) {
  const CutBoxes& c = p.cut_boxes;
  for (CutBoxes* b : {&lc.nearby, &lc.far}) {
    for (int k = 0; k < p.d; ++k) {
      b->lo[k].clear();
      b->hi[k].clear();
    }
    b->w.clear();
    b->hw.clear();
    b->hs.clear();
  }
  lc.position.assign(c.w.size(), -1);
  constexpr int kHoldsSourceLeaf = -2;  // marks the cut boxes that hold a point's source leaf
  for (const int i : lc.near_of) lc.position[static_cast<size_t>(i)] = kHoldsSourceLeaf;
  double diag2 = 0.0;
  for (int k = 0; k < p.d; ++k) diag2 += (T.hi[k] - T.lo[k]) * (T.hi[k] - T.lo[k]);
  const double reach2 = kReach * kReach * diag2;
  for (size_t i = 0; i < c.w.size(); ++i) {
    double gap2 = 0.0;
    for (int k = 0; k < p.d; ++k) {
      const double gap = std::max({c.lo[k][i] - T.hi[k], T.lo[k] - c.hi[k][i], 0.0});
      gap2 += gap * gap;
    }
    const bool nearby = lc.position[i] == kHoldsSourceLeaf || !(gap2 > reach2) || !(gap2 > 0.0);
    lc.position[i] = nearby ? static_cast<int>(lc.nearby.w.size()) : -1;
    append_box(c, i, p.d, nearby ? lc.nearby : lc.far);
  }
  for (int& i : lc.near_of) i = lc.position[static_cast<size_t>(i)];
}

/// The lower bounds of the outer points of `leaf` (lower_sums over the boxes near the
/// leaf, with the source leaf found by descending towards each point, plus the far boxes'
/// bounds for the whole leaf), their minima, and the leaf's scales.
void leaf_bounds(Pass& p, size_t id, double w_min, LeafCut& lc) {
  const KdNode& T = p.ot->nodes()[id];
  const Eigen::MatrixXd& X = p.ot->points();
  const unsigned flags = p.flags | kMagnitude;
  const size_t n = static_cast<size_t>(T.end - T.begin);
  lc.leaf_of.resize(n);
  lc.near_of.resize(n);
  double c_ref = 0.0;  // the far boxes' bounds are computed at the leaf's largest scale
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Index q = T.begin + static_cast<Eigen::Index>(i);
    double o[3] = {0.0, 0.0, 0.0};
    for (int k = 0; k < p.d; ++k) o[k] = X(q, k);
    int near_cut = 0;
    lc.leaf_of[i] = leaf_near(*p.st, o, p.d, p.cut_depth, near_cut);
    // The cut lists its nodes in increasing id order (depth first, left before right).
    const auto at = std::lower_bound(p.cut.begin(), p.cut.end(), near_cut);
    if (at == p.cut.end() || *at != near_cut)
      throw std::logic_error("leaf_bounds: the near leaf's node is not in the cut");
    lc.near_of[i] = static_cast<int>(at - p.cut.begin());
    c_ref = std::max(c_ref, p.oc[q]);
  }
  split_cut(p, T, lc);
  PairSums far, none;  // S, Gm at the scale c_ref; H, G2m carry the sources' own scales
  add_box_lowers(p, lc.far, T.lo, T.hi, c_ref, -1, far, none);
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Index q = T.begin + static_cast<Eigen::Index>(i);
    double o[3] = {0.0, 0.0, 0.0};
    for (int k = 0; k < p.d; ++k) o[k] = X(q, k);
    const PairSources leaf = p.slice(p.st->nodes()[static_cast<size_t>(lc.leaf_of[i])]);
    const PairSums exact = pair_sums(o, p.oc[q], leaf, *p.power, p.eps, flags);
    PairSums s = lower_sums(p, lc.nearby, o, p.oc[q], static_cast<size_t>(lc.near_of[i]), exact);
    const double rescale = c_ref > 0.0 ? std::pow(p.oc[q] / c_ref, p.alpha) : 1.0;
    s.S += rescale * far.S;  // (c_o t)^α = (c_o/c_ref)^α (c_ref t)^α
    s.Gm += rescale * far.Gm;
    s.H += far.H;
    s.G2m += far.G2m;
    // The nearest source (r = r_min, so p = 1) alone gives S ≥ w_min, and, when
    // r_min > 0, Gm ≥ w_min/c_o: the bound that matters at large α.
    s.S = std::max(s.S, w_min);
    if (p.oc[q] > p.eps) s.Gm = std::max(s.Gm, w_min / p.oc[q]);
    const double lc_o = p.alpha * std::log(p.oc[q]);
    const double v[4] = {std::log(s.S) - lc_o, std::log(s.Gm) - lc_o, std::log(s.H),
                         std::log(s.G2m)};
    for (int k = 0; k < 4; ++k) p.log_low[4 * id + k] = std::min(p.log_low[4 * id + k], v[k]);
    if (!p.point_low.empty()) std::copy(v, v + 4, &p.point_low[4 * static_cast<size_t>(q)]);
    p.kappa[id] = std::max(p.kappa[id], p.oc[q]);
    p.cmin[id] = std::min(p.cmin[id], p.oc[q]);
  }
}

}  // namespace

void prepare_outer(Pass& p, const PassOuter& in) {
  const KdTree& ot = *p.ot;
  const size_t nn = ot.nodes().size();
  p.oc = ot.permute(Eigen::Map<const Eigen::VectorXd>(in.scale, ot.size()));
  p.log_low.assign(4 * nn, kInf);
  if (p.point_prune || p.cfg.audit) p.point_low.assign(4 * static_cast<size_t>(ot.size()), kInf);
  p.kappa.assign(nn, 0.0);
  p.cmin.assign(nn, kInf);
  p.local_ok.assign(nn, 0);
  if (p.interp) p.obox.resize(nn);
  p.cut_depth = cut_depth(ot.size(), p.st->size());
  cut_nodes(*p.st, 0, 0, p.cut_depth, p.cut);
  fill_cut_boxes(p);
}

int subtree_end(const KdTree& tree, int id) {
  while (tree.nodes()[static_cast<size_t>(id)].right >= 0)
    id = tree.nodes()[static_cast<size_t>(id)].right;
  return id + 1;
}

void outer_bounds(Pass& p, const std::vector<int>& roots, int threads) {
  const KdTree& ot = *p.ot;
  const std::vector<KdNode>& nodes = ot.nodes();
  std::vector<int> leaves;
  for (const int root : roots) {
    const int end = subtree_end(ot, root);
    for (int id = root; id < end; ++id)
      if (nodes[static_cast<size_t>(id)].right < 0) leaves.push_back(id);
  }
  const double w_min = p.outer_kinds() ? p.w.minCoeff() : 0.0;
#pragma omp parallel num_threads(threads)
  {
    LeafCut scratch;
#pragma omp for schedule(dynamic, 8)
    for (size_t l = 0; l < leaves.size(); ++l)
      leaf_bounds(p, static_cast<size_t>(leaves[l]), w_min, scratch);
  }
  for (const int root : roots)
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
      if (!p.interp) continue;
      // Locals carry (κ_T t)^α; the factor (c_o/κ_T)^α must not underflow.
      p.local_ok[id] = p.alpha * (std::log(p.kappa[id]) - std::log(p.cmin[id])) <= 300.0;
      p.obox[id] = interpolation_box(nodes[id].lo, nodes[id].hi, p.d);
      set_grid_slopes(p.obox[id], p.d, p.cfg.grid_rho);
    }
  if (p.interp)
    for (const int root : roots) inherit_slopes(ot, root, p.d, p.obox);
}

}  // namespace softhd::detail::dual
