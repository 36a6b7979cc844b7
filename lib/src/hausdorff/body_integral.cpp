#include "body_integral.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <utility>

#include "../common/decimal.hpp"
#include "../common/gauss_legendre.hpp"
#include "../common/surface_bvh.hpp"
#include "body_integral_internal.hpp"
#include "softhd/error.hpp"
#include "softhd/parallel.hpp"

// BodyIntegral's construction (the triangles' geometry, the checks, the tree) and the all-pairs
// evaluation; the other parts in body_integral_internal.hpp.

namespace softhd::detail {

namespace body {

// The geometry of one triangle (area2 = 2 × its area > 0).
Triangle make_triangle(const double v[3][3], double near_ratio, double* area2) {
  Triangle t;
  std::copy(&v[0][0], &v[0][0] + 9, &t.v[0][0]);
  double e1[3], e2[3], n[3];
  for (int i = 0; i < 3; ++i) {
    e1[i] = v[1][i] - v[0][i];
    e2[i] = v[2][i] - v[0][i];
    t.c[i] = (v[0][i] + v[1][i] + v[2][i]) / 3.0;
  }
  cross(e1, e2, n);
  *area2 = std::sqrt(dot(n, n));
  if (!(*area2 > 0.0)) return t;
  double radius2 = 0.0;
  for (int i = 0; i < 3; ++i) t.n[i] = n[i] / *area2;
  for (int e = 0; e < 3; ++e) {
    const double* a = v[e];
    const double* b = v[(e + 1) % 3];
    const double d[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    t.len[e] = std::sqrt(dot(d, d));
    for (int i = 0; i < 3; ++i) t.tau[e][i] = d[i] / t.len[e];
    cross(t.tau[e], t.n, t.nu[e]);
    const double g[3] = {a[0] - t.c[0], a[1] - t.c[1], a[2] - t.c[2]};
    radius2 = std::max(radius2, dot(g, g));
  }
  t.near2 = near_ratio * near_ratio * radius2;
  t.far2 = kCoarseRatio * kCoarseRatio * t.near2;
  for (int a = 0; a < 3; ++a) {  // ∇λ_a = n × (v_{a+2} − v_{a+1}) / (2 area)
    const double* p = v[(a + 1) % 3];
    const double* q = v[(a + 2) % 3];
    const double d[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]};
    cross(t.n, d, t.glam[a]);
    for (int i = 0; i < 3; ++i) t.glam[a][i] /= *area2;
  }
  // A rule's points x = Σ_a λ_a v_a by coordinate, and its weights times the area.
  const auto place = [&](const auto& rule, int n, double* x, double* y, double* z, double* w) {
    double* coord[3] = {x, y, z};
    for (int q = 0; q < n; ++q) {
      const double* lam = rule.lam[q];
      for (int i = 0; i < 3; ++i)
        coord[i][q] = lam[0] * v[0][i] + lam[1] * v[1][i] + lam[2] * v[2][i];
      w[q] = 0.5 * *area2 * rule.w[q];
    }
  };
  place(far_rule(), kFarPoints, t.qx, t.qy, t.qz, t.wq);
  place(coarse_rule(), kCoarsePoints, t.cx, t.cy, t.cz, t.cw);
  return t;
}

}  // namespace body

using namespace body;

namespace {

void validate(const BodyIntegralOptions& o) {
  if (!(o.epsilon > 0.0) || !std::isfinite(o.epsilon))
    throw InvalidArgument("body integral: epsilon must be finite and > 0, got " +
                          decimal(o.epsilon));
  if (!(o.alpha > 0.0) || !std::isfinite(o.alpha))
    throw InvalidArgument("body integral: alpha must be finite and > 0, got " + decimal(o.alpha));
  if (!(o.near_ratio >= 1.0) || !std::isfinite(o.near_ratio))
    throw InvalidArgument("body integral: near_ratio must be finite and >= 1, got " +
                          decimal(o.near_ratio));
  if (o.angle_points < 2 || o.angle_points > 64)
    throw InvalidArgument("body integral: angle_points must be in [2, 64], got " +
                          std::to_string(o.angle_points));
  if (!(o.panel_width > 0.0) || !std::isfinite(o.panel_width))
    throw InvalidArgument("body integral: panel_width must be finite and > 0, got " +
                          decimal(o.panel_width));
  if (!(o.tolerance >= 0.0 && o.tolerance < 1.0))
    throw InvalidArgument("body integral: tolerance must be in [0, 1), got " +
                          decimal(o.tolerance));
  if (o.tolerance > 0.0 && o.alpha != 4.0)
    throw InvalidArgument(
        "body integral: tolerance > 0 needs alpha = 4 (the tree's expansions), "
        "got alpha " +
        decimal(o.alpha));
  check_threads(o.threads);
}

// Throws InvalidArgument unless the triangles (3 corners each) close up with one orientation:
// every directed edge (a, b) as often as (b, a) (the divergence theorem, and the far solid
// angles' winding number, need a closed, consistently oriented surface).
void check_closed(const std::vector<int>& corners) {
  std::vector<std::pair<int, int>> edges;
  edges.reserve(corners.size());
  for (std::size_t t = 0; t < corners.size(); t += 3)
    for (int e = 0; e < 3; ++e) edges.emplace_back(corners[t + e], corners[t + (e + 1) % 3]);
  std::sort(edges.begin(), edges.end());
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i;
    while (j < edges.size() && edges[j] == edges[i]) ++j;
    const auto back = std::equal_range(edges.begin(), edges.end(),
                                       std::make_pair(edges[i].second, edges[i].first));
    if (static_cast<std::size_t>(back.second - back.first) != j - i)
      throw InvalidArgument("body integral: the surface is not closed and consistently oriented: " +
                            std::to_string(j - i) + " edge(s) from point " +
                            std::to_string(edges[i].first) + " to " +
                            std::to_string(edges[i].second) + ", " +
                            std::to_string(back.second - back.first) + " back");
    i = j;
  }
}

// Each triangle's coplanar neighbours (Triangle::twin): across edge (a, b) the one triangle with
// the edge (b, a), when their unit normals agree to 1e-13 and its centroid lies in the plane to
// 1e-13 of the edges' length; else −1.
void find_twins(const std::vector<int>& corners, std::vector<Triangle>* tris) {
  std::vector<std::array<int, 4>> edges;  // (a, b, triangle, edge)
  for (std::size_t t = 0; t < tris->size(); ++t)
    for (int e = 0; e < 3; ++e)
      edges.push_back({corners[3 * t + e], corners[3 * t + (e + 1) % 3], static_cast<int>(t), e});
  std::sort(edges.begin(), edges.end());
  for (const auto& ed : edges) {
    Triangle& t = (*tris)[ed[2]];
    t.twin[ed[3]] = -1;
    const std::array<int, 4> lo{ed[1], ed[0], -1, -1}, hi{ed[1], ed[0] + 1, -1, -1};
    const auto first = std::lower_bound(edges.begin(), edges.end(), lo);
    const auto last = std::lower_bound(edges.begin(), edges.end(), hi);
    if (last - first != 1) continue;
    const Triangle& s = (*tris)[(*first)[2]];
    const double size = t.len[0] + t.len[1] + t.len[2];
    const double off[3] = {s.c[0] - t.c[0], s.c[1] - t.c[1], s.c[2] - t.c[2]};
    bool flat = std::abs(dot(t.n, off)) <= 1e-13 * size;
    for (int i = 0; i < 3; ++i) flat = flat && std::abs(s.n[i] - t.n[i]) <= 1e-13;
    if (flat) t.twin[ed[3]] = (*first)[2];
  }
}

}  // namespace

double radial_g(double r, double epsilon, double alpha) {
  Radial k(epsilon, alpha);
  k.four = false;  // the general closed form and series
  return k.g(r);
}

BodyIntegral::BodyIntegral(const TriangleSurface& surface, const BodyIntegralOptions& options)
    : options_(options) {
  validate(options);
  if (surface.points.cols() != 3)
    throw InvalidArgument("body integral: the surface's points must be N by 3");
  point_count_ = surface.points.rows();
  const Eigen::Index count = surface.triangles.rows();
  triangles_.resize(count);
  corners_.resize(3 * count);
  for (Eigen::Index t = 0; t < count; ++t) {
    double v[3][3];
    for (int a = 0; a < 3; ++a) {
      const int idx = surface.triangles(t, a);
      if (idx < 0 || idx >= point_count_)
        throw InvalidArgument("body integral: triangle " + std::to_string(t) +
                              " has a point index out of range: " + std::to_string(idx));
      corners_[3 * t + a] = idx;
      for (int i = 0; i < 3; ++i) v[a][i] = surface.points(idx, i);
    }
    double area2 = 0.0;
    triangles_[t] = make_triangle(v, options.near_ratio, &area2);
    if (!(area2 > 0.0))
      throw InvalidArgument("body integral: triangle " + std::to_string(t) + " has zero area");
  }
  check_closed(corners_);
  find_twins(corners_, &triangles_);
  gauss_legendre_unit(options.angle_points, &rule_x_, &rule_w_);
  if (options.tolerance > 0.0) {
    const Bvh bvh = build_bvh(surface);
    order_ = bvh.order;
    clusters_.reserve(bvh.nodes.size());
    for (const BvhNode& node : bvh.nodes)
      clusters_.push_back(make_cluster(triangles_, order_, node));
    total_area_ = clusters_[0].area;
    group_radius_ = kGroupRadius * clusters_[0].rho;
    std::vector<int> position(order_.size());
    for (std::size_t j = 0; j < order_.size(); ++j) position[order_[j]] = static_cast<int>(j);
    for (int t : order_) {
      ordered_.push_back(triangles_[t]);
      for (int& twin : ordered_.back().twin)
        if (twin >= 0) twin = position[twin];
    }
  }
}

void BodyIntegral::evaluate(const Eigen::MatrixXd& points, Eigen::VectorXd* value,
                            Eigen::MatrixXd* grad) const {
  if (points.cols() != 3) throw InvalidArgument("body integral: the points must be M by 3");
  const Eigen::Index m = points.rows();
  value->resize(m);
  if (grad) grad->resize(m, 3);
  if (options_.tolerance > 0.0) return evaluate_tree(points, value, grad);
  const Radial k(options_.epsilon, options_.alpha);
  const Rules rule{rule_x_, rule_w_, options_.panel_width};
  const bool want_b = grad != nullptr;
  const int threads = resolve_threads(options_.threads);
  const bool coulomb = k.alpha >= Radial::kCoulomb;
  // Runs points × triangles times: the near/far switch, then 16 or 8 kernel evaluations (far)
  // or 3 edges × panels × angle_points (near).
#pragma omp parallel for schedule(static) num_threads(threads)
  for (Eigen::Index j = 0; j < m; ++j) {
    const double y[3] = {points(j, 0), points(j, 1), points(j, 2)};
    PointSums s;  // Σ ω_t: near (exact), far (the rule's)
    direct_range(triangles_, 0, static_cast<int>(triangles_.size()), k, rule, y, want_b, coulomb,
                 &s);
    double J = s.J;
    if (coulomb) J += k.g_inf * far_solid_angle(s.near_omega, s.far_omega, s.on_surface);
    (*value)[j] = J;
    if (grad)
      for (int i = 0; i < 3; ++i) (*grad)(j, i) = s.g[i];
  }
}

}  // namespace softhd::detail
