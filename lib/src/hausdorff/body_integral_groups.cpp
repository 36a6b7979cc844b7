// BodyIntegral::evaluate by the tree: blocks of rows, groups of nearby rows sharing one
// traversal, the budgets from the previous group's values, each point's check
// (body_integral.hpp, docs/formulation.md §2.8).

#include <algorithm>
#include <cmath>
#include <limits>

#include "body_integral_internal.hpp"
#include "softhd/parallel.hpp"

namespace softhd::detail::body {

namespace {

// The centre and radius of rows [begin, end) of points (the mean; the largest distance to it,
// widened by 1e-12 of itself against rounding).
double group_sphere(const Eigen::MatrixXd& points, Eigen::Index begin, Eigen::Index end,
                    double* centre) {
  for (int i = 0; i < 3; ++i) centre[i] = points.col(i).segment(begin, end - begin).mean();
  double r2 = 0.0;
  for (Eigen::Index j = begin; j < end; ++j) {
    const double d[3] = {points(j, 0) - centre[0], points(j, 1) - centre[1],
                         points(j, 2) - centre[2]};
    r2 = std::max(r2, dot(d, d));
  }
  return std::sqrt(r2) * (1.0 + 1e-12);
}

// What one evaluation by the tree reads: the clusters, the triangles in the tree's order, the
// rules, whether ∂J/∂y is wanted, τ and |∂Ω|.
struct TreeView {
  const std::vector<BodyIntegral::Cluster>& clusters;
  const std::vector<Triangle>& tris;
  const Radial& k;
  const Rules& rule;
  bool want_b;
  double tau, area;
};

// The guesses of J and S a budget is made from, and whether y was on the surface.
struct Guess {
  double j = 0.0, s = 0.0;
  bool surface = false;
};

// J = Σ + G∞ × the far solid angles (exact off the surface) and the bound of its error.
double total_j(const Radial& k, const PointSums& s) {
  return s.J + k.g_inf * far_solid_angle(s.near_omega, s.far_omega, s.on_surface);
}
double error_j(const Radial& k, const PointSums& s) {
  return s.err_j + (s.on_surface ? k.g_inf * s.err_omega : 0.0);
}

// A probe's lower bounds of J and S at y (clusters with ρ ≤ z/4 taken).
Guess probe(const TreeView& t, const double* y) {
  const PointSums s = traverse(t.clusters, t.tris, t.k, t.rule, y, t.want_b,
                               Budget{0.0, 3.0 / t.area, 0.0, kProbeTheta});
  return {total_j(t.k, s) - error_j(t.k, s), s.S - s.err_g, s.on_surface};
}

// The budget of the guesses (per unit area τ J/(2 |∂Ω|), τ S/(2 |∂Ω|); on the surface, where the
// far solid angles' estimate enters J, a quarter of J's for it and a quarter for the rest), or
// none (exact: every triangle).
Budget make_budget(const TreeView& t, const Guess& g, bool exact) {
  if (exact) return Budget{0.0, 0.0, 0.0};
  const double share = g.surface ? 0.25 : 0.5;
  const double omega = g.surface ? std::min(3.0, share * t.tau * g.j / t.k.g_inf) : 3.0;
  return Budget{share * t.tau * g.j / t.area, omega / t.area, 0.5 * t.tau * g.s / t.area};
}

// One point's sums from its group's lists.
PointSums group_point(const TreeView& t, const double* y, const Budget& budget,
                      const GroupLists& lists) {
  return group_point(t.clusters, t.tris, t.k, t.rule, y, t.want_b, budget, lists);
}

// A point's sums s checked: accepted (its J into *J) when E_J ≤ τ (J̃ − E_J) and, with the
// gradient, E_g ≤ τ (S̃ − E_g), or when exact; else redone with the budget its own lower bounds
// give, then over all pairs.
PointSums settle(const TreeView& t, const double* y, PointSums s, bool exact, double* J) {
  for (int attempt = 1;; ++attempt) {
    *J = total_j(t.k, s);
    const double err = error_j(t.k, s);
    if (exact || (err <= t.tau * (*J - err) && (!t.want_b || s.err_g <= t.tau * (s.S - s.err_g))))
      return s;
    const Guess own{*J - err, s.S - s.err_g, s.on_surface};
    exact = attempt == 2 || own.j <= 0.0 || (t.want_b && own.s <= 0.0);
    s = traverse(t.clusters, t.tris, t.k, t.rule, y, t.want_b, make_budget(t, own, exact));
  }
}

}  // namespace

// The group of rows from begin: the most consecutive rows, up to kGroup and before limit, whose
// sphere's radius stays ≤ max_radius (one row at least); its end into *end, centre and radius.
double next_group(const Eigen::MatrixXd& points, Eigen::Index begin, Eigen::Index limit,
                  double max_radius, double* centre, Eigen::Index* end) {
  double radius = group_sphere(points, begin, begin + 1, centre);
  *end = begin + 1;
  for (Eigen::Index e = begin + 2; e <= std::min(limit, begin + kGroup); ++e) {
    double c[3];
    const double r = group_sphere(points, begin, e, c);
    if (r > max_radius) break;
    std::copy(c, c + 3, centre);
    radius = r;
    *end = e;
  }
  return radius;
}

// One point's sums from its group's lists.
PointSums group_point(const std::vector<BodyIntegral::Cluster>& clusters,
                      const std::vector<Triangle>& tris, const Radial& k, const Rules& rule,
                      const double* y, bool want_b, const Budget& budget, const GroupLists& g) {
  PointSums s;
  const auto direct = [&](const BodyIntegral::Cluster& c) {
    direct_range(tris, c.begin, c.end, k, rule, y, want_b, true, &s);
  };
  for (int id : g.taken) {  // by the bounds at y's own distance (≥ the group's, up to rounding)
    const BodyIntegral::Cluster& c = clusters[id];
    const double d[3] = {c.p[0] - y[0], c.p[1] - y[1], c.p[2] - y[2]};
    const Bounds e = cluster_bounds(c, k.eps, std::sqrt(dot(d, d)) - c.rho, want_b);
    if (e.valid)
      take_cluster(c, k.eps, y, want_b, e, &s);
    else  // invalid at y by rounding only: its triangles one by one
      direct(c);
  }
  for (int id : g.leaves) direct(clusters[id]);
  traverse(clusters, tris, k, rule, y, want_b, budget, g.open, &s);
  return s;
}

}  // namespace softhd::detail::body

namespace softhd::detail {

using namespace body;

void BodyIntegral::evaluate_tree(const Eigen::MatrixXd& points, Eigen::VectorXd* value,
                                 Eigen::MatrixXd* grad) const {
  const Eigen::Index m = points.rows();  // value and grad sized by evaluate()
  const Radial k(options_.epsilon, options_.alpha);
  const Rules rule{rule_x_, rule_w_, options_.panel_width};
  const TreeView t{clusters_, ordered_, k, rule, grad != nullptr, options_.tolerance, total_area_};
  const Eigen::Index blocks = (m + kBlock - 1) / kBlock;
  // Per block of points in order, per group of kGroup rows in it: one budget for the group from
  // the previous group's smallest J and S (for a block's first, from a probe at its first point:
  // clusters with ρ ≤ z/4 taken, J̃ − E and S̃ − E), per unit area τ J/(2 |∂Ω|), likewise for g;
  // the far solid angles' total bound below 3 (< 2π with the far rules' own error: the winding
  // number rounds right; on the surface, where their estimate enters J, below τ J/(4 G∞) and
  // J's own τ J/(4 |∂Ω|)). One traversal decides what the group's points share (group_lists),
  // each point the rest. A point is accepted when the bounds give E_J ≤ τ (J̃ − E_J) ≤ τ J and
  // E_g ≤ τ (S̃ − E_g) ≤ τ S; else redone with its own budget, then with none (every triangle).
#pragma omp parallel for schedule(static) num_threads(resolve_threads(options_.threads))
  for (Eigen::Index b = 0; b < blocks; ++b) {
    Guess guess;
    GroupLists lists;
    const Eigen::Index block_end = std::min(m, (b + 1) * kBlock);
    for (Eigen::Index g = b * kBlock, end; g < block_end; g = end) {
      double centre[3];
      const double radius = next_group(points, g, block_end, group_radius_, centre, &end);
      if (guess.j <= 0.0) {  // a block's first group: a probe's lower bounds as the guesses
        const double y[3] = {points(g, 0), points(g, 1), points(g, 2)};
        guess = probe(t, y);
      }
      const bool exact = guess.j <= 0.0 || (t.want_b && guess.s <= 0.0);
      const Budget budget = make_budget(t, guess, exact);
      group_lists(
          t.clusters, centre, radius,
          [&](const Cluster& c, double z) {
            return cluster_fits(c, cluster_bounds(c, k.eps, z, t.want_b), z, budget);
          },
          &lists);
      Guess next{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
                 false};
      for (Eigen::Index j = g; j < end; ++j) {
        const double y[3] = {points(j, 0), points(j, 1), points(j, 2)};
        double J;
        const PointSums s = settle(t, y, group_point(t, y, budget, lists), exact, &J);
        next = {std::min(next.j, J), std::min(next.s, s.S), next.surface || s.on_surface};
        (*value)[j] = J;
        if (grad)
          for (int i = 0; i < 3; ++i) (*grad)(j, i) = s.g[i];
      }
      guess = next;
    }
  }
}

}  // namespace softhd::detail
