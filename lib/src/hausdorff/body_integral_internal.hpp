#pragma once
// BodyIntegral's parts (internal to body_integral*.cpp; body_integral.hpp describes the method):
//   rules        (body_integral_rules.hpp)  the far rules, the kernel's radial functions,
//   polar rule   (body_integral_polar.cpp)  the triangles near y, per edge wedge,
//   far rules    (body_integral_far.cpp)    the far triangles, and any triangle one by one,
//   tree         (body_integral_tree.cpp)   the clusters, their expansions and bounds,
//   groups       (body_integral_groups.cpp) evaluate by the tree, rows grouped by place,
//   product      (body_integral_vjp.cpp)    the surface vector–Jacobian product,
//   construction (body_integral.cpp)        the triangles' geometry, the tree, all pairs.

#include <Eigen/Core>
#include <vector>

#include "../common/surface_bvh.hpp"
#include "body_integral.hpp"
#include "body_integral_rules.hpp"

namespace softhd::detail::body {

using Cluster = BodyIntegral::Cluster;

inline double dot(const double* a, const double* b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

inline void cross(const double* a, const double* b, double* c) {
  c[0] = a[1] * b[2] - a[2] * b[1];
  c[1] = a[2] * b[0] - a[0] * b[2];
  c[2] = a[0] * b[1] - a[1] * b[0];
}

// |y − c_t|²: near below t.near2 (the polar rule), the 16-point rule below t.far2.
inline double distance2(const Triangle& t, const double* y) {
  const double dx = y[0] - t.c[0], dy = y[1] - t.c[1], dz = y[2] - t.c[2];
  return dx * dx + dy * dy + dz * dz;
}

// The geometry of one triangle with corners v, its rules' points (body_integral.cpp); twin not
// set; area2 = 2 × its area (0: degenerate).
Triangle make_triangle(const double v[3][3], double near_ratio, double* area2);

// ---- The polar rule (body_integral_polar.cpp).

// Signed distance of y's foot to edge e's line (> 0 on the triangle's side), its ends along
// the line, and h_t = n·(v_0 − y).
struct EdgeFrame {
  double h;
  double pe[3], t1[3];
};

EdgeFrame edge_frame(const Triangle& t, const double* y);

// A = ∫_t G(r)/r³ dA and B = ∫_t k dA of a near triangle; the edges in the bit mask skip left
// out (their wedges cancel against a coplanar neighbour's).
void near_pair(const Triangle& t, const Radial& k, const Rules& rule, const EdgeFrame& f,
               bool want_a, bool want_b, double* a, double* b, int skip = 0);

// The signed solid angle of a triangle seen from y (positive when y is on the inner side).
double solid_angle(const Triangle& t, const double* y);

// Whether y lies on the near triangle t.
bool on_triangle(const Triangle& t, const EdgeFrame& f);

// ∫_t k λ_a dA for the three corners a of a near triangle.
void near_moments(const Triangle& t, const Radial& k, const Rules& rule, const EdgeFrame& f,
                  const double* y, double c[3]);

// ---- The far rules and the triangles one by one (body_integral_far.cpp).

// One point's sums over the triangles: J without the far solid angles' G∞ part, the near
// triangles' exact solid angles and the far ones' estimate, ∂J/∂y, S = ∫_∂Ω k dA (with the
// gradient), and the tree's error bounds of J, of the far solid angles and of g and S.
struct PointSums {
  double J = 0.0, near_omega = 0.0, far_omega = 0.0, g[3] = {0.0, 0.0, 0.0}, S = 0.0;
  double err_j = 0.0, err_omega = 0.0, err_g = 0.0;
  bool on_surface = false;
};

// The far triangles' exact Σ ω_t from the rule's estimate (the winding number).
double far_solid_angle(double near_sum, double estimate, bool on_surface);

// ∫_t k λ_a dA for the three corners of any triangle: the polar rule near y, the far rule else.
void corner_moments(const Triangle& tri, const Radial& k, const Rules& rule, const double* y,
                    double c[3]);

// The triangles tris[begin, end) one by one (a leaf of the tree, or all of them).
void direct_range(const std::vector<Triangle>& tris, int begin, int end, const Radial& k,
                  const Rules& rule, const double* y, bool want_b, bool coulomb, PointSums* s);

// ---- The tree (body_integral_tree.cpp).

// The per-unit-area error budgets of one traversal: J's, the far solid angles' and g's (and S's);
// theta > 0 (a probe for a first guess of J and S): J's and g's budgets replaced by ρ ≤ θ z.
struct Budget {
  double j, omega, g, theta = 0.0;
};

// The probe's opening ratio (a guess only: its results are not used unless the check passes).
constexpr double kProbeTheta = 0.25;

// A cluster's remainder bounds per unit area at z = |p − y| − ρ (valid: the expansion may be
// taken there): J's tail, the solid angle's, and with the gradient k's.
struct Bounds {
  bool valid;
  double j, omega, g;
};

// A cluster's moments over its triangles order[begin, end).
Cluster make_cluster(const std::vector<Triangle>& tris, const std::vector<int>& order,
                     const BvhNode& node);

Bounds cluster_bounds(const Cluster& c, double eps, double z, bool want_b);

// Whether a cluster at z, its bounds e there, enters by its expansions under the budget
// (decreasing in z: fits at z implies fits at every larger z).
bool cluster_fits(const Cluster& c, const Bounds& e, double z, const Budget& budget);

// A cluster's expansions into y's sums, e its bounds at y's distance.
void take_cluster(const Cluster& c, double eps, const double* y, bool want_b, const Bounds& e,
                  PointSums* s);

// One point's sums by the tree below the nodes `start`, added to s; and by the whole tree.
void traverse(const std::vector<Cluster>& clusters, const std::vector<Triangle>& tris,
              const Radial& k, const Rules& rule, const double* y, bool want_b,
              const Budget& budget, const std::vector<int>& start, PointSums* s);
PointSums traverse(const std::vector<Cluster>& clusters, const std::vector<Triangle>& tris,
                   const Radial& k, const Rules& rule, const double* y, bool want_b,
                   const Budget& budget);

// ---- Groups of rows sharing one traversal (body_integral_groups.cpp).

// A group of points (|y − centre| ≤ radius for each) and the decisions its points share: the
// clusters every point takes (fits at z − radius ≤ each point's z), the leaves no point takes
// (fails at z + radius), the nodes each point decides itself (the roots of its own traversal).
// With one budget for the group, each point's sums are those of its own traversal (the fits are
// monotone in z), in another order.
struct GroupLists {
  std::vector<int> taken, leaves, open;
};

template <class Fits>
void group_lists(const std::vector<Cluster>& clusters, const double* centre, double radius,
                 Fits&& fits, GroupLists* out) {
  out->taken.clear();
  out->leaves.clear();
  out->open.clear();
  int stack[2 * kBvhMaxDepth + 2];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const int id = stack[--top];
    const Cluster& c = clusters[id];
    const double d[3] = {c.p[0] - centre[0], c.p[1] - centre[1], c.p[2] - centre[2]};
    const double z = std::sqrt(dot(d, d)) - c.rho;
    if (fits(c, z - radius)) {
      out->taken.push_back(id);
    } else if (fits(c, z + radius)) {
      out->open.push_back(id);
    } else if (c.left >= 0) {
      stack[top++] = c.left + 1;
      stack[top++] = c.left;
    } else {
      out->leaves.push_back(id);
    }
  }
}

// Points are taken in blocks of kBlock rows (a block's points depend on the ones before them in
// it, not on the threads), each in groups of up to kGroup consecutive rows within a sphere of
// radius kGroupRadius × the root cluster's ρ that share one traversal.
constexpr Eigen::Index kBlock = 64;
constexpr Eigen::Index kGroup = 8;
constexpr double kGroupRadius = 1.0 / 32.0;

// The group of rows from begin: the most consecutive rows, up to kGroup and before limit, whose
// sphere's radius stays ≤ max_radius (one row at least); its end into *end, centre and radius.
double next_group(const Eigen::MatrixXd& points, Eigen::Index begin, Eigen::Index limit,
                  double max_radius, double* centre, Eigen::Index* end);

// One point's sums from its group's lists.
PointSums group_point(const std::vector<Cluster>& clusters, const std::vector<Triangle>& tris,
                      const Radial& k, const Rules& rule, const double* y, bool want_b,
                      const Budget& budget, const GroupLists& g);

}  // namespace softhd::detail::body
