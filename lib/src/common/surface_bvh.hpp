#pragma once
// A bounding-volume hierarchy of a triangle surface (internal), shared by scan/visibility.cpp
// (segment casts) and the cell-integrated distance (docs/formulation.md §2.8: the signed
// distance sd(y) to the other body's boundary at the outer quadrature points, and the
// triangles within a radius of y for the near field).
//
//   build_bvh              the hierarchy: median splits, deterministic
//   closest_on_triangle    the closest point of one triangle and its feature (face/edge/vertex)
//   closest_point          the closest point of the surface (branch and bound)
//   for_each_within        the triangles within a distance r of y (a callback)
//   SurfaceDistance        a closed surface's signed distance (angle-weighted pseudo-normals,
//                          Bærentzen & Aanæs 2005), its derivatives, and radius queries
//
// The surface's points are N by 3, its triangles T by 3 point ids (softhd::TriangleSurface).

#include <Eigen/Core>
#include <array>
#include <limits>
#include <vector>

#include "softhd/triangle_surface.hpp"

namespace softhd::detail {

// ---------------------------------------------------------------------------------------------
// The hierarchy

/// A node: a box around the triangles order[begin, end) (a leaf) or around its children
/// left and left + 1.
struct BvhNode {
  Eigen::Vector3d lo, hi;
  int left = -1;  ///< −1: a leaf
  int begin = 0, end = 0;
};

constexpr int kBvhLeafSize = 4;
constexpr int kBvhMaxDepth = 64;  ///< median splits: depth ≤ log2(T) + 1, far below

struct Bvh {
  std::vector<BvhNode> nodes;  ///< nodes[0] the root (a leaf with begin = end for T = 0)
  std::vector<int> order;      ///< triangle ids, grouped by leaf
};

/// The hierarchy of s's triangles: median split along the widest axis of the centroids, ties
/// broken by triangle id, so the hierarchy (and every result) is deterministic.
Bvh build_bvh(const TriangleSurface& s);

/// The squared distance from y to the box [lo, hi]: Σ_k max(lo_k − y_k, 0, y_k − hi_k)².
double box_distance2(const Eigen::Vector3d& y, const Eigen::Vector3d& lo,
                     const Eigen::Vector3d& hi);

// ---------------------------------------------------------------------------------------------
// Closest points

/// Where on a triangle a closest point lies.
enum class Feature : int { kFace = 0, kEdge = 1, kVertex = 2 };

/// A point of a triangle (a, b, c) = corners 0, 1, 2.
struct TrianglePoint {
  Eigen::Vector3d lambda = Eigen::Vector3d::Zero();  ///< barycentric: λ0 a + λ1 b + λ2 c
  Feature feature = Feature::kFace;
  /// kEdge: the corner opposite the edge (its λ is 0); kVertex: the corner (its λ is 1);
  /// kFace: −1.
  int corner = -1;
};

/// The closest point of the triangle (a, b, c) to y by Ericson's Voronoi-region test
/// (Real-Time Collision Detection §5.1.5): a vertex, an edge or the face interior. The
/// triangle must not be degenerate (zero area).
TrianglePoint closest_on_triangle(const Eigen::Vector3d& y, const Eigen::Vector3d& a,
                                  const Eigen::Vector3d& b, const Eigen::Vector3d& c);

/// A closest point of a surface.
struct SurfacePoint {
  int triangle = -1;  ///< −1: the surface has no triangles
  TrianglePoint where;
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  double distance2 = std::numeric_limits<double>::infinity();  ///< |y − point|²
};

/// The corner `k` of triangle t of s.
inline Eigen::Vector3d corner(const TriangleSurface& s, Eigen::Index t, int k) {
  return s.points.row(s.triangles(t, k)).transpose();
}

/// The closest point of s to y: branch and bound over the hierarchy (the nearer child first,
/// a box pruned when its distance is not below the best so far). Of equally close triangles,
/// the first met (deterministic).
SurfacePoint closest_point(const TriangleSurface& s, const Bvh& bvh, const Eigen::Vector3d& y);

/// Calls f(t, d2) for every triangle t of s whose squared distance d2 to y is ≤ r² (r ≥ 0),
/// in the hierarchy's order (deterministic).
template <class F>
void for_each_within(const TriangleSurface& s, const Bvh& bvh, const Eigen::Vector3d& y, double r,
                     F&& f) {
  if (bvh.order.empty()) return;
  const double r2 = r * r;
  std::array<int, kBvhMaxDepth> stack;
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const BvhNode& n = bvh.nodes[stack[--top]];
    if (box_distance2(y, n.lo, n.hi) > r2) continue;
    if (n.left >= 0) {
      stack[top++] = n.left + 1;
      stack[top++] = n.left;
      continue;
    }
    for (int j = n.begin; j < n.end; ++j) {
      const int t = bvh.order[j];
      const Eigen::Vector3d a = corner(s, t, 0), b = corner(s, t, 1), c = corner(s, t, 2);
      const TrianglePoint p = closest_on_triangle(y, a, b, c);
      const double d2 = (y - (p.lambda[0] * a + p.lambda[1] * b + p.lambda[2] * c)).squaredNorm();
      if (d2 <= r2) f(t, d2);
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Signed distance

/// The signed distance at one query point y and what its derivatives need.
struct SignedDistance {
  SurfacePoint closest;  ///< the closest point c (triangle, barycentric λ, feature)
  double sd = 0.0;       ///< ±|y − c|, negative inside
  /// ∂sd/∂y: the face's outward unit normal at a face feature, else sign · (y − c)/|y − c|
  /// (the unit pseudo-normal where y = c, where sd is not differentiable).
  Eigen::Vector3d gradient = Eigen::Vector3d::Zero();
};

/// The signed distance to a closed, outward-oriented triangle surface, with the triangles
/// within a radius. Built once per surface (its hierarchy and pseudo-normals); the queries
/// are const and thread-safe. Keeps its own copy of the surface.
///
/// The sign is that of (y − c)·n at the closest point c, n the angle-weighted pseudo-normal of
/// c's feature (Bærentzen & Aanæs 2005): the face normal on a face, the mean of the two face
/// normals on an edge, Σ θ_t n_t over the incident triangles at a vertex (θ_t the triangle's
/// angle there). Correct for any closed, consistently oriented, non-self-intersecting surface.
///
/// Where sd is differentiable (the closest point unique, y not on the surface at an edge or
/// vertex): ∂sd/∂y = n̂ (SignedDistance::gradient) and, for every corner a of the closest
/// triangle, ∂sd/∂x_a = −λ_a n̂ — at a face δsd = −n·Σ λ_a δx_a (the plane moves under y by
/// the displacement of the material point c); at an edge or vertex δsd = −n̂·δc with c's λ
/// fixed (the closest point's own motion along the feature is second order).
class SurfaceDistance {
 public:
  /// Throws InvalidArgument unless s is closed and consistently oriented (every edge in
  /// exactly two triangles, once each way), its points finite and N by 3, its triangles name
  /// its points, and no triangle has zero area.
  explicit SurfaceDistance(TriangleSurface s);

  const TriangleSurface& surface() const { return s_; }

  /// The triangles within `radius` of `centre` (a little more, for rounding): the candidates
  /// for the closest triangle of the queries in that ball, e.g. the points of one line
  /// (at(y, candidates)).
  struct Candidates {
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    double radius = 0.0;
    /// nearest the centre first (their boxes' distances; ties: ascending ids)
    std::vector<int> triangles;
    std::vector<double> boxes;  ///< 6 per triangle: its box's lo (x, y, z), then hi
  };
  /// InvalidArgument unless centre is finite and radius ≥ 0.
  Candidates candidates(const Eigen::Vector3d& centre, double radius) const;
  const Bvh& bvh() const { return bvh_; }

  /// The signed distance at y (InvalidArgument unless y is finite).
  SignedDistance at(const Eigen::Vector3d& y) const;
  /// The same as at(y), bit for bit, from the candidates where they settle it: their nearest
  /// triangle is nearer than every other candidate by more than the rounding of a computed
  /// squared distance, and nearer than the candidates' ball's boundary seen from y (so no
  /// triangle outside the ball is as near); then at(y)'s branch and bound, which returns the
  /// nearest triangle unless another is within rounding of it, would return it too. Else (a
  /// tie within rounding, y too far out) at(y) itself. Cheap for many y in a small ball.
  SignedDistance at(const Eigen::Vector3d& y, const Candidates& candidates) const;
  /// At every row of y (Q by 3), over `threads` OpenMP threads (0: max_threads()); each
  /// query is independent, so the results do not depend on the threads.
  std::vector<SignedDistance> at_rows(const Eigen::MatrixXd& y, int threads = 0) const;

  /// Σ_k w_k ∂sd(y_k)/∂x_a for every surface point a (N by 3): −Σ_k w_k λ_{k,a} n̂_k over the
  /// queries whose closest triangle has a as a corner. Summed in query order (deterministic).
  Eigen::MatrixXd pullback(const std::vector<SignedDistance>& q, const Eigen::VectorXd& w) const;

  /// The triangles within distance r of y (distance ≤ r), ascending ids.
  std::vector<int> within(const Eigen::Vector3d& y, double r) const;
  /// The same for every row of y (Q by 3), as compressed rows: the triangles of query k are
  /// (*triangles)[(*start)[k], (*start)[k + 1]). Over `threads` threads; deterministic.
  void within_rows(const Eigen::MatrixXd& y, double r, std::vector<int>* start,
                   std::vector<int>* triangles, int threads = 0) const;

  /// The unit outward normal of triangle t.
  Eigen::Vector3d face_normal(int t) const { return face_normal_.row(t).transpose(); }
  /// The pseudo-normal (not normalised) of a closest point's feature on triangle t.
  Eigen::Vector3d pseudo_normal(int t, const TrianglePoint& p) const;

 private:
  SignedDistance unchecked_at(const Eigen::Vector3d& y) const;                      // y finite
  SignedDistance signed_at(const Eigen::Vector3d& y, const SurfacePoint& c) const;  // c closest
  std::vector<int> unchecked_within(const Eigen::Vector3d& y, double r) const;  // y finite, r ≥ 0

  TriangleSurface s_;
  Bvh bvh_;
  Eigen::MatrixXd face_normal_;    // T by 3, unit
  Eigen::MatrixXd edge_normal_;    // T by 3 rows per triangle: row 3t + k, the edge opposite k
  Eigen::MatrixXd vertex_normal_;  // N by 3: Σ θ n over the incident triangles
  double bvh_scale_ = 0.0;         // max |coordinate| + the longest edge: the rounding's scale
};

}  // namespace softhd::detail
