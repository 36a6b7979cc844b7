// Visibility of a surface's points from a camera (docs/formulation.md §8.7): the facing test
// and a segment cast through a bounding-volume hierarchy of the triangles.

#include "softhd/scan/visibility.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <numeric>
#include <string>
#include <vector>

#include "../common/surface_bvh.hpp"
#include "softhd/error.hpp"
#include "softhd/parallel.hpp"

namespace softhd::scan {

namespace {

using detail::build_bvh;
using detail::Bvh;
using detail::BvhNode;

// Whether the segment o + t d, t in [0, t_max], meets the box [lo, hi] (slab test; inv_d =
// 1/d; a slab parallel to the segment is met iff o lies in it).
bool segment_meets_box(const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                       const Eigen::Vector3d& inv_d, double t_max, const Eigen::Vector3d& lo,
                       const Eigen::Vector3d& hi) {
  double t0 = 0.0, t1 = t_max;
  for (int k = 0; k < 3; ++k) {
    if (d[k] == 0.0) {
      if (o[k] < lo[k] || o[k] > hi[k]) return false;
      continue;
    }
    double a = (lo[k] - o[k]) * inv_d[k], b = (hi[k] - o[k]) * inv_d[k];
    if (a > b) std::swap(a, b);
    t0 = std::max(t0, a);
    t1 = std::min(t1, b);
    if (t0 > t1) return false;
  }
  return true;
}

// Barycentric slack of a meeting: a line through an edge or vertex shared by triangles meets
// them all, so rounding cannot let it slip between two of them.
constexpr double kEdgeSlack = 1e-10;

// The parameter t of the meeting of the line o + t d with the triangle (a, b, c) (the
// Möller–Trumbore solution of o + t d = a + v (b − a) + w (c − a), v, w ≥ −s, v + w ≤ 1 + s,
// s = kEdgeSlack), or a negative value if they do not meet (a line in the triangle's plane
// meets nothing).
double meet(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Eigen::Vector3d& a,
            const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d e1 = b - a, e2 = c - a, p = d.cross(e2);
  const double det = e1.dot(p);
  if (det == 0.0) return -1.0;
  const Eigen::Vector3d s = o - a, q = s.cross(e1);
  const double v = s.dot(p) / det, w = d.dot(q) / det;
  if (v < -kEdgeSlack || w < -kEdgeSlack || v + w > 1.0 + kEdgeSlack) return -1.0;
  return e2.dot(q) / det;
}

// Triangles incident to each point (compressed rows).
void incidence(const TriangleSurface& s, std::vector<int>* start, std::vector<int>* tri) {
  start->assign(static_cast<size_t>(s.points.rows()) + 1, 0);
  for (Eigen::Index t = 0; t < s.triangles.rows(); ++t)
    for (int c = 0; c < 3; ++c) ++(*start)[s.triangles(t, c) + 1];
  std::partial_sum(start->begin(), start->end(), start->begin());
  tri->resize(static_cast<size_t>(start->back()));
  std::vector<int> fill(start->begin(), start->end() - 1);
  for (Eigen::Index t = 0; t < s.triangles.rows(); ++t)
    for (int c = 0; c < 3; ++c) (*tri)[fill[s.triangles(t, c)]++] = static_cast<int>(t);
}

void check(const TriangleSurface& s, const Eigen::Vector3d& camera, double tolerance) {
  if (s.points.cols() != 3) throw InvalidArgument("visible_points: the points must be N by 3");
  if (!s.points.allFinite()) throw InvalidArgument("visible_points: a point is not finite");
  if (!camera.allFinite()) throw InvalidArgument("visible_points: camera is not finite");
  if (!(tolerance >= 0.0 && tolerance < 1.0))
    throw InvalidArgument("visible_points: tolerance must be in [0, 1), got " +
                          std::to_string(tolerance));
  const Eigen::Index N = s.points.rows();
  if (s.triangles.size() && (s.triangles.minCoeff() < 0 || s.triangles.maxCoeff() >= N))
    throw InvalidArgument("visible_points: a triangle names a point outside 0.." +
                          std::to_string(N - 1));
}

}  // namespace

Eigen::Array<bool, Eigen::Dynamic, 1> visible_points(const TriangleSurface& s,
                                                     const Eigen::Vector3d& camera,
                                                     double tolerance) {
  check(s, camera, tolerance);
  const Eigen::Index N = s.points.rows();
  Eigen::Array<bool, Eigen::Dynamic, 1> seen = Eigen::Array<bool, Eigen::Dynamic, 1>::Zero(N);
  if (N == 0) return seen;
  const double diag = (s.points.colwise().maxCoeff() - s.points.colwise().minCoeff()).norm();
  const double slack = tolerance * diag;  // hits closer than this to x do not hide it
  std::vector<int> start, incident;
  incidence(s, &start, &incident);
  const Bvh bvh = build_bvh(s);
  auto P = [&](Eigen::Index t, int c) { return Eigen::Vector3d(s.points.row(s.triangles(t, c))); };
  // One segment cast a point, each independent: threads as softhd's other loops (clamped to
  // kMaxThreads), serial below a few hundred points.
  const int threads = max_threads();
#pragma omp parallel for schedule(dynamic, 64) num_threads(threads) if (N > 256)
  for (Eigen::Index i = 0; i < N; ++i) {
    const Eigen::Vector3d x = s.points.row(i).transpose(), to_camera = camera - x;
    // Facing: some incident triangle's outward normal n has n·(camera − x) > 0.
    bool facing = false;
    for (int k = start[i]; k < start[i + 1] && !facing; ++k) {
      const int t = incident[k];
      facing = (P(t, 1) - P(t, 0)).cross(P(t, 2) - P(t, 0)).dot(to_camera) > 0.0;
    }
    if (!facing) continue;
    // The segment camera + t d, d = x − camera, t in [0, t_max]: t_max stops `slack` short of x.
    const Eigen::Vector3d d = -to_camera;
    const double length = d.norm();
    if (length <= slack) {
      seen[i] = true;
      continue;
    }
    const double t_max = 1.0 - slack / length;
    const Eigen::Vector3d inv_d = d.cwiseInverse();
    std::array<int, detail::kBvhMaxDepth> stack;
    int top = 0;
    stack[top++] = 0;
    bool hidden = false;
    while (top > 0 && !hidden) {
      const BvhNode& n = bvh.nodes[stack[--top]];
      if (!segment_meets_box(camera, d, inv_d, t_max, n.lo, n.hi)) continue;
      if (n.left >= 0) {
        stack[top++] = n.left;
        stack[top++] = n.left + 1;
        continue;
      }
      for (int j = n.begin; j < n.end && !hidden; ++j) {
        const int t = bvh.order[j];
        if (s.triangles(t, 0) == i || s.triangles(t, 1) == i || s.triangles(t, 2) == i) continue;
        const double h = meet(camera, d, P(t, 0), P(t, 1), P(t, 2));
        hidden = h >= 0.0 && h <= t_max;
      }
    }
    seen[i] = !hidden;
  }
  return seen;
}

}  // namespace softhd::scan
