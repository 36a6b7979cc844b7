// A bounding-volume hierarchy of a triangle surface, its closest points, signed distance and
// radius queries (surface_bvh.hpp; docs/formulation.md §2.8).

#include "surface_bvh.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>
#include <tuple>

#include "softhd/error.hpp"
#include "softhd/parallel.hpp"

namespace softhd::detail {

namespace {

// Median split along the widest axis of the triangles' centroids; ties broken by triangle id,
// so the hierarchy (and every result) is deterministic.
void build_node(const Eigen::MatrixXd& lo, const Eigen::MatrixXd& hi, const Eigen::MatrixXd& mid,
                Bvh* bvh, int node, int begin, int end) {
  BvhNode& n = bvh->nodes[node];
  n.begin = begin;
  n.end = end;
  n.lo = lo.row(bvh->order[begin]).transpose();
  n.hi = hi.row(bvh->order[begin]).transpose();
  Eigen::Vector3d cmin = mid.row(bvh->order[begin]).transpose(), cmax = cmin;
  for (int i = begin + 1; i < end; ++i) {
    const int t = bvh->order[i];
    n.lo = n.lo.cwiseMin(lo.row(t).transpose());
    n.hi = n.hi.cwiseMax(hi.row(t).transpose());
    cmin = cmin.cwiseMin(mid.row(t).transpose());
    cmax = cmax.cwiseMax(mid.row(t).transpose());
  }
  if (end - begin <= kBvhLeafSize) return;
  int axis = 0;
  (cmax - cmin).maxCoeff(&axis);
  const int m = begin + (end - begin) / 2;
  std::nth_element(bvh->order.begin() + begin, bvh->order.begin() + m, bvh->order.begin() + end,
                   [&](int a, int b) {
                     return mid(a, axis) != mid(b, axis) ? mid(a, axis) < mid(b, axis) : a < b;
                   });
  const int left = static_cast<int>(bvh->nodes.size());
  bvh->nodes.emplace_back();
  bvh->nodes.emplace_back();
  bvh->nodes[node].left = left;  // `n` may dangle after the emplace
  build_node(lo, hi, mid, bvh, left, begin, m);
  build_node(lo, hi, mid, bvh, left + 1, m, end);
}

// The point λ0 a + λ1 b + λ2 c of triangle t.
Eigen::Vector3d point_of(const TriangleSurface& s, Eigen::Index t, const Eigen::Vector3d& lambda) {
  return lambda[0] * corner(s, t, 0) + lambda[1] * corner(s, t, 1) + lambda[2] * corner(s, t, 2);
}

// A vertex of the triangle: λ = e_k.
TrianglePoint vertex_point(int k) {
  TrianglePoint p;
  p.lambda[k] = 1.0;
  p.feature = Feature::kVertex;
  p.corner = k;
  return p;
}

// A point of the edge opposite corner k: λ_{k+1} = 1 − v, λ_{k+2} = v.
TrianglePoint edge_point(int k, double v) {
  TrianglePoint p;
  p.lambda[(k + 1) % 3] = 1.0 - v;
  p.lambda[(k + 2) % 3] = v;
  p.feature = Feature::kEdge;
  p.corner = k;
  return p;
}

}  // namespace

Bvh build_bvh(const TriangleSurface& s) {
  const Eigen::Index T = s.triangles.rows();
  Eigen::MatrixXd lo(T, 3), hi(T, 3), mid(T, 3);
  for (Eigen::Index t = 0; t < T; ++t) {
    const Eigen::Vector3d a = corner(s, t, 0), b = corner(s, t, 1), c = corner(s, t, 2);
    lo.row(t) = a.cwiseMin(b).cwiseMin(c).transpose();
    hi.row(t) = a.cwiseMax(b).cwiseMax(c).transpose();
    mid.row(t) = ((a + b + c) / 3.0).transpose();
  }
  Bvh bvh;
  bvh.order.resize(static_cast<size_t>(T));
  std::iota(bvh.order.begin(), bvh.order.end(), 0);
  bvh.nodes.reserve(static_cast<size_t>(2 * T / kBvhLeafSize + 2));
  bvh.nodes.emplace_back();
  if (T > 0) build_node(lo, hi, mid, &bvh, 0, 0, static_cast<int>(T));
  return bvh;
}

double box_distance2(const Eigen::Vector3d& y, const Eigen::Vector3d& lo,
                     const Eigen::Vector3d& hi) {
  // Σ_k max(lo_k − y_k, 0, y_k − hi_k)²
  return (lo - y).cwiseMax(y - hi).cwiseMax(0.0).squaredNorm();
}

TrianglePoint closest_on_triangle(const Eigen::Vector3d& y, const Eigen::Vector3d& a,
                                  const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  // Ericson §5.1.5: the Voronoi regions of the vertices, then of the edges, else the face.
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = y - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) return vertex_point(0);
  const Eigen::Vector3d bp = y - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) return vertex_point(1);
  const double vc = d1 * d4 - d3 * d2;  // the edge ab: λ1 = d1/(d1 − d3)
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return edge_point(2, d1 / (d1 - d3));
  const Eigen::Vector3d cp = y - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) return vertex_point(2);
  const double vb = d5 * d2 - d1 * d6;  // the edge ac: λ2 = d2/(d2 − d6), λ0 = −d6/(d2 − d6)
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return edge_point(1, -d6 / (d2 - d6));
  const double va = d3 * d6 - d5 * d4;  // the edge bc: λ2 = (d4 − d3)/((d4 − d3) + (d5 − d6))
  if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0)
    return edge_point(0, (d4 - d3) / ((d4 - d3) + (d5 - d6)));
  // The face: λ = (va, vb, vc)/(va + vb + vc), the sub-triangle areas.
  TrianglePoint p;
  const double inv = 1.0 / (va + vb + vc);
  p.lambda = Eigen::Vector3d(1.0 - (vb + vc) * inv, vb * inv, vc * inv);
  return p;
}

namespace {

// The closest point of triangle t of s to y, and its squared distance: closest_point's
// per-triangle steps (the same expressions, written out there to keep its loop as fast), for
// SurfaceDistance::at with candidates; test_surface_bvh checks both give the same bits.
[[gnu::always_inline]] inline SurfacePoint nearest_of(const TriangleSurface& s, int t,
                                                      const Eigen::Vector3d& y) {
  SurfacePoint p;
  p.triangle = t;
  p.where = closest_on_triangle(y, corner(s, t, 0), corner(s, t, 1), corner(s, t, 2));
  p.point = point_of(s, t, p.where.lambda);
  p.distance2 = (y - p.point).squaredNorm();
  return p;
}

}  // namespace

SurfacePoint closest_point(const TriangleSurface& s, const Bvh& bvh, const Eigen::Vector3d& y) {
  SurfacePoint best;
  if (bvh.order.empty()) return best;
  std::array<int, kBvhMaxDepth> stack;
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const BvhNode& n = bvh.nodes[stack[--top]];
    if (box_distance2(y, n.lo, n.hi) >= best.distance2) continue;
    if (n.left >= 0) {
      const double dl = box_distance2(y, bvh.nodes[n.left].lo, bvh.nodes[n.left].hi);
      const double dr = box_distance2(y, bvh.nodes[n.left + 1].lo, bvh.nodes[n.left + 1].hi);
      const bool left_first = dl <= dr;  // pushed last, popped first
      stack[top++] = left_first ? n.left + 1 : n.left;
      stack[top++] = left_first ? n.left : n.left + 1;
      continue;
    }
    for (int j = n.begin; j < n.end; ++j) {  // nearest_of's steps, kept apart from best
      const int t = bvh.order[j];
      const TrianglePoint p =
          closest_on_triangle(y, corner(s, t, 0), corner(s, t, 1), corner(s, t, 2));
      const Eigen::Vector3d x = point_of(s, t, p.lambda);
      const double d2 = (y - x).squaredNorm();
      if (d2 < best.distance2) {
        best.triangle = t;
        best.where = p;
        best.point = x;
        best.distance2 = d2;
      }
    }
  }
  return best;
}

// ---------------------------------------------------------------------------------------------
// SurfaceDistance

namespace {

void check_surface(const TriangleSurface& s) {
  const std::string who = "SurfaceDistance: ";
  if (s.points.cols() != 3) throw InvalidArgument(who + "the surface's points must be N by 3");
  if (!s.points.allFinite()) throw InvalidArgument(who + "a point of the surface is not finite");
  const Eigen::Index N = s.points.rows();
  if (s.triangles.rows() == 0) throw InvalidArgument(who + "the surface has no triangles");
  if (s.triangles.minCoeff() < 0 || s.triangles.maxCoeff() >= N)
    throw InvalidArgument(who + "a triangle names a point outside 0.." + std::to_string(N - 1));
  for (Eigen::Index t = 0; t < s.triangles.rows(); ++t)
    if ((corner(s, t, 1) - corner(s, t, 0)).cross(corner(s, t, 2) - corner(s, t, 0)).norm() == 0.0)
      throw InvalidArgument(who + "triangle " + std::to_string(t) + " has zero area");
}

// The half-edges of s, the edge opposite corner k of triangle t running from corner k + 1 to
// corner k + 2, sorted by their undirected edge (lo, hi), then triangle and corner.
struct HalfEdge {
  int lo, hi, t, k;
  bool forward;  // runs lo → hi
};

std::vector<HalfEdge> half_edges(const TriangleSurface& s) {
  std::vector<HalfEdge> h;
  h.reserve(static_cast<size_t>(3 * s.triangles.rows()));
  for (int t = 0; t < static_cast<int>(s.triangles.rows()); ++t)
    for (int k = 0; k < 3; ++k) {
      const int from = s.triangles(t, (k + 1) % 3), to = s.triangles(t, (k + 2) % 3);
      h.push_back({std::min(from, to), std::max(from, to), t, k, from < to});
    }
  std::sort(h.begin(), h.end(), [](const HalfEdge& a, const HalfEdge& b) {
    return std::tie(a.lo, a.hi, a.t, a.k) < std::tie(b.lo, b.hi, b.t, b.k);
  });
  return h;
}

// The unit vector along v, or v itself if it is zero.
Eigen::Vector3d unit_or_zero(const Eigen::Vector3d& v) {
  const double n = v.norm();
  return n > 0.0 ? Eigen::Vector3d(v / n) : v;
}

}  // namespace

SurfaceDistance::SurfaceDistance(TriangleSurface s) : s_(std::move(s)) {
  check_surface(s_);
  const Eigen::Index T = s_.triangles.rows(), N = s_.points.rows();
  face_normal_.resize(T, 3);
  vertex_normal_ = Eigen::MatrixXd::Zero(N, 3);
  for (Eigen::Index t = 0; t < T; ++t) {
    const Eigen::Vector3d x[3] = {corner(s_, t, 0), corner(s_, t, 1), corner(s_, t, 2)};
    const Eigen::Vector3d n = (x[1] - x[0]).cross(x[2] - x[0]).normalized();  // outward
    face_normal_.row(t) = n.transpose();
    for (int k = 0; k < 3; ++k) {
      // The angle at corner k, θ = atan2(|e1 × e2|, e1·e2), weighs n in the vertex normal.
      const Eigen::Vector3d e1 = x[(k + 1) % 3] - x[k], e2 = x[(k + 2) % 3] - x[k];
      vertex_normal_.row(s_.triangles(t, k)) +=
          std::atan2(e1.cross(e2).norm(), e1.dot(e2)) * n.transpose();
    }
  }
  for (Eigen::Index i = 0; i < N; ++i)
    vertex_normal_.row(i) = unit_or_zero(vertex_normal_.row(i).transpose()).transpose();
  // Closed and consistently oriented: each undirected edge has two half-edges, one each way.
  // The edge normal, the sum of the two face normals (normalised), is the same for both.
  edge_normal_.resize(3 * T, 3);
  const std::vector<HalfEdge> h = half_edges(s_);
  for (size_t i = 0; i < h.size();) {
    size_t j = i + 1;
    while (j < h.size() && h[j].lo == h[i].lo && h[j].hi == h[i].hi) ++j;
    auto edge = [&] {
      return "(" + std::to_string(h[i].lo) + ", " + std::to_string(h[i].hi) + ")";
    };
    if (j - i != 2)
      throw InvalidArgument("SurfaceDistance: the surface is not closed: the edge " + edge() +
                            " belongs to " + std::to_string(j - i) + " triangle(s), not 2");
    if (h[i].forward == h[i + 1].forward)
      throw InvalidArgument("SurfaceDistance: the surface is not consistently oriented: the edge " +
                            edge() + " runs the same way in triangles " + std::to_string(h[i].t) +
                            " and " + std::to_string(h[i + 1].t));
    const Eigen::Vector3d n = unit_or_zero(face_normal(h[i].t) + face_normal(h[i + 1].t));
    edge_normal_.row(3 * h[i].t + h[i].k) = n.transpose();
    edge_normal_.row(3 * h[i + 1].t + h[i + 1].k) = n.transpose();
    i = j;
  }
  bvh_ = build_bvh(s_);
  double longest = 0.0;
  for (Eigen::Index t = 0; t < T; ++t)
    for (int k = 0; k < 3; ++k)
      longest = std::max(longest, (corner(s_, t, (k + 1) % 3) - corner(s_, t, k)).norm());
  bvh_scale_ = s_.points.cwiseAbs().maxCoeff() + longest;
}

Eigen::Vector3d SurfaceDistance::pseudo_normal(int t, const TrianglePoint& p) const {
  switch (p.feature) {
    case Feature::kFace:
      return face_normal(t);
    case Feature::kEdge:  // (n_t + n_t')/|n_t + n_t'|, t' across the edge
      return edge_normal_.row(3 * t + p.corner).transpose();
    case Feature::kVertex:  // Σ θ n over the incident triangles, normalised
      return vertex_normal_.row(s_.triangles(t, p.corner)).transpose();
  }
  throw InternalError("SurfaceDistance: unknown feature");
}

SignedDistance SurfaceDistance::at(const Eigen::Vector3d& y) const {
  if (!y.allFinite()) throw InvalidArgument("SurfaceDistance::at: y is not finite");
  return unchecked_at(y);
}

inline SignedDistance SurfaceDistance::signed_at(const Eigen::Vector3d& y,
                                                 const SurfacePoint& c) const {
  SignedDistance q;
  q.closest = c;
  const Eigen::Vector3d r = y - q.closest.point,
                        n = pseudo_normal(q.closest.triangle, q.closest.where);
  const double d = std::sqrt(q.closest.distance2);
  const double sign = r.dot(n) < 0.0 ? -1.0 : 1.0;  // Bærentzen & Aanæs: sign((y − c)·n)
  q.sd = sign * d;
  // ∂sd/∂y = sign (y − c)/|y − c|; the face normal on a face (equal up to rounding, and
  // defined at d = 0); the unit pseudo-normal at an edge or vertex with d = 0.
  if (q.closest.where.feature == Feature::kFace || d == 0.0)
    q.gradient = n;
  else
    q.gradient = sign * r / d;
  return q;
}

SignedDistance SurfaceDistance::unchecked_at(const Eigen::Vector3d& y) const {
  return signed_at(y, closest_point(s_, bvh_, y));
}

std::vector<SignedDistance> SurfaceDistance::at_rows(const Eigen::MatrixXd& y, int threads) const {
  if (y.cols() != 3) throw InvalidArgument("SurfaceDistance::at_rows: y must be Q by 3");
  if (!y.allFinite()) throw InvalidArgument("SurfaceDistance::at_rows: a row of y is not finite");
  const Eigen::Index Q = y.rows();
  std::vector<SignedDistance> q(static_cast<size_t>(Q));
  const int nt = resolve_threads(threads);
#pragma omp parallel for schedule(dynamic, 64) num_threads(nt) if (Q > 256)
  for (Eigen::Index k = 0; k < Q; ++k)
    q[static_cast<size_t>(k)] = unchecked_at(Eigen::Vector3d(y.row(k)));
  return q;
}

Eigen::MatrixXd SurfaceDistance::pullback(const std::vector<SignedDistance>& q,
                                          const Eigen::VectorXd& w) const {
  if (w.size() != static_cast<Eigen::Index>(q.size()))
    throw InvalidArgument("SurfaceDistance::pullback: w has " + std::to_string(w.size()) +
                          " entries for " + std::to_string(q.size()) + " queries");
  Eigen::MatrixXd g = Eigen::MatrixXd::Zero(s_.points.rows(), 3);
  for (size_t k = 0; k < q.size(); ++k) {
    const SurfacePoint& c = q[k].closest;
    if (c.triangle < 0 || c.triangle >= s_.triangles.rows())
      throw InvalidArgument("SurfaceDistance::pullback: query " + std::to_string(k) +
                            " names no triangle of this surface");
    for (int a = 0; a < 3; ++a)  // ∂sd/∂x_a = −λ_a n̂
      if (c.where.lambda[a] != 0.0)
        g.row(s_.triangles(c.triangle, a)) -=
            (w[static_cast<Eigen::Index>(k)] * c.where.lambda[a]) * q[k].gradient.transpose();
  }
  return g;
}

SurfaceDistance::Candidates SurfaceDistance::candidates(const Eigen::Vector3d& centre,
                                                        double radius) const {
  if (!(radius >= 0.0) || !std::isfinite(radius))
    throw InvalidArgument("SurfaceDistance::candidates: radius must be finite and >= 0");
  if (!centre.allFinite())
    throw InvalidArgument("SurfaceDistance::candidates: centre is not finite");
  Candidates c;
  c.centre = centre;
  c.radius = radius;
  // a relative 1e-6 more than asked: the acceptance test at(y, c) uses `radius` itself
  const std::vector<int> found =
      unchecked_within(centre, radius * (1.0 + 1e-6) + 1e-6 * bvh_scale_);
  std::vector<std::pair<double, int>> by_distance;
  std::vector<Eigen::Vector3d> lo(found.size()), hi(found.size());
  for (size_t i = 0; i < found.size(); ++i) {
    const int t = found[i];
    lo[i] = corner(s_, t, 0).cwiseMin(corner(s_, t, 1)).cwiseMin(corner(s_, t, 2));
    hi[i] = corner(s_, t, 0).cwiseMax(corner(s_, t, 1)).cwiseMax(corner(s_, t, 2));
    by_distance.emplace_back(box_distance2(centre, lo[i], hi[i]), static_cast<int>(i));
  }
  std::sort(by_distance.begin(), by_distance.end());  // found is ascending: ties by id
  for (const auto& [d2, i] : by_distance) {
    c.triangles.push_back(found[static_cast<size_t>(i)]);
    for (int k = 0; k < 3; ++k) c.boxes.push_back(lo[static_cast<size_t>(i)][k]);
    for (int k = 0; k < 3; ++k) c.boxes.push_back(hi[static_cast<size_t>(i)][k]);
  }
  return c;
}

SignedDistance SurfaceDistance::at(const Eigen::Vector3d& y, const Candidates& c) const {
  if (!y.allFinite()) throw InvalidArgument("SurfaceDistance::at: y is not finite");
  // The nearest candidate and the next nearest computed d2, each triangle as closest_point
  // computes it (nearest_of, the same bits).
  // A candidate whose box is farther than √best by a relative 1e-6 (plus 1e-9 of the scale)
  // is skipped: its computed d2 exceeds best by more than the rounding the test (a) allows,
  // so it is neither the nearest nor within rounding of it.
  SurfacePoint best;
  double second = std::numeric_limits<double>::infinity();
  const double floor2 = 1e-18 * bvh_scale_ * bvh_scale_;
  for (size_t i = 0; i < c.triangles.size(); ++i) {
    const double* b = c.boxes.data() + 6 * i;
    double box2 = 0.0;  // Σ_k max(lo_k − y_k, 0, y_k − hi_k)²
    for (int k = 0; k < 3; ++k) {
      const double g = std::max({b[k] - y[k], 0.0, y[k] - b[3 + k]});
      box2 += g * g;
    }
    if (box2 > best.distance2 * (1.0 + 1e-6) + floor2) continue;
    const SurfacePoint p = nearest_of(s_, c.triangles[i], y);
    if (p.distance2 < best.distance2) {
      second = best.distance2;
      best = p;
    } else {
      second = std::min(second, p.distance2);
    }
  }
  // Settled when (a) every other candidate is farther by more than rounding can move a
  // computed d2 (closest_point then returns `best` whatever its order), and (b) the ball's
  // boundary is farther from y than best (by a relative 1e-6): a triangle outside the ball
  // is at least radius − |y − centre| away.
  constexpr double u = std::numeric_limits<double>::epsilon();
  const double d = std::sqrt(best.distance2), e = 64.0 * u * (bvh_scale_ + d);
  const double slack = 2.0 * e * d + e * e + 16.0 * u * best.distance2;
  const double reach = c.radius - (y - c.centre).norm();
  if (best.triangle >= 0 && second > best.distance2 + slack && d * (1.0 + 1e-6) + e < reach)
    return signed_at(y, best);
  return unchecked_at(y);
}

std::vector<int> SurfaceDistance::within(const Eigen::Vector3d& y, double r) const {
  if (!(r >= 0.0)) throw InvalidArgument("SurfaceDistance::within: r must be >= 0");
  if (!y.allFinite()) throw InvalidArgument("SurfaceDistance::within: y is not finite");
  return unchecked_within(y, r);
}

std::vector<int> SurfaceDistance::unchecked_within(const Eigen::Vector3d& y, double r) const {
  std::vector<int> found;
  for_each_within(s_, bvh_, y, r, [&](int t, double) { found.push_back(t); });
  std::sort(found.begin(), found.end());
  return found;
}

void SurfaceDistance::within_rows(const Eigen::MatrixXd& y, double r, std::vector<int>* start,
                                  std::vector<int>* triangles, int threads) const {
  if (y.cols() != 3) throw InvalidArgument("SurfaceDistance::within_rows: y must be Q by 3");
  if (!y.allFinite())
    throw InvalidArgument("SurfaceDistance::within_rows: a row of y is not finite");
  if (!(r >= 0.0)) throw InvalidArgument("SurfaceDistance::within_rows: r must be >= 0");
  const Eigen::Index Q = y.rows();
  std::vector<std::vector<int>> lists(static_cast<size_t>(Q));
  const int nt = resolve_threads(threads);
#pragma omp parallel for schedule(dynamic, 64) num_threads(nt) if (Q > 256)
  for (Eigen::Index k = 0; k < Q; ++k)
    lists[static_cast<size_t>(k)] = unchecked_within(Eigen::Vector3d(y.row(k)), r);
  start->assign(static_cast<size_t>(Q) + 1, 0);
  for (size_t k = 0; k < lists.size(); ++k)
    (*start)[k + 1] = (*start)[k] + static_cast<int>(lists[k].size());
  triangles->clear();
  triangles->reserve(static_cast<size_t>(start->back()));
  for (const std::vector<int>& l : lists) triangles->insert(triangles->end(), l.begin(), l.end());
}

}  // namespace softhd::detail
