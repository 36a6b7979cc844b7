// The far field of the dual-tree backend (dual_tree_internal.hpp): tensor Chebyshev grids
// of boxes, one chain per degree m. Proxy weights go upwards (anterpolation at a box's
// points or M2M from its children's grids), locals downwards (L2L to the children's grids,
// L2P to the points of the others). Both translations are exact for the tensor
// polynomials of degree m − 1 of a grid, so they add no error term (tree_tolerance.md §7).

#include <algorithm>

#include "dual_tree_internal.hpp"

namespace softhd::detail::dual {

namespace {

/// The tensor basis values L_q(x) of box b at degree m (b.grid_size values, grid_points'
/// order).
void tensor_basis(const Pass& p, const Box& b, int m, const double* x, double* L) {
  double axis[3][kMaxChebyshev];
  int q[3] = {1, 1, 1};
  for (int k = 0; k < p.d; ++k) {
    q[k] = b.points_along(k, m);
    p.rules[static_cast<size_t>(q[k])].basis((x[k] - b.c[k]) / b.a[k], axis[k]);
  }
  if (p.d == 2) {
    for (int i = 0; i < q[0]; ++i)
      for (int j = 0; j < q[1]; ++j) L[i * q[1] + j] = axis[0][i] * axis[1][j];
    return;
  }
  for (int i = 0; i < q[0]; ++i)
    for (int j = 0; j < q[1]; ++j) {
      const double lij = axis[0][i] * axis[1][j];
      double* row = L + (i * q[1] + j) * q[2];
      for (int l = 0; l < q[2]; ++l) row[l] = lij * axis[2][l];
    }
}

/// The per-axis matrices carrying box b's degree-`from` grid to its degree-`to` grid
/// (from ≤ to: raise, Pass::raise) and their sizes.
void axis_raise(const Pass& p, const Box& b, int from, int to, const double** A, int* rows,
                int* cols) {
  for (int k = 0; k < p.d; ++k) {
    rows[k] = b.points_along(k, to);
    cols[k] = b.points_along(k, from);
    A[k] = p.raise(rows[k], cols[k]);
  }
}

/// Anterpolation into source box s at degree m: adds the points [begin, end) to the
/// weights at its interpolation points, W_q += Σ_x w_x L_q(x) and, for inner sums,
/// Σ_x h̃_x L_q(x) with h̃ = h (c/C)^α, C = the box's scale.
void anterpolate(const Pass& p, int s, int m, Eigen::Index begin, Eigen::Index end, ProxySet& ps) {
  const Box& b = p.sbox[static_cast<size_t>(s)];
  const size_t P = static_cast<size_t>(p.proxy_points(s, m));
  double L[kMaxChebyshev * kMaxChebyshev * kMaxChebyshev];
  const Eigen::MatrixXd& X = p.st->points();
  for (Eigen::Index q = begin; q < end; ++q) {
    double x[3] = {0.0, 0.0, 0.0};
    for (int k = 0; k < p.d; ++k) x[k] = X(q, k);
    tensor_basis(p, b, m, x, L);
    if (p.outer_kinds())
      for (size_t j = 0; j < P; ++j) ps.weight[j] += p.w[q] * L[j];
    if (p.want[kH]) {
      const double ht = p.h[q] * p.power->scalar(p.c[q] / ps.sc[0]);
      for (size_t j = 0; j < P; ++j) ps.coef[j] += ht * L[j];
    }
  }
}

/// The proxies of source box s at degree m: from its marked children by translation (M2M;
/// an inner weight is rescaled by (C_child/C)^α ≤ 1; their grids nest, inherit_slopes),
/// from the points of the others.
void source_proxies(const Pass& p, int s, int m, SourceProxies& sp) {
  const KdNode& S = p.st->nodes()[static_cast<size_t>(s)];
  ProxySet& ps = sp.sets[static_cast<size_t>(sp.slot[p.slot(s, m)])];
  const size_t P = static_cast<size_t>(p.proxy_points(s, m));
  ps.coord = grid_points(p, p.sbox[static_cast<size_t>(s)], m);
  if (p.outer_kinds()) ps.weight.assign(P, 0.0);
  if (p.want[kH]) {
    ps.coef.assign(P, 0.0);
    ps.sc.assign(P, p.mh[static_cast<size_t>(s)].scale);
  }
  if (S.right < 0) {
    anterpolate(p, s, m, S.begin, S.end, ps);
    return;
  }
  for (const int ch : {s + 1, S.right}) {
    const KdNode& C = p.st->nodes()[static_cast<size_t>(ch)];
    const int slot = sp.slot[p.slot(ch, m)];
    const Box &parent = p.sbox[static_cast<size_t>(s)], &child = p.sbox[static_cast<size_t>(ch)];
    if (slot < 0) {
      anterpolate(p, s, m, C.begin, C.end, ps);
      continue;
    }
    const ProxySet& cs = sp.sets[static_cast<size_t>(slot)];
    Translation E;
    make_translation(p.rules.data(), parent, child, m, p.d, E);
    if (p.outer_kinds()) tensor_apply(E, true, p.d, cs.weight.data(), 1.0, ps.weight.data());
    if (p.want[kH])
      tensor_apply(E, true, p.d, cs.coef.data(), p.power->scalar(cs.sc[0] / ps.sc[0]),
                   ps.coef.data());
  }
}

/// The proxies of source box s at degree m < n from its degree-n weights:
/// W^(m)_q = Σ_j ℓ^(m)_q(ξ^(n)_j) W^(n)_j (exact: ℓ^(m)_q is a polynomial of degree < n).
void derive_proxies(const Pass& p, int s, int m, SourceProxies& sp) {
  ProxySet& ps = sp.sets[static_cast<size_t>(sp.slot[p.slot(s, m)])];
  const ProxySet& top = sp.at(p, s, p.n);
  const Box& b = p.sbox[static_cast<size_t>(s)];
  const size_t P = static_cast<size_t>(p.proxy_points(s, m));
  const double* R[3];
  int rows[3], cols[3];
  axis_raise(p, b, m, p.n, R, rows, cols);
  double lower[3][kMaxChebyshev * kMaxChebyshev];  // the transposes: degree n to m
  const double* L[3] = {lower[0], lower[1], lower[2]};
  for (int k = 0; k < p.d; ++k)
    for (int q = 0; q < cols[k]; ++q)
      for (int j = 0; j < rows[k]; ++j) lower[k][q * rows[k] + j] = R[k][j * cols[k] + q];
  ps.coord = grid_points(p, b, m);
  if (!top.weight.empty()) {
    ps.weight.assign(P, 0.0);
    tensor_rect(L, cols, rows, p.d, top.weight.data(), ps.weight.data());
  }
  if (!top.coef.empty()) {
    ps.coef.assign(P, 0.0);
    tensor_rect(L, cols, rows, p.d, top.coef.data(), ps.coef.data());
    ps.sc.assign(P, top.sc[0]);
  }
}

/// The lower-degree locals of an outer box (task position i) raised to its degree-n grid:
/// the values of their interpolants there (exact: they are polynomials of degree < n).
void raise_locals(const Pass& p, int t, int i, std::vector<std::vector<double>>& local) {
  const size_t P = static_cast<size_t>(p.local_points(t, p.n));
  std::vector<double>& top = local[p.slot(i, p.n)];
  for (int m = 2; m < p.n; ++m) {
    std::vector<double>& loc = local[p.slot(i, m)];
    if (loc.empty()) continue;
    if (top.empty()) top.assign(static_cast<size_t>(p.nf) * P, 0.0);
    const size_t Pm = static_cast<size_t>(p.local_points(t, m));
    const double* R[3];
    int rows[3], cols[3];
    axis_raise(p, p.obox[static_cast<size_t>(t)], m, p.n, R, rows, cols);
    for (int f = 0; f < p.nf; ++f)
      tensor_rect(R, rows, cols, p.d, loc.data() + static_cast<size_t>(f) * Pm,
                  top.data() + static_cast<size_t>(f) * P);
    std::vector<double>().swap(loc);
  }
}

/// Marks (id, m) and its descendants that may carry grids at degree m (a child's grid
/// nests in its parent's, inherit_slopes, so they translate).
template <class Eligible>
void mark_subtree(const Pass& p, const KdTree& tree, Eligible eligible, int id, int m,
                  std::vector<char>& mark) {
  if (!eligible(id, m) || mark[p.slot(id, m)]) return;
  mark[p.slot(id, m)] = 1;
  const KdNode& n = tree.nodes()[static_cast<size_t>(id)];
  if (n.right < 0) return;
  mark_subtree(p, tree, eligible, id + 1, m, mark);
  mark_subtree(p, tree, eligible, n.right, m, mark);
}

/// L2P: the degree-m locals of outer box t interpolated to its points [begin, end), the
/// outer sums rescaled from κ_T to each point's own scale, (c_o/κ_T)^α ≤ 1.
void locals_to_points(const Pass& p, int t, int m, Eigen::Index begin, Eigen::Index end,
                      const double* loc, std::vector<Acc>& acc) {
  const Eigen::MatrixXd& X = p.ot->points();
  const Box& b = p.obox[static_cast<size_t>(t)];
  const int P = p.local_points(t, m);
  double L[kMaxChebyshev * kMaxChebyshev * kMaxChebyshev];
  double v[8];
  for (Eigen::Index q = begin; q < end; ++q) {
    double o[3] = {0.0, 0.0, 0.0};
    for (int k = 0; k < p.d; ++k) o[k] = X(q, k);
    tensor_basis(p, b, m, o, L);
    for (int f = 0; f < p.nf; ++f) {
      const double* lf = loc + static_cast<size_t>(f) * static_cast<size_t>(P);
      double sum = 0.0;
#pragma omp simd reduction(+ : sum)
      for (int j = 0; j < P; ++j) sum += L[j] * lf[j];
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

/// The degree-m locals of outer box t to its children: L2L to those that carry locals at
/// degree m (their grids nest, inherit_slopes; the outer fields rescaled by
/// (κ_child/κ_T)^α ≤ 1), L2P to the others' points.
void locals_to_children(const Pass& p, int t, int m, int root, const double* loc,
                        std::vector<std::vector<double>>& local, std::vector<Acc>& acc) {
  const std::vector<KdNode>& nodes = p.ot->nodes();
  const KdNode& T = nodes[static_cast<size_t>(t)];
  const size_t P = static_cast<size_t>(p.local_points(t, m));
  for (const int ch : {t + 1, T.right}) {
    const KdNode& C = nodes[static_cast<size_t>(ch)];
    const Box &parent = p.obox[static_cast<size_t>(t)], &child = p.obox[static_cast<size_t>(ch)];
    if (!p.has_local(ch, m)) {
      locals_to_points(p, t, m, C.begin, C.end, loc, acc);
      continue;
    }
    std::vector<double>& cl = local[p.slot(ch - root, m)];
    if (cl.empty()) cl.assign(static_cast<size_t>(p.nf * p.local_points(ch, m)), 0.0);
    Translation E;
    make_translation(p.rules.data(), parent, child, m, p.d, E);
    const size_t Pc = static_cast<size_t>(p.local_points(ch, m));
    const double scale =
        p.power->scalar(p.kappa[static_cast<size_t>(ch)] / p.kappa[static_cast<size_t>(t)]);
    for (int f = 0; f < p.nf; ++f) {
      const bool outer = p.field[kH] < 0 || f < p.field[kH];  // S, G come before H, G2
      tensor_apply(E, false, p.d, loc + static_cast<size_t>(f) * P, outer ? scale : 1.0,
                   cl.data() + static_cast<size_t>(f) * Pc);
    }
  }
}

}  // namespace

std::vector<double> grid_points(const Pass& p, const Box& b, int m) {
  const int P = b.grid_size(p.d, m);
  std::vector<double> x(static_cast<size_t>(p.d * P));
  for (int q = 0; q < P; ++q) {
    int rest = q;
    for (int k = p.d - 1; k >= 0; --k) {
      const int mk = b.points_along(k, m);
      x[static_cast<size_t>(k * P + q)] =
          b.c[k] + b.a[k] * p.rules[static_cast<size_t>(mk)].xi[rest % mk];
      rest /= mk;
    }
  }
  return x;
}

void mark_grids(const Pass& p, const std::vector<std::vector<Interaction>>& lists,
                std::vector<char>& smark, std::vector<char>& sderive, std::vector<char>& omark) {
  const auto proxy = [&p](int id, int m) { return p.has_proxy(id, m); };
  const auto local = [&p](int id, int m) { return p.has_local(id, m); };
  for (const auto& list : lists)
    for (const Interaction& it : list) {
      if (it.op == kM2P || it.op == kM2L) {
        const bool derive = it.deg < p.n && p.has_proxy(it.s, p.n);
        if (derive) sderive[p.slot(it.s, it.deg)] = 1;
        mark_subtree(p, *p.st, proxy, it.s, derive ? p.n : it.deg, smark);
      }
      if (it.op == kP2L || it.op == kM2L) {
        const int m = p.has_local(it.t, p.n) ? p.n : it.deg;
        mark_subtree(p, *p.ot, local, it.t, m, omark);
      }
    }
}

void source_upward(const Pass& p, const std::vector<char>& smark, const std::vector<char>& sderive,
                   SourceProxies& out, int threads) {
  const std::vector<KdNode>& nodes = p.st->nodes();
  std::vector<int> depth(nodes.size(), 0);
  std::vector<std::vector<std::pair<int, int>>> level;  // (node, degree) per depth
  out.slot.assign(smark.size(), -1);
  for (size_t id = 0; id < nodes.size(); ++id) {
    if (nodes[id].right >= 0)
      depth[id + 1] = depth[static_cast<size_t>(nodes[id].right)] = depth[id] + 1;
    for (int m = 2; m <= p.n; ++m) {
      if (!smark[p.slot(static_cast<int>(id), m)]) continue;
      if (level.size() <= static_cast<size_t>(depth[id]))
        level.resize(static_cast<size_t>(depth[id]) + 1);
      level[static_cast<size_t>(depth[id])].emplace_back(static_cast<int>(id), m);
      out.slot[p.slot(static_cast<int>(id), m)] = static_cast<int>(out.sets.size());
      out.sets.emplace_back();
    }
  }
  // The deepest level first, so that every box translates from its children
  // (deterministic: each grid is computed by one thread alone).
  for (size_t l = level.size(); l-- > 0;) {
    const auto& items = level[l];
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
    for (size_t i = 0; i < items.size(); ++i)
      source_proxies(p, items[i].first, items[i].second, out);
  }
  std::vector<size_t> derived;  // Pass::slot of each derived (node, degree)
  for (size_t i = 0; i < sderive.size(); ++i)
    if (sderive[i] && out.slot[i] < 0) {
      out.slot[i] = static_cast<int>(out.sets.size());
      out.sets.emplace_back();
      derived.push_back(i);
    }
#pragma omp parallel for schedule(dynamic, 16) num_threads(threads)
  for (size_t i = 0; i < derived.size(); ++i) {
    const size_t k = derived[i], per = static_cast<size_t>(p.n + 1);
    derive_proxies(p, static_cast<int>(k / per), static_cast<int>(k % per), out);
  }
}

PairSources proxy_sources(const Pass& p, const ProxySet& ps) {
  PairSources src;
  src.dim = p.d;
  src.size = static_cast<Eigen::Index>(ps.coord.size()) / p.d;
  for (int k = 0; k < p.d; ++k) src.coord[k] = ps.coord.data() + k * src.size;
  src.weight = ps.weight.empty() ? nullptr : ps.weight.data();
  src.coef = ps.coef.empty() ? nullptr : ps.coef.data();
  src.scale = ps.sc.empty() ? nullptr : ps.sc.data();
  return src;
}

void add_local(const Pass& p, const PairSums& s, int j, int P, double* loc) {
  auto at = [&](int field) {
    return loc + static_cast<size_t>(field) * static_cast<size_t>(P) + j;
  };
  if (p.field[kS] >= 0) *at(p.field[kS]) += s.S;
  if (p.field[kH] >= 0) *at(p.field[kH]) += s.H;
  for (int k = 0; k < p.d; ++k) {
    if (p.field[kG] >= 0) *at(p.field[kG] + k) += s.G[k];
    if (p.field[kG2] >= 0) *at(p.field[kG2] + k) += s.G2[k];
  }
}

void downward(const Pass& p, int root, std::vector<std::vector<double>>& local,
              std::vector<Acc>& acc) {
  const std::vector<KdNode>& nodes = p.ot->nodes();
  const size_t count = local.size() / static_cast<size_t>(p.n + 1);
  for (size_t i = 0; i < count; ++i) {  // preorder: parents before children
    const int t = root + static_cast<int>(i);
    const KdNode& T = nodes[static_cast<size_t>(t)];
    if (p.has_local(t, p.n)) raise_locals(p, t, static_cast<int>(i), local);
    for (int m = 2; m <= p.n; ++m) {
      std::vector<double>& loc = local[p.slot(static_cast<int>(i), m)];
      if (loc.empty()) continue;
      if (T.right < 0)
        locals_to_points(p, t, m, T.begin, T.end, loc.data(), acc);
      else
        locals_to_children(p, t, m, root, loc.data(), local, acc);
      std::vector<double>().swap(loc);
    }
  }
}

std::int64_t grid_work(const Pass& p, const KdTree& tree, const std::vector<Box>& box,
                       const std::vector<char>& mark, int fields, std::int64_t& translations) {
  std::int64_t work = 0;
  const std::vector<KdNode>& nodes = tree.nodes();
  for (size_t id = 0; id < nodes.size(); ++id)
    for (int m = 2; m <= p.n; ++m) {
      if (!mark[p.slot(static_cast<int>(id), m)]) continue;
      const std::int64_t P = box[id].grid_size(p.d, m);
      if (nodes[id].right < 0) {
        work += size_of(nodes[id]) * P;
        continue;
      }
      for (const size_t ch : {id + 1, static_cast<size_t>(nodes[id].right)}) {
        if (mark[p.slot(static_cast<int>(ch), m)]) {
          int rows[3], cols[3];
          for (int k = 0; k < p.d; ++k)
            rows[k] = box[ch].points_along(k, m), cols[k] = box[id].points_along(k, m);
          work += tensor_products(rows, cols, p.d) * fields;
          ++translations;
        } else {
          work += size_of(nodes[ch]) * P;
        }
      }
    }
  return work;
}

}  // namespace softhd::detail::dual
