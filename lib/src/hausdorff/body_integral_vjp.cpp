// BodyIntegral::surface_vjp, the vector–Jacobian product for the surface points: over all
// pairs, or by the tree, the clusters' local expansions pushed to their triangles' corners
// (body_integral.hpp, docs/formulation.md §2.8).

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <utility>

#include "body_integral_internal.hpp"
#include "softhd/error.hpp"
#include "softhd/parallel.hpp"

namespace softhd::detail::body {

namespace {

// The surface product's far field: a cluster's expansion of k(|x − y|) = k(|d + s|), d = p − y,
// s = x − p, to second order, k̃(s) = f + f1 d·s + ½ (f1 |s|² + f2 (d·s)²), its coefficients
// times w added to L (kLocal numbers: f, f1 d, f1, f2 d dᵀ by (00, 01, 02, 11, 12, 22)); returns
// the cluster's ∫ k̃ dA = f A + f1 d·m1 + ½ (f1 tr m2 + f2 dᵀ m2 d) (S's share).
constexpr int kLocal = 11;

double local_share(const BodyIntegral::Cluster& c, double eps, const double* y, double w,
                   double* L) {
  const double d[3] = {c.p[0] - y[0], c.p[1] - y[1], c.p[2] - y[2]};
  const double r = std::sqrt(dot(d, d)), ir = 1.0 / r, iw = 1.0 / (r + eps);
  const double f = (iw * iw) * (iw * iw), f1 = -4.0 * ir * f * iw;
  const double f2 = 4.0 * ir * ir * ir * f * iw + 20.0 * ir * ir * f * iw * iw;
  L[0] += w * f;
  for (int i = 0; i < 3; ++i) L[1 + i] += w * f1 * d[i];
  L[4] += w * f1;
  const int pair[6][2] = {{0, 0}, {0, 1}, {0, 2}, {1, 1}, {1, 2}, {2, 2}};
  for (int e = 0; e < 6; ++e) L[5 + e] += w * f2 * d[pair[e][0]] * d[pair[e][1]];
  double dm2d = 0.0;
  for (int j = 0; j < 3; ++j)
    for (int k = 0; k < 3; ++k) dm2d += d[j] * c.s2[3 * j + k] * d[k];
  return f * c.area + f1 * dot(c.s1, d) + 0.5 * (f1 * c.tr2 + f2 * dm2d);
}

// Σ_q W_q λ_a(q) k̃(s_q) for the corners a of triangle t (the 16-point rule: exact, λ_a k̃ is
// cubic), k̃ the expansion with coefficients L about p, added to c.
void push_local(const Triangle& t, const double* p, const double* L, double* c) {
  const FarRule& rule = far_rule();
  for (int q = 0; q < kFarPoints; ++q) {
    const double s[3] = {t.qx[q] - p[0], t.qy[q] - p[1], t.qz[q] - p[2]};
    const double quad = L[5] * s[0] * s[0] + 2.0 * L[6] * s[0] * s[1] + 2.0 * L[7] * s[0] * s[2] +
                        L[8] * s[1] * s[1] + 2.0 * L[9] * s[1] * s[2] + L[10] * s[2] * s[2];
    const double v = t.wq[q] * (L[0] + L[1] * s[0] + L[2] * s[1] + L[3] * s[2] +
                                0.5 * (L[4] * dot(s, s) + quad));
    for (int a = 0; a < 3; ++a) c[a] += v * rule.lam[q][a];
  }
}

// One point's share of the surface product by the tree, kept until its bound is checked: the
// triangles taken one by one (w ∫_t k λ_a), the clusters by their expansions (w L), S̃ and the
// bound of its error (that of every corner's sum too).
struct VjpPoint {
  std::vector<std::pair<int, std::array<double, 3>>> tris;
  std::vector<std::pair<int, std::array<double, kLocal>>> clusters;
  double S = 0.0, err = 0.0;
};

// What the surface product's traversals read: the clusters, the tree's triangle order and the
// triangles in it, the rules.
struct VjpView {
  const std::vector<BodyIntegral::Cluster>& clusters;
  const std::vector<int>& order;
  const std::vector<Triangle>& tris;
  const Radial& k;
  const Rules& rule;
};

// Cluster id's expansion into y's share (weight w), g its bound per unit area at y.
void take_vjp_cluster(const VjpView& v, int id, const double* y, double w, double g,
                      VjpPoint* out) {
  const BodyIntegral::Cluster& c = v.clusters[id];
  std::array<double, kLocal> L{};
  out->S += local_share(c, v.k.eps, y, w, L.data());
  out->err += c.area * g;
  out->clusters.emplace_back(id, L);
}

// The triangles of cluster c one by one into y's share.
void direct_vjp(const VjpView& v, const BodyIntegral::Cluster& c, const double* y, double w,
                VjpPoint* out) {
  for (int j = c.begin; j < c.end; ++j) {
    double ct[3];
    corner_moments(v.tris[j], v.k, v.rule, y, ct);
    out->S += ct[0] + ct[1] + ct[2];
    out->tris.push_back({v.order[j], {w * ct[0], w * ct[1], w * ct[2]}});
  }
}

// Whether a cluster at z enters the product by its expansion: valid, and its bound g per unit
// area within the budget (or, theta > 0, ρ ≤ θ z).
bool vjp_fits(const BodyIntegral::Cluster& c, const Bounds& e, double z, double budget,
              double theta) {
  return e.valid && (theta > 0.0 ? c.rho <= theta * z : e.g <= budget);
}

// y's share of the surface product below the nodes `start`, added to out.
void traverse_vjp(const VjpView& v, const double* y, double w, double budget, double theta,
                  const std::vector<int>& start, VjpPoint* out) {
  int stack[2 * kBvhMaxDepth + 2];
  for (int root : start) {
    int top = 0;
    stack[top++] = root;
    while (top > 0) {
      const int id = stack[--top];
      const BodyIntegral::Cluster& c = v.clusters[id];
      const double d[3] = {c.p[0] - y[0], c.p[1] - y[1], c.p[2] - y[2]};
      const double z = std::sqrt(dot(d, d)) - c.rho;
      const Bounds e = cluster_bounds(c, v.k.eps, z, true);
      if (vjp_fits(c, e, z, budget, theta)) {
        take_vjp_cluster(v, id, y, w, e.g, out);
      } else if (c.left >= 0) {
        stack[top++] = c.left + 1;
        stack[top++] = c.left;
      } else {
        direct_vjp(v, c, y, w, out);
      }
    }
  }
}

// y's share by the whole tree (out cleared first).
void traverse_vjp(const VjpView& v, const double* y, double w, double budget, double theta,
                  VjpPoint* out) {
  out->tris.clear();
  out->clusters.clear();
  out->S = out->err = 0.0;
  traverse_vjp(v, y, w, budget, theta, {0}, out);
}

// y's share from its group's lists (out cleared first); a taken cluster by its bound at y's own
// distance (its triangles one by one where rounding makes it invalid there).
void group_vjp(const VjpView& v, const double* y, double w, double budget, const GroupLists& g,
               VjpPoint* out) {
  out->tris.clear();
  out->clusters.clear();
  out->S = out->err = 0.0;
  for (int id : g.taken) {
    const BodyIntegral::Cluster& c = v.clusters[id];
    const double d[3] = {c.p[0] - y[0], c.p[1] - y[1], c.p[2] - y[2]};
    const Bounds e = cluster_bounds(c, v.k.eps, std::sqrt(dot(d, d)) - c.rho, true);
    if (e.valid)
      take_vjp_cluster(v, id, y, w, e.g, out);
    else
      direct_vjp(v, c, y, w, out);
  }
  for (int id : g.leaves) direct_vjp(v, v.clusters[id], y, w, out);
  traverse_vjp(v, y, w, budget, 0.0, g.open, out);
}

// A point's share pt checked: accepted when E ≤ τ (S̃ − E) (S̃ = pt->S, without the weight), or
// when exact; else redone with the budget its own lower bound gives, then over all pairs.
void settle_vjp(const VjpView& v, const double* y, double w, double tau, double area, bool exact,
                VjpPoint* pt) {
  for (int attempt = 1;; ++attempt) {
    if (exact || pt->err <= tau * (pt->S - pt->err)) return;
    const double own = pt->S - pt->err;
    exact = attempt == 2 || own <= 0.0;
    traverse_vjp(v, y, w, exact ? 0.0 : 0.5 * tau * own / area, 0.0, pt);
  }
}

// The corner sums Σ_k w_k ∫_t k λ_a dA of every triangle (3 per triangle, in the surface's
// order): the threads' direct sums (acc) and their clusters' expansion coefficients (loc, kLocal
// per cluster) pushed to the clusters' triangles, summed in thread order.
std::vector<double> corner_sums(const VjpView& v, const std::vector<std::vector<double>>& acc,
                                const std::vector<std::vector<double>>& loc) {
  const std::size_t count = v.tris.size(), nodes = v.clusters.size();
  std::vector<double> sum(3 * count, 0.0), local(kLocal);
  for (const std::vector<double>& a : acc)
    for (std::size_t i = 0; i < a.size(); ++i) sum[i] += a[i];
  for (std::size_t id = 0; id < nodes; ++id) {
    std::fill(local.begin(), local.end(), 0.0);
    bool any = false;
    for (const std::vector<double>& l : loc)
      for (int i = 0; i < kLocal && !l.empty(); ++i) {
        local[i] += l[kLocal * id + i];
        any = any || l[kLocal * id + i] != 0.0;
      }
    if (!any) continue;
    const BodyIntegral::Cluster& cl = v.clusters[id];
    for (int j = cl.begin; j < cl.end; ++j)
      push_local(v.tris[j], cl.p, local.data(), &sum[3 * v.order[j]]);
  }
  return sum;
}

}  // namespace

}  // namespace softhd::detail::body

namespace softhd::detail {

using namespace body;

Eigen::MatrixXd BodyIntegral::surface_vjp(const Eigen::MatrixXd& points,
                                          const Eigen::VectorXd& weights) const {
  if (points.cols() != 3) throw InvalidArgument("body integral: the points must be M by 3");
  if (weights.size() != points.rows())
    throw InvalidArgument("body integral: weights must have one entry per point");
  if (options_.tolerance > 0.0) return surface_vjp_tree(points, weights);
  const Radial k(options_.epsilon, options_.alpha);
  const Rules rule{rule_x_, rule_w_, options_.panel_width};
  const int threads = resolve_threads(options_.threads);
  const std::size_t count = triangles_.size();
  // Per thread, per triangle and corner: Σ_k w_k ∫_t k λ_a dA; summed in thread order.
  std::vector<std::vector<double>> acc(threads);
  const Eigen::Index m = points.rows();
#pragma omp parallel num_threads(threads)
  {
    std::vector<double>& c = acc[thread_id()];
    c.assign(3 * count, 0.0);
#pragma omp for schedule(static)
    for (Eigen::Index j = 0; j < m; ++j) {
      const double wj = weights[j];
      if (wj == 0.0) continue;
      const double y[3] = {points(j, 0), points(j, 1), points(j, 2)};
      for (std::size_t t = 0; t < count; ++t) {
        const Triangle& tri = triangles_[t];
        double ct[3];
        corner_moments(tri, k, rule, y, ct);
        for (int a = 0; a < 3; ++a) c[3 * t + a] += wj * ct[a];
      }
    }
  }
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(point_count_, 3);
  for (std::size_t t = 0; t < count; ++t)
    for (int a = 0; a < 3; ++a) {
      double s = 0.0;
      for (const std::vector<double>& c : acc)
        if (!c.empty()) s += c[3 * t + a];
      for (int i = 0; i < 3; ++i) out(corners_[3 * t + a], i) += s * triangles_[t].n[i];
    }
  return out;
}

Eigen::MatrixXd BodyIntegral::surface_vjp_tree(const Eigen::MatrixXd& points,
                                               const Eigen::VectorXd& weights) const {
  const Radial k(options_.epsilon, options_.alpha);
  const Rules rule{rule_x_, rule_w_, options_.panel_width};
  const VjpView view{clusters_, order_, ordered_, k, rule};
  const int threads = resolve_threads(options_.threads);
  const std::size_t count = triangles_.size(), nodes = clusters_.size();
  const Eigen::Index m = points.rows(), blocks = (m + kBlock - 1) / kBlock;
  // Per thread: the triangles' corner sums and the clusters' coefficients, summed in thread
  // order. Per group of rows (as in evaluate_tree) one budget (per unit area, of every corner
  // sum's error) τ S/(2 |∂Ω|) from the previous group's smallest S (a probe's S̃ − E for a
  // block's first), one traversal for what its points share; a point is accepted when E ≤
  // τ (S̃ − E): then Σ_{t,a} |error of w ∫_t k λ_a| ≤ τ |w| S, S = ∫_∂Ω k dA; else redone with its
  // own budget, then over all pairs.
  std::vector<std::vector<double>> acc(threads), loc(threads);
#pragma omp parallel num_threads(threads)
  {
    std::vector<double>& c = acc[thread_id()];
    std::vector<double>& L = loc[thread_id()];
    c.assign(3 * count, 0.0);
    L.assign(kLocal * nodes, 0.0);
    VjpPoint pt;
    GroupLists lists;
#pragma omp for schedule(static)
    for (Eigen::Index b = 0; b < blocks; ++b) {
      double s_guess = 0.0;
      const Eigen::Index block_end = std::min(m, (b + 1) * kBlock);
      for (Eigen::Index g = b * kBlock, end; g < block_end; g = end) {
        double centre[3];
        const double radius = next_group(points, g, block_end, group_radius_, centre, &end);
        if (s_guess <= 0.0) {  // a block's first group: a probe's lower bound as the guess
          const double y[3] = {points(g, 0), points(g, 1), points(g, 2)};
          traverse_vjp(view, y, 1.0, 0.0, kProbeTheta, &pt);
          s_guess = pt.S - pt.err;
        }
        const double budget =
            s_guess > 0.0 ? 0.5 * options_.tolerance * s_guess / total_area_ : 0.0;
        group_lists(
            clusters_, centre, radius,
            [&](const Cluster& cl, double z) {
              return vjp_fits(cl, cluster_bounds(cl, k.eps, z, true), z, budget, 0.0);
            },
            &lists);
        double next = std::numeric_limits<double>::infinity();
        for (Eigen::Index j = g; j < end; ++j) {
          const double wj = weights[j];
          if (wj == 0.0) continue;
          const double y[3] = {points(j, 0), points(j, 1), points(j, 2)};
          group_vjp(view, y, wj, budget, lists, &pt);
          settle_vjp(view, y, wj, options_.tolerance, total_area_, budget == 0.0, &pt);
          next = std::min(next, pt.S);
          for (const auto& t : pt.tris)
            for (int a = 0; a < 3; ++a) c[3 * t.first + a] += t.second[a];
          for (const auto& q : pt.clusters)
            for (int i = 0; i < kLocal; ++i) L[kLocal * q.first + i] += q.second[i];
        }
        if (next < std::numeric_limits<double>::infinity()) s_guess = next;
      }
    }
  }
  const std::vector<double> sum = corner_sums(view, acc, loc);
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(point_count_, 3);
  for (std::size_t t = 0; t < count; ++t)
    for (int a = 0; a < 3; ++a)
      for (int i = 0; i < 3; ++i)
        out(corners_[3 * t + a], i) += sum[3 * t + a] * triangles_[t].n[i];
  return out;
}

}  // namespace softhd::detail
